#include "sinew/formats/hdf5_heap_check.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_handle.hpp"

namespace sinew::formats::hdf5 {
namespace {

constexpr char kSignature[] = "GCOL";
constexpr std::size_t kHeader = 8;  // signature, version, reserved; the size field follows

// What the checks need of the file: its bytes on demand, its length, and the widths of addresses
// and lengths and the base address (the user block) that HDF5 addresses are relative to.
class RawFile {
 public:
  RawFile(hid_t obj, const std::string& file, const std::string& where)
      : file_(file), where_(where) {
    Handle f(H5Iget_file_id(obj), H5Fclose);
    const auto n = f.valid() ? H5Fget_name(f, nullptr, 0) : -1;
    if (n <= 0) throw FormatError(file, where, "cannot find the file to check its global heap");
    std::string path(static_cast<std::size_t>(n), '\0');
    H5Fget_name(f, path.data(), path.size() + 1);
    Handle fcpl(H5Fget_create_plist(f), H5Pclose);
    std::size_t sizeof_addr = 8, sizeof_size = 8;
    hsize_t userblock = 0;
    H5Pget_sizes(fcpl, &sizeof_addr, &sizeof_size);
    H5Pget_userblock(fcpl, &userblock);
    addr_ = sizeof_addr;
    length_ = sizeof_size;
    base_ = userblock;
    in_.open(path, std::ios::binary);
    in_.seekg(0, std::ios::end);
    size_ = in_ ? static_cast<std::uint64_t>(in_.tellg()) : 0;
    if (!in_ || addr_ > 8 || length_ > 8 || addr_ == 0 || length_ == 0) {
      throw FormatError(file, where, "cannot read the file to check its global heap");
    }
  }
  std::uint64_t size() const { return size_; }
  std::size_t addr_width() const { return addr_; }
  std::size_t length_width() const { return length_; }
  std::uint64_t base() const { return base_; }

  // n bytes at offset, or nothing when they are not all inside the file.
  std::optional<std::vector<unsigned char>> bytes(std::uint64_t offset, std::uint64_t n) {
    if (offset > size_ || n > size_ - offset) return std::nullopt;
    std::vector<unsigned char> b(static_cast<std::size_t>(n));
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(n));
    if (!in_) return std::nullopt;
    return b;
  }
  FormatError fail(const std::string& what) const { return FormatError(file_, where_, what); }

 private:
  std::string file_, where_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
  std::size_t addr_ = 8, length_ = 8;
  std::uint64_t base_ = 0;
};

std::uint64_t little_endian(const unsigned char* p, std::size_t width) {
  std::uint64_t v = 0;
  for (std::size_t k = 0; k < width; ++k) v |= std::uint64_t{p[k]} << (8 * k);
  return v;
}

// The objects of the collection at file offset `at` (index -> size), walked as HDF5's loader
// walks them but with every step bounded by the collection; nothing when it is malformed.
std::optional<std::map<std::uint16_t, std::uint64_t>> collection_objects(RawFile& raw,
                                                                         std::uint64_t at) {
  const auto head = raw.bytes(at, kHeader + raw.length_width());
  if (!head || std::memcmp(head->data(), kSignature, 4) != 0 || (*head)[4] != 1) {
    return std::nullopt;
  }
  const auto size = little_endian(head->data() + kHeader, raw.length_width());
  const auto header = kHeader + raw.length_width();
  if (size < header || size > raw.size()) return std::nullopt;
  const auto chunk = raw.bytes(at, size);
  if (!chunk) return std::nullopt;
  const std::uint64_t object_header = 8 + raw.length_width();
  std::map<std::uint16_t, std::uint64_t> objects;
  std::uint64_t p = header;
  while (p < size) {
    if (size - p < object_header) break;  // a tail too small for a header: free space to HDF5
    const unsigned char* o = chunk->data() + p;
    const auto index = static_cast<std::uint16_t>(little_endian(o, 2));
    const auto length = little_endian(o + 8, raw.length_width());
    std::uint64_t need;
    if (index == 0) {
      need = length;  // the free space, its header included
      if (need < object_header) return std::nullopt;
    } else {
      if (length > size) return std::nullopt;
      need = object_header + ((length + 7) / 8) * 8;
      if (!objects.emplace(index, length).second) return std::nullopt;  // an index used twice
    }
    if (need > size - p) return std::nullopt;
    p += need;
  }
  return objects;
}

// The object header address of `obj`.
std::optional<std::uint64_t> header_address(hid_t obj) {
#if H5_VERSION_GE(1, 12, 0)
  H5O_info2_t info;
  haddr_t addr = HADDR_UNDEF;
  if (H5Oget_info3(obj, &info, H5O_INFO_BASIC) < 0 ||
      H5VLnative_token_to_addr(obj, info.token, &addr) < 0) {
    return std::nullopt;
  }
#else
  H5O_info_t info;
  if (H5Oget_info2(obj, &info, H5O_INFO_BASIC) < 0) return std::nullopt;
  const haddr_t addr = info.addr;
#endif
  if (addr == HADDR_UNDEF) return std::nullopt;
  return addr;
}

// Calls visit(type, data, size) for every message of a version 1 object header (no checksum),
// walking its continuation blocks; false when the header is version 2 (checksummed: HDF5 refuses
// a damaged one) or cannot be walked.
template <typename Visit>
bool for_each_v1_message(RawFile& raw, std::uint64_t header, Visit visit) {
  const auto prefix = raw.bytes(raw.base() + header, 16);
  if (!prefix || (*prefix)[0] != 1) return false;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> blocks{
      {raw.base() + header + 16, little_endian(prefix->data() + 8, 4)}};
  for (std::size_t b = 0; b < blocks.size() && b < 64; ++b) {
    const auto block = raw.bytes(blocks[b].first, blocks[b].second);
    if (!block) return false;
    for (std::size_t p = 0; p + 8 <= block->size();) {
      const unsigned char* m = block->data() + p;
      const auto type = little_endian(m, 2);
      const auto size = little_endian(m + 2, 2);
      if (p + 8 + size > block->size()) return false;
      const unsigned char* d = m + 8;
      if (type == 0x10 && size >= raw.addr_width() + raw.length_width()) {  // continuation
        blocks.emplace_back(raw.base() + little_endian(d, raw.addr_width()),
                            little_endian(d + raw.addr_width(), raw.length_width()));
      } else if (!visit(type, d, static_cast<std::size_t>(size))) {
        return true;
      }
      p += 8 + size;
    }
  }
  return true;
}

// The datatype and the 16-byte-or-so value of attribute `name` as stored in a version 1 object
// header; nothing when the header is version 2 or the attribute is not found there. `damaged`: the
// message's own sizes put the value past its end, where HDF5 would read a descriptor out of other
// bytes (a damaged dataspace size made one read take 21 s in a fuzz case).
struct RawAttribute {
  std::vector<unsigned char> datatype, value;
  bool damaged = false;
};
std::optional<RawAttribute> v1_attribute(RawFile& raw, std::uint64_t header,
                                         const std::string& name) {
  std::optional<RawAttribute> out;
  for_each_v1_message(
      raw, header, [&](std::uint64_t type, const unsigned char* d, std::size_t size) {
        if (type != 0x0C || size < 8 || d[0] < 1 || d[0] > 3) return true;  // not an attribute
        const auto version = d[0];
        const auto name_size = little_endian(d + 2, 2);
        const auto type_size = little_endian(d + 4, 2);
        const auto space_size = little_endian(d + 6, 2);
        const auto pad = [&](std::uint64_t n) { return version == 1 ? (n + 7) / 8 * 8 : n; };
        const std::uint64_t start = 8 + (version == 3 ? 1 : 0);
        const auto type_at = start + pad(name_size);
        const auto value = type_at + pad(type_size) + pad(space_size);
        if (name_size != name.size() + 1 || start + name_size > size ||
            std::memcmp(d + start, name.c_str(), name.size() + 1) != 0) {
          return true;
        }
        out = RawAttribute{};
        if (type_at + type_size > size || value > size) {
          out->damaged = true;
        } else {
          out->datatype.assign(d + type_at, d + type_at + type_size);
          out->value.assign(d + value, d + size);
        }
        return false;
      });
  return out;
}

// The datatype message of a dataset's version 1 object header; nothing otherwise.
std::optional<std::vector<unsigned char>> v1_dataset_type(RawFile& raw, std::uint64_t header) {
  std::optional<std::vector<unsigned char>> out;
  for_each_v1_message(raw, header,
                      [&](std::uint64_t type, const unsigned char* d, std::size_t size) {
                        if (type != 0x03) return true;
                        out = std::vector<unsigned char>(d, d + size);
                        return false;
                      });
  return out;
}

// A variable-length string's stored datatype (HDF5 file format spec, "Datatype Message": class 9,
// type 1 = string, then the base type) must have 1-byte characters. HDF5 1.10 takes the base
// type's size as it is and, converting one string of n characters, allocates and clears n × that
// size: a damaged size of 2^30 made one attribute read take 57 s (a fuzz case in the earliest
// format). An empty optional (no unchecksummed header) passes.
void check_vlen_string_type(const RawFile& raw,
                            const std::optional<std::vector<unsigned char>>& type) {
  if (!type || type->size() < 16) return;
  const auto& t = *type;
  if ((t[0] & 0x0f) != 9 || (t[1] & 0x0f) != 1) return;  // not a variable-length string
  const auto base_size = little_endian(t.data() + 12, 4);
  if (base_size != 1) {
    throw raw.fail(fmt::format(
        "its datatype is damaged (a variable-length string of {}-byte characters)", base_size));
  }
}

}  // namespace

void check_vlen_dataset(hid_t dataset, const std::string& file, const std::string& name) {
  const LibraryLock lock;
  Handle dcpl(H5Dget_create_plist(dataset), H5Pclose);
  if (!dcpl.valid() || H5Pget_layout(dcpl) != H5D_CONTIGUOUS) {
    throw FormatError(file, name,
                      "variable-length strings must be stored contiguous, not chunked, compressed "
                      "or compact (sinew checks their heap references before reading, which only "
                      "that layout allows): store this dataset contiguous (h5repack -l " +
                          name + ":CONTI) or as fixed-length strings");
  }
  Handle space(H5Dget_space(dataset), H5Sclose);
  const auto count = H5Sget_simple_extent_npoints(space);
  if (count <= 0) return;
  const haddr_t offset = H5Dget_offset(dataset);
  if (offset == HADDR_UNDEF) return;  // no storage allocated: HDF5 reads fill values
  RawFile raw(dataset, file, name);
  if (const auto header = header_address(dataset)) {
    check_vlen_string_type(raw, v1_dataset_type(raw, *header));
  }
  const std::uint64_t width = 4 + raw.addr_width() + 4;  // length, collection address, index
  const auto n = static_cast<std::uint64_t>(count);
  if (n > raw.size() / width) throw raw.fail("more strings than the file can hold");
  const auto descriptors = raw.bytes(offset, n * width);
  if (!descriptors) throw raw.fail("the strings' storage lies outside the file");
  std::map<std::uint64_t, std::map<std::uint16_t, std::uint64_t>> seen;
  for (std::uint64_t i = 0; i < n; ++i) {
    const unsigned char* d = descriptors->data() + i * width;
    const auto length = little_endian(d, 4);
    const auto address = little_endian(d + 4, raw.addr_width());
    const auto index = little_endian(d + 4 + raw.addr_width(), 4);
    if (address == 0) continue;  // a null string: HDF5 reads no heap
    auto it = seen.find(address);
    if (it == seen.end()) {
      auto objects = collection_objects(raw, raw.base() + address);
      if (!objects) {
        throw raw.fail(fmt::format("string {}: its global heap collection (address {}) is damaged",
                                   i, address));
      }
      it = seen.emplace(address, std::move(*objects)).first;
    }
    const auto object =
        index <= 0xffff ? it->second.find(static_cast<std::uint16_t>(index)) : it->second.end();
    if (object == it->second.end() || object->second != length) {
      throw raw.fail(fmt::format(
          "string {}: its heap reference (collection {}, object {}, {} bytes) is damaged", i,
          address, index, length));
    }
  }
}

void check_attribute_messages(hid_t obj, const std::string& file, const std::string& where) {
  const auto header = header_address(obj);
  if (!header) return;
  RawFile raw(obj, file, where);
  int index = 0;
  std::string damage;
  for_each_v1_message(
      raw, *header, [&](std::uint64_t type, const unsigned char* d, std::size_t size) {
        if (type != 0x0C) return true;
        const int at = index++;
        auto bad = [&](const std::string& what) {
          damage = fmt::format("attribute message {} of its header is damaged ({})", at, what);
          return false;
        };
        if (size < 8 || d[0] < 1 || d[0] > 3) return bad("unknown version");
        const auto version = d[0];
        const std::uint64_t name_size = little_endian(d + 2, 2),
                            type_size = little_endian(d + 4, 2),
                            space_size = little_endian(d + 6, 2);
        const auto pad = [&](std::uint64_t n) { return version == 1 ? (n + 7) / 8 * 8 : n; };
        const std::uint64_t start = 8 + (version == 3 ? 1 : 0);
        const std::uint64_t type_at = start + pad(name_size), space_at = type_at + pad(type_size),
                            value = space_at + pad(space_size);
        if (value > size || type_size < 8 || space_size < 4) return bad("its parts overrun it");
        // The value's size: the datatype's size × the dataspace's points (HDF5 copies that many bytes
        // from the message). Dataspace version 1: dims from byte 8; version 2: from byte 4, type at 3.
        const unsigned char* sp = d + space_at;
        const unsigned rank = sp[1];
        const std::uint64_t dims_at = sp[0] == 1 ? 8 : 4;
        if ((sp[0] != 1 && sp[0] != 2) || dims_at + rank * raw.length_width() > space_size) {
          return bad("its dataspace");
        }
        std::uint64_t points = sp[0] == 2 && sp[3] == 2 ? 0 : 1;  // version 2 type 2: null
        for (unsigned r = 0; r < rank && points > 0; ++r) {
          const auto dim = little_endian(sp + dims_at + r * raw.length_width(), raw.length_width());
          if (dim > size) return bad("its dataspace");
          points *= dim;
          if (points > size) return bad("its dataspace");
        }
        const auto element = little_endian(d + type_at + 4, 4);
        if (element > size || points * element > size - value) return bad("its value overruns it");
        return true;
      });
  if (!damage.empty()) throw raw.fail(damage);
}

void check_global_heaps(hid_t obj, const std::string& file, const std::string& where,
                        const std::string& attribute) {
  const LibraryLock lock;
  RawFile raw(obj, file, where);
  // In an unchecksummed header, the attribute's own heap reference: length, collection, index.
  if (const auto header = header_address(obj)) {
    const auto found_attribute = v1_attribute(raw, *header, attribute);
    if (found_attribute && found_attribute->damaged) {
      throw raw.fail("its header message is damaged (its parts overrun the message)");
    }
    if (found_attribute) check_vlen_string_type(raw, found_attribute->datatype);
    const auto value = found_attribute ? std::optional(found_attribute->value) : std::nullopt;
    if (value && value->size() < 4 + raw.addr_width() + 4) {
      throw raw.fail("its header message is damaged (too short for a string's heap reference)");
    }
    if (value) {
      const auto length = little_endian(value->data(), 4);
      const auto address = little_endian(value->data() + 4, raw.addr_width());
      const auto index = little_endian(value->data() + 4 + raw.addr_width(), 4);
      if (address != 0) {
        const auto objects = collection_objects(raw, raw.base() + address);
        bool found = false;
        if (objects && index <= 0xffff) {
          const auto object = objects->find(static_cast<std::uint16_t>(index));
          found = object != objects->end() && object->second == length;
        }
        if (!found) {
          throw raw.fail(
              fmt::format("its heap reference (collection {}, object {}, {} bytes) is damaged",
                          address, index, length));
        }
      }
    }
  }
  // Read in blocks that overlap by the signature's length, so none is missed at a block edge.
  constexpr std::uint64_t kBlock = 1 << 20;
  for (std::uint64_t at = 0; at < raw.size(); at += kBlock) {
    const auto n = std::min<std::uint64_t>(kBlock + 3, raw.size() - at);
    const auto block = raw.bytes(at, n);
    if (!block) break;
    const auto* begin = block->data();
    const auto* end = begin + block->size();
    for (const auto* p = begin; end - p >= 4;) {
      p = static_cast<const unsigned char*>(std::memchr(p, 'G', static_cast<std::size_t>(end - p)));
      if (!p || end - p < 4) break;
      if (std::memcmp(p, kSignature, 4) == 0) {
        const auto offset = at + static_cast<std::uint64_t>(p - begin);
        // The signature and version 1 are all HDF5 checks before it loads a collection (not the
        // reserved bytes: a fuzz case with them damaged hung HDF5's loader). Raw data that spells
        // "GCOL" and then 1 is not expected.
        const auto head = raw.bytes(offset, kHeader);
        if (head && (*head)[4] == 1 && !collection_objects(raw, offset)) {
          throw raw.fail(fmt::format("the global heap collection at byte {} is damaged", offset));
        }
      }
      ++p;
    }
  }
}

}  // namespace sinew::formats::hdf5
