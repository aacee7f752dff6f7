#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/hdf5_heap_check.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <new>
#include <type_traits>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/input_file.hpp"

namespace sinew::formats::hdf5 {

namespace {

// The memory type, the file type and the name in errors of each element type.
template <typename T>
struct Type {
  static hid_t native();
  static hid_t stored();
  static const char* name();
};

// H5T_NATIVE_* are macros that call H5open(), so they are looked up at run time, not cached.
#define SINEW_HDF5_TYPE(T, NATIVE, STORED, NAME) \
  template <>                                    \
  hid_t Type<T>::native() {                      \
    return NATIVE;                               \
  }                                              \
  template <>                                    \
  hid_t Type<T>::stored() {                      \
    return STORED;                               \
  }                                              \
  template <>                                    \
  const char* Type<T>::name() {                  \
    return NAME;                                 \
  }
SINEW_HDF5_TYPE(double, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, "float64")
SINEW_HDF5_TYPE(float, H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, "float32")
SINEW_HDF5_TYPE(std::int32_t, H5T_NATIVE_INT32, H5T_STD_I32LE, "int32")
SINEW_HDF5_TYPE(std::int64_t, H5T_NATIVE_INT64, H5T_STD_I64LE, "int64")
SINEW_HDF5_TYPE(std::uint8_t, H5T_NATIVE_UINT8, H5T_STD_U8LE, "uint8")
#undef SINEW_HDF5_TYPE

// A failed system call inside HDF5's file driver reads "... errno = 28, error message = 'No space
// left on device', buf = 0x..., bytes actually written = 18446744073709551615, ..." (the -1 of
// write() as unsigned): reduce that to the reason alone.
std::string system_reason(const std::string& detail) {
  const std::string key = "errno = ";
  const auto at = detail.find(key);
  if (at == std::string::npos) return {};
  const int err = std::atoi(detail.c_str() + at + key.size());
  return err > 0 ? write_failure(err) : std::string();
}

IoError io_fail(const std::string& file, const std::string& name, const std::string& what) {
  const std::string detail = error_detail();
  const std::string reason = system_reason(detail);
  return IoError(file, name, reason.empty() ? what + detail : what + ": " + reason);
}

FormatError format_fail(const std::string& file, const std::string& name, const std::string& what) {
  return FormatError(file, name, what + error_detail());
}

// Property lists without object time stamps: the same data must give byte-identical files.
Handle untimed(hid_t cls) {
  Handle p(H5Pcreate(cls), H5Pclose);
  H5Pset_obj_track_times(p, false);
  return p;
}

Handle scalar_space() {
  return Handle(H5Screate(H5S_SCALAR), H5Sclose);
}

Handle simple_space(const std::vector<hsize_t>& dims, const hsize_t* maxdims = nullptr) {
  if (dims.empty()) return scalar_space();
  return Handle(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims), H5Sclose);
}

Handle utf8_string_type() {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return t;
}

// The path of an object within its file ("/" for the root), for naming attributes in errors.
std::string attribute_path(hid_t obj, const std::string& name) {
  const ssize_t len = H5Iget_name(obj, nullptr, 0);
  std::string path = "/";
  if (len > 0) {
    path.assign(static_cast<std::size_t>(len) + 1, '\0');
    H5Iget_name(obj, path.data(), path.size());
    path.resize(static_cast<std::size_t>(len));
  }
  H5Eclear2(H5E_DEFAULT);
  return path.back() == '/' ? path + name : path + "/" + name;
}

std::string show_dims(const std::vector<hsize_t>& dims) {
  if (dims.empty()) return "scalar";
  std::string s = "(";
  for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
  return s + ")";
}

std::vector<hsize_t> dims_of(hid_t dataset, const std::string& file, const std::string& name) {
  Handle space(H5Dget_space(dataset), H5Sclose);
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space) : -1;
  if (rank < 0) throw format_fail(file, name, "cannot read the shape");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  return dims;
}

// The schemas keep every value in the one file. A link to another file, a virtual dataset (its
// values mapped from other files) or external raw storage would make what is read depend on files
// found relative to the working folder, which HDF5 opens as it follows them (a damaged model of a
// fuzz campaign crashed sinew-inspect named by a relative path and not by its absolute one). Each
// is refused before anything is read through it, naming how to bring the data in.
void refuse_external_links(hid_t loc, const std::string& name, const std::string& file) {
  std::size_t pos = 0;
  while (true) {
    pos = name.find('/', pos + 1);
    const auto part = name.substr(0, pos);
    if (!part.empty() && part != "/") {
      H5L_info_t info;
      if (H5Lget_info(loc, part.c_str(), &info, H5P_DEFAULT) >= 0 &&
          info.type != H5L_TYPE_HARD && info.type != H5L_TYPE_SOFT) {
        throw FormatError(file, part,
                          "a link to another file (or of a user-defined kind): the file must "
                          "hold its data itself (h5copy -f ext copies the linked object in)");
      }
      H5Eclear2(H5E_DEFAULT);
    }
    if (pos == std::string::npos) return;
  }
}

void refuse_other_storage(hid_t ds, const std::string& name, const std::string& file) {
  Handle dcpl(H5Dget_create_plist(ds), H5Pclose);
  if (!dcpl.valid()) return;
  if (H5Pget_layout(dcpl) == H5D_VIRTUAL) {
    // A view of this file's own data ("." as the source, the results' /frame_views) is fine.
    size_t mappings = 0;
    if (H5Pget_virtual_count(dcpl, &mappings) < 0) mappings = 1;
    for (size_t i = 0; i < mappings; ++i) {
      char source[2] = {0, 0};
      const ssize_t len = H5Pget_virtual_filename(dcpl, i, source, sizeof source);
      if (len == 1 && source[0] == '.') continue;
      throw FormatError(file, name,
                        "a virtual dataset mapping values from other files: store it in this "
                        "file (h5repack -l " + name + ":CONTI)");
    }
  }
  if (H5Pget_external_count(dcpl) > 0) {
    throw FormatError(file, name,
                      "stored in external raw files: store it in this file (h5repack -l " + name +
                          ":CONTI)");
  }
}

// Allocates n values, reporting a count too large for memory (a corrupt shape) as FormatError.
template <typename T>
std::vector<T> allocate(hsize_t n, const std::string& file, const std::string& name) {
  std::vector<T> out;
  try {
    out.resize(static_cast<std::size_t>(n));
  } catch (const std::bad_alloc&) {
    throw FormatError(file, name, fmt::format("cannot allocate memory for {} values", n));
  } catch (const std::length_error&) {
    throw FormatError(file, name, fmt::format("cannot allocate memory for {} values", n));
  }
  return out;
}

// Opens a dataset whose stored type must have class `cls` and, for numbers, T's size and sign.
template <typename T>
Handle open_typed(hid_t loc, const std::string& name, const std::string& file, H5T_class_t cls,
                  const char* dtype) {
  if (!exists(loc, name)) throw FormatError(file, name, "missing dataset");
  refuse_external_links(loc, name, file);
  Handle ds(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) throw format_fail(file, name, "cannot open, not a dataset");
  refuse_other_storage(ds, name, file);
  Handle type(H5Dget_type(ds), H5Tclose);
  bool ok = type.valid() && H5Tget_class(type) == cls;
  if (ok && cls != H5T_STRING) ok = H5Tget_size(type) == sizeof(T);
  if (ok && cls == H5T_INTEGER) {
    ok = H5Tget_sign(type) == (std::is_signed_v<T> ? H5T_SGN_2 : H5T_SGN_NONE);
  }
  if (!ok) throw FormatError(file, name, fmt::format("wrong dtype, expected {}", dtype));
  return ds;
}

// Checks rank (0: scalar, 1: (n), 2: (n, cols)) and the row limit; returns the dims.
std::vector<hsize_t> expect_shape(hid_t ds, int rank, hsize_t cols, const std::string& file,
                                  const std::string& name) {
  const auto dims = dims_of(ds, file, name);
  if (dims.size() > 2)
    throw FormatError(file, name, fmt::format("wrong shape, rank {}", dims.size()));
  const std::string want = rank == 0 ? "scalar" : rank == 1 ? "(n)" : fmt::format("(n, {})", cols);
  if (static_cast<int>(dims.size()) != rank || (rank == 2 && dims[1] != cols)) {
    throw FormatError(file, name,
                      fmt::format("wrong shape {}, expected {}", show_dims(dims), want));
  }
  if (rank > 0 && dims[0] > static_cast<hsize_t>(std::numeric_limits<std::int32_t>::max())) {
    throw FormatError(file, name,
                      fmt::format("{} rows, more than 32-bit ids can address", dims[0]));
  }
  return dims;
}

std::vector<std::string> read_string_values(hid_t ds, std::size_t n, const std::string& file,
                                            const std::string& name) {
  std::vector<std::string> out;
  out.reserve(n);
  if (n == 0) return out;
  Handle type(H5Dget_type(ds), H5Tclose);
  if (H5Tis_variable_str(type) > 0) {
    check_vlen_dataset(ds, file, name);  // the heap is unchecksummed; HDF5 would trust it
    Handle mem = utf8_string_type();
    std::vector<char*> ptrs(n, nullptr);
    if (H5Dread(ds, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()) < 0) {
      throw format_fail(file, name, "cannot read");
    }
    for (char* p : ptrs) out.emplace_back(p ? p : "");
    Handle space(H5Dget_space(ds), H5Sclose);
    H5Dvlen_reclaim(mem, space, H5P_DEFAULT, ptrs.data());
    return out;
  }
  // Fixed-length: read with one more byte per value so every value ends in NUL, in the stored
  // character set (HDF5 has no conversion between ASCII and UTF-8: a UTF-8 dataset read as ASCII
  // fails; ASCII is UTF-8, so the bytes are the same either way). Space padding (Fortran's) is
  // turned into NUL termination by HDF5's conversion.
  const std::size_t size = H5Tget_size(type);
  Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mem, size + 1);
  const H5T_cset_t cset = H5Tget_cset(type);
  if (cset == H5T_CSET_UTF8) H5Tset_cset(mem, H5T_CSET_UTF8);
  auto buf = allocate<char>(n * (size + 1), file, name);
  if (H5Dread(ds, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0) {
    throw format_fail(file, name, "cannot read");
  }
  for (std::size_t i = 0; i < n; ++i) out.emplace_back(buf.data() + i * (size + 1));
  return out;
}

// Opens attribute `name` of `obj`, which must hold one value of class `cls`.
Handle open_attribute(hid_t obj, const std::string& name, const std::string& file, H5T_class_t cls,
                      const char* what) {
  const std::string where = attribute_path(obj, name);
  if (!has_attribute(obj, name)) throw FormatError(file, where, "missing attribute");
  Handle a(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!a.valid()) throw format_fail(file, where, "cannot open the attribute");
  Handle t(H5Aget_type(a), H5Tclose);
  Handle space(H5Aget_space(a), H5Sclose);
  const H5T_class_t got = t.valid() ? H5Tget_class(t) : H5T_NO_CLASS;
  const bool class_ok = got == cls || (cls == H5T_FLOAT && got == H5T_INTEGER);
  if (!class_ok || H5Sget_simple_extent_npoints(space) != 1) {
    throw FormatError(file, where, std::string("must be one ") + what);
  }
  return a;
}

template <typename T>
T numeric_attribute(hid_t obj, const std::string& name, const std::string& file, H5T_class_t cls,
                    const char* what) {
  Handle a = open_attribute(obj, name, file, cls, what);
  T v{};
  if (H5Aread(a, Type<T>::native(), &v) < 0) {
    throw format_fail(file, attribute_path(obj, name), "cannot read the attribute");
  }
  return v;
}

// Creates (replacing) attribute `name` and writes one value of memory type `mem`.
void put_attribute(hid_t obj, const std::string& name, hid_t file_type, hid_t mem,
                   const void* value, const std::string& file) {
  Handle space = scalar_space();
  if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
  Handle attr(H5Acreate2(obj, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attr.valid() || H5Awrite(attr, mem, value) < 0) {
    throw io_fail(file, attribute_path(obj, name), "cannot write the attribute");
  }
}

}  // namespace

// ---- Files ------------------------------------------------------------------------------------

bool is_hdf5(const std::string& path) {
  std::error_code ec;  // a FIFO or a device is no HDF5 file, and reading one may block for good
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const LibraryLock lock;
  const htri_t r = H5Fis_hdf5(path.c_str());
  H5Eclear2(H5E_DEFAULT);
  return r > 0;
}

Handle create_file(const std::string& path, const std::string& display) {
  const LibraryLock lock;
  Handle fcpl = untimed(H5P_FILE_CREATE);  // the root group: no time stamps
  // The 1.8 format as the lowest: superblock v2 and object headers v2, which carry checksums, with
  // links and attributes in the headers or in checksummed fractal heaps and v2 B-trees; so a
  // damaged metadata block is an error on read, not garbage that HDF5 follows (and may crash on).
  // Not the 1.10 low bound: its superblock v3 records "open for writing" and refuses to open a
  // file whose writer was killed, and results and checkpoints must stay readable after SIGKILL.
  // The high bound keeps a newer library from writing what HDF5 1.10 (h5py on Debian, the GPU
  // machine) cannot read; the frame views (VDS) need it.
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V110);
  Handle f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl, fapl), H5Fclose);
  if (!f.valid()) throw io_fail(display.empty() ? path : display, "", "cannot create the file");
  return f;
}

namespace {

// File access for reading: one attempt at each metadata read. A block whose checksum fails is
// damaged, not being written by another process (sinew does not use SWMR), so retrying with sleeps
// in between, as HDF5 did, only delays the error (a damaged model took 0.3 s, and over 5 s on a
// loaded machine, in the fuzz test; 2 ms with one attempt).
Handle read_access() {
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_metadata_read_attempts(fapl, 1);
  return fapl;
}

}  // namespace

Handle open_file(const std::string& path, bool writable) {
  const LibraryLock lock;
  require_regular_file(path, "file");  // a FIFO would block H5Fopen for good
  const Handle fapl = read_access();
  Handle f(H5Fopen(path.c_str(), writable ? H5F_ACC_RDWR : H5F_ACC_RDONLY, fapl), H5Fclose);
  if (!f.valid()) throw io_fail(path, "", "cannot open as an HDF5 file");
  check_attribute_messages(f, path, "/");  // before any attribute is looked at
  return f;
}

Handle open_checked(const std::string& path) {
  const LibraryLock lock;
  require_regular_file(path, "file");  // a FIFO would block H5Fopen for good
  {
    // HDF5 says "unable to open file" for a missing file and for a damaged one alike; ask the
    // system first so a missing or unreadable file is an IoError with the real reason.
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw IoError(path, "", std::string("cannot open: ") + std::strerror(errno));
  }
  if (!is_hdf5(path)) throw FormatError(path, "", "not an HDF5 file (no HDF5 signature found)");
  const Handle fapl = read_access();
  Handle f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl), H5Fclose);
  if (!f.valid()) {
    throw format_fail(path, "", "cannot open as HDF5, the file is truncated or corrupt");
  }
  check_attribute_messages(f, path, "/");  // before any attribute is looked at
  return f;
}

void close_file(Handle& file, const std::string& display) {
  const LibraryLock lock;
  if (!file.close()) throw io_fail(display, "", "cannot close (flush) the file");
}

void flush(hid_t file, const std::string& path) {
  const LibraryLock lock;
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) throw io_fail(path, "", "cannot flush to disk");
}

// ---- Groups -----------------------------------------------------------------------------------

Handle create_group(hid_t loc, const std::string& name, const std::string& file, bool ordered) {
  const LibraryLock lock;
  Handle gcpl = untimed(H5P_GROUP_CREATE);
  if (ordered) H5Pset_link_creation_order(gcpl, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED);
  Handle g(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, gcpl, H5P_DEFAULT), H5Gclose);
  if (!g.valid()) throw io_fail(file, name, "cannot create the group");
  return g;
}

Handle open_group(hid_t loc, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  if (!exists(loc, name)) throw FormatError(file, name, "missing group");
  refuse_external_links(loc, name, file);
  Handle g(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g.valid()) throw format_fail(file, name, "cannot open, not a group");
  return g;
}

bool exists(hid_t loc, const std::string& name) {
  const LibraryLock lock;
  // H5Lexists needs every intermediate group to exist, so walk the path prefix by prefix.
  std::size_t pos = 0;
  while (true) {
    pos = name.find('/', pos + 1);
    const auto part = name.substr(0, pos);
    if (!part.empty() && part != "/" && H5Lexists(loc, part.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
    if (pos == std::string::npos) return true;
  }
}

std::vector<std::string> members(hid_t loc, const std::string& group, const std::string& file) {
  const LibraryLock lock;
  Handle g = open_group(loc, group, file);
  Handle gcpl(H5Gget_create_plist(g), H5Pclose);
  unsigned flags = 0;
  H5Pget_link_creation_order(gcpl, &flags);
  const H5_index_t index = (flags & H5P_CRT_ORDER_INDEXED) ? H5_INDEX_CRT_ORDER : H5_INDEX_NAME;
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  if (H5Literate(g, index, H5_ITER_INC, nullptr, cb, &names) < 0) {
    throw format_fail(file, group, "cannot list members");
  }
  return names;
}

// ---- Datasets ---------------------------------------------------------------------------------

namespace {
void write_dataset(hid_t loc, const std::string& name, const Handle& space, hid_t file_type,
                   hid_t mem_type, const void* data, bool empty, const std::string& file) {
  if (!space.valid()) throw io_fail(file, name, "cannot create a dataspace");
  Handle dcpl = untimed(H5P_DATASET_CREATE);
  Handle ds(H5Dcreate2(loc, name.c_str(), file_type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT),
            H5Dclose);
  if (!ds.valid()) throw io_fail(file, name, "cannot create the dataset");
  if (!empty && H5Dwrite(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    throw io_fail(file, name, "cannot write the dataset");
  }
}
}  // namespace

template <typename T>
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const T* data,
           const std::string& file) {
  const LibraryLock lock;
  hsize_t count = 1;
  for (auto d : dims) count *= d;
  write_dataset(loc, name, simple_space(dims), Type<T>::stored(), Type<T>::native(), data,
                count == 0, file);
}

void write_strings(hid_t loc, const std::string& name, const std::vector<std::string>& values,
                   const std::string& file) {
  const LibraryLock lock;
  std::vector<const char*> ptrs;
  ptrs.reserve(values.size());
  for (const auto& s : values) ptrs.push_back(s.c_str());
  Handle type = utf8_string_type();
  write_dataset(loc, name, simple_space({values.size()}), type, type, ptrs.data(), ptrs.empty(),
                file);
}

void write_string(hid_t loc, const std::string& name, const std::string& value,
                  const std::string& file) {
  const LibraryLock lock;
  const char* ptr = value.c_str();
  Handle type = utf8_string_type();
  write_dataset(loc, name, scalar_space(), type, type, &ptr, false, file);
}

Handle open_dataset(hid_t loc, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  if (!exists(loc, name)) throw FormatError(file, name, "missing dataset");
  refuse_external_links(loc, name, file);
  Handle ds(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) throw format_fail(file, name, "cannot open, not a dataset");
  refuse_other_storage(ds, name, file);
  // A compact dataset keeps its values in its header's layout message, whose size no checksum
  // ties to the dataspace in an old-format header: HDF5 1.10 copies the dataspace's worth of bytes
  // whatever the message holds (a fuzz case read past an 8-byte block under valgrind, and the heap
  // was corrupt by the end of the run). Refuse a layout that holds less than its dataspace needs.
  Handle dcpl(H5Dget_create_plist(ds), H5Pclose);
  if (dcpl.valid() && H5Pget_layout(dcpl) == H5D_COMPACT) {
    Handle space(H5Dget_space(ds), H5Sclose);
    Handle type(H5Dget_type(ds), H5Tclose);
    const hssize_t points = space.valid() ? H5Sget_simple_extent_npoints(space) : -1;
    const std::size_t size = type.valid() ? H5Tget_size(type) : 0;
    const hsize_t stored = H5Dget_storage_size(ds);
    if (points < 0 || size == 0 ||
        static_cast<hsize_t>(points) > std::numeric_limits<hsize_t>::max() / size ||
        stored < static_cast<hsize_t>(points) * size) {
      throw FormatError(
          file, name,
          fmt::format("damaged: its compact storage holds {} bytes for {} values", stored, points));
    }
  }
  return ds;
}

std::vector<hsize_t> shape(hid_t loc, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  return dims_of(open_dataset(loc, name, file), file, name);
}

template <typename T>
std::vector<T> read(hid_t loc, const std::string& name, const std::string& file,
                    std::int64_t expected) {
  const LibraryLock lock;
  Handle ds = open_dataset(loc, name, file);
  hsize_t n = 1;
  for (auto d : dims_of(ds, file, name)) n *= d;
  if (expected >= 0 && n != static_cast<hsize_t>(expected)) {
    throw FormatError(file, name, fmt::format("expected {} values, found {}", expected, n));
  }
  auto out = allocate<T>(n, file, name);
  if (n > 0 && H5Dread(ds, Type<T>::native(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) {
    throw format_fail(file, name, "cannot read");
  }
  return out;
}

template <typename T>
std::vector<T> read_array(hid_t loc, const std::string& name, const std::string& file,
                          hsize_t cols) {
  const LibraryLock lock;
  constexpr H5T_class_t cls = std::is_floating_point_v<T> ? H5T_FLOAT : H5T_INTEGER;
  Handle ds = open_typed<T>(loc, name, file, cls, Type<T>::name());
  const auto dims = expect_shape(ds, cols == 0 ? 1 : 2, cols, file, name);
  auto out = allocate<T>(dims[0] * (cols == 0 ? 1 : cols), file, name);
  if (!out.empty() &&
      H5Dread(ds, Type<T>::native(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) {
    throw format_fail(file, name, "cannot read");
  }
  return out;
}

template <typename T>
T read_scalar(hid_t loc, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  constexpr H5T_class_t cls = std::is_floating_point_v<T> ? H5T_FLOAT : H5T_INTEGER;
  Handle ds = open_typed<T>(loc, name, file, cls, Type<T>::name());
  expect_shape(ds, 0, 0, file, name);
  T v{};
  if (H5Dread(ds, Type<T>::native(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &v) < 0) {
    throw format_fail(file, name, "cannot read");
  }
  return v;
}

std::vector<std::string> read_strings(hid_t loc, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  Handle ds = open_typed<char>(loc, name, file, H5T_STRING, "string");
  const auto dims = expect_shape(ds, 1, 0, file, name);
  return read_string_values(ds, static_cast<std::size_t>(dims[0]), file, name);
}

std::string read_string(hid_t loc, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  Handle ds = open_typed<char>(loc, name, file, H5T_STRING, "string");
  expect_shape(ds, 0, 0, file, name);
  return read_string_values(ds, 1, file, name).front();
}

// ---- Extendible datasets ----------------------------------------------------------------------

template <typename T>
Handle create_series(hid_t loc, const std::string& name, const std::vector<hsize_t>& tail,
                     const std::string& file) {
  const LibraryLock lock;
  std::vector<hsize_t> dims{0}, maxdims{H5S_UNLIMITED}, chunk{1};
  for (auto t : tail) {
    dims.push_back(t);
    maxdims.push_back(t);
    chunk.push_back(t == 0 ? 1 : t);  // a chunk dimension of 0 is invalid
  }
  Handle space = simple_space(dims, maxdims.data());
  Handle plist = untimed(H5P_DATASET_CREATE);
  H5Pset_chunk(plist, static_cast<int>(chunk.size()), chunk.data());
  Handle ds(
      H5Dcreate2(loc, name.c_str(), Type<T>::stored(), space, H5P_DEFAULT, plist, H5P_DEFAULT),
      H5Dclose);
  if (!ds.valid()) throw io_fail(file, name, "cannot create the extendible dataset");
  return ds;
}

template <typename T>
void append(hid_t dataset, hsize_t frame, const T* data, const std::string& file,
            const std::string& name) {
  const LibraryLock lock;
  auto dims = dims_of(dataset, file, name);
  dims[0] = frame + 1;
  if (H5Dset_extent(dataset, dims.data()) < 0) throw io_fail(file, name, "cannot extend");
  Handle fspace(H5Dget_space(dataset), H5Sclose);
  std::vector<hsize_t> start(dims.size(), 0), count = dims;
  start[0] = frame;
  count[0] = 1;
  H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
  Handle mspace = simple_space(count);
  if (H5Dwrite(dataset, Type<T>::native(), mspace, fspace, H5P_DEFAULT, data) < 0) {
    throw io_fail(file, name, "cannot write a frame");
  }
}

std::vector<ChunkExtent> chunk_extents(hid_t dataset, const std::string& file,
                                       const std::string& name) {
  // A damaged chunk address (one flipped byte of a results file in a fuzz case) put a chunk past
  // the file's end or over another one; freeing it on a resume left HDF5's free-space manager to
  // crash when the file was closed.
  const LibraryLock lock;
  std::vector<ChunkExtent> out;
  Handle dcpl(H5Dget_create_plist(dataset), H5Pclose);
  if (!dcpl.valid() || H5Pget_layout(dcpl) != H5D_CHUNKED) return out;
  Handle owner(H5Iget_file_id(dataset), H5Fclose);
  Handle space(H5Dget_space(dataset), H5Sclose);
  hsize_t eof = 0, chunks = 0;
  if (H5Fget_filesize(owner, &eof) < 0 || H5Dget_num_chunks(dataset, space, &chunks) < 0) {
    throw format_fail(file, name, "cannot list the chunks");
  }
  for (hsize_t i = 0; i < chunks; ++i) {
    haddr_t addr = HADDR_UNDEF;
    hsize_t size = 0;
    if (H5Dget_chunk_info(dataset, space, i, nullptr, nullptr, &addr, &size) < 0) {
      throw format_fail(file, name, "cannot read the chunk index");
    }
    if (addr == HADDR_UNDEF) continue;
    if (addr > eof || size > eof - addr) {
      throw FormatError(file, name,
                        fmt::format("damaged: chunk {} at bytes {} to {} lies past the file's "
                                    "end ({} bytes)",
                                    i, addr, addr + size, eof));
    }
    out.push_back({addr, size, name});
  }
  return out;
}

void check_disjoint(std::vector<ChunkExtent> extents, const std::string& file) {
  std::sort(extents.begin(), extents.end(),
            [](const ChunkExtent& a, const ChunkExtent& b) { return a.address < b.address; });
  for (std::size_t i = 1; i < extents.size(); ++i) {
    const auto& a = extents[i - 1];
    const auto& b = extents[i];
    if (b.address < a.address + a.size) {
      throw FormatError(
          file, b.dataset,
          fmt::format("damaged: a chunk at bytes {} to {} overlaps one of {} at {} "
                      "to {}",
                      b.address, b.address + b.size, a.dataset, a.address, a.address + a.size));
    }
  }
}

void set_frames(hid_t dataset, hsize_t frames, const std::string& file, const std::string& name) {
  const LibraryLock lock;
  auto dims = dims_of(dataset, file, name);
  if (dims.empty()) throw FormatError(file, name, "a scalar has no frames");
  // Shrinking frees the chunks past `frames` at the addresses the chunk index gives.
  if (frames < dims[0]) (void)chunk_extents(dataset, file, name);
  dims[0] = frames;
  if (H5Dset_extent(dataset, dims.data()) < 0) {
    throw io_fail(file, name, "cannot change the frame count");
  }
}

void create_frame_view(hid_t loc, const std::string& name, const std::string& source, hsize_t frame,
                       const std::string& file) {
  const LibraryLock lock;
  Handle src(H5Dopen2(loc, source.c_str(), H5P_DEFAULT), H5Dclose);
  if (!src.valid()) throw io_fail(file, source, "cannot open the dataset to view");
  auto dims = dims_of(src, file, source);
  if (dims.empty() || frame >= dims[0]) {
    throw IoError(file, source, "a frame view past the dataset's last frame");
  }
  Handle type(H5Dget_type(src), H5Tclose);
  std::vector<hsize_t> start(dims.size(), 0), count = dims;
  start[0] = frame;
  count[0] = 1;
  // The source selection is frame `frame` of a space whose first axis is unlimited, so the view
  // stays valid while the series grows; "." names the file the view is in.
  std::vector<hsize_t> maxdims = dims;
  maxdims[0] = H5S_UNLIMITED;
  Handle src_space = simple_space(dims, maxdims.data());
  H5Sselect_hyperslab(src_space, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
  const std::vector<hsize_t> tail(dims.begin() + 1, dims.end());
  Handle view_space = simple_space(tail);
  Handle plist = untimed(H5P_DATASET_CREATE);
  if (H5Pset_virtual(plist, view_space, ".", source.c_str(), src_space) < 0) {
    throw io_fail(file, name, "cannot map the frame view");
  }
  Handle lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl, 1);
  Handle ds(H5Dcreate2(loc, name.c_str(), type, view_space, lcpl, plist, H5P_DEFAULT), H5Dclose);
  if (!ds.valid()) throw io_fail(file, name, "cannot create the frame view");
}

// ---- Attributes -------------------------------------------------------------------------------

void set_attribute(hid_t obj, const std::string& name, const std::string& value,
                   const std::string& file, StringKind kind) {
  const LibraryLock lock;
  if (kind == StringKind::variable) {
    Handle type = utf8_string_type();
    const char* ptr = value.c_str();
    put_attribute(obj, name, type, type, &ptr, file);
    return;
  }
  // HDF5 has no zero-size strings: an empty value is stored as one NUL.
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type, value.empty() ? 1 : value.size());
  H5Tset_strpad(type, H5T_STR_NULLPAD);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  put_attribute(obj, name, type, type, padded.data(), file);
}

void set_attribute(hid_t obj, const std::string& name, double value, const std::string& file) {
  const LibraryLock lock;
  put_attribute(obj, name, Type<double>::stored(), Type<double>::native(), &value, file);
}
void set_attribute(hid_t obj, const std::string& name, std::int64_t value,
                   const std::string& file) {
  const LibraryLock lock;
  put_attribute(obj, name, Type<std::int64_t>::stored(), Type<std::int64_t>::native(), &value,
                file);
}
void set_attribute(hid_t obj, const std::string& name, std::int32_t value,
                   const std::string& file) {
  const LibraryLock lock;
  put_attribute(obj, name, Type<std::int32_t>::stored(), Type<std::int32_t>::native(), &value,
                file);
}

bool has_attribute(hid_t obj, const std::string& name) {
  const LibraryLock lock;
  const bool yes = H5Aexists(obj, name.c_str()) > 0;
  H5Eclear2(H5E_DEFAULT);
  return yes;
}

std::string string_attribute(hid_t obj, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  Handle a = open_attribute(obj, name, file, H5T_STRING, "string");
  Handle t(H5Aget_type(a), H5Tclose);
  if (H5Tis_variable_str(t) > 0) {
    check_global_heaps(obj, file, attribute_path(obj, name), name);  // as for string datasets
    Handle mem = utf8_string_type();
    char* value = nullptr;
    if (H5Aread(a, mem, &value) < 0) {
      throw format_fail(file, attribute_path(obj, name), "cannot read the attribute");
    }
    std::string out = value ? value : "";
    H5free_memory(value);
    return out;
  }
  const std::size_t size = H5Tget_size(t);
  std::vector<char> buf(size + 1, '\0');  // one more byte: always NUL-terminated
  Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mem, size + 1);
  if (H5Aread(a, mem, buf.data()) < 0) {
    throw format_fail(file, attribute_path(obj, name), "cannot read the attribute");
  }
  return std::string(buf.data());
}

double double_attribute(hid_t obj, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  return numeric_attribute<double>(obj, name, file, H5T_FLOAT, "number");
}
std::int64_t int_attribute(hid_t obj, const std::string& name, const std::string& file) {
  const LibraryLock lock;
  return numeric_attribute<std::int64_t>(obj, name, file, H5T_INTEGER, "integer");
}

// ---- Instantiations ---------------------------------------------------------------------------

#define SINEW_HDF5_INSTANTIATE(T)                                                                \
  template void write<T>(hid_t, const std::string&, const std::vector<hsize_t>&, const T*,       \
                         const std::string&);                                                    \
  template std::vector<T> read<T>(hid_t, const std::string&, const std::string&, std::int64_t);  \
  template std::vector<T> read_array<T>(hid_t, const std::string&, const std::string&, hsize_t); \
  template T read_scalar<T>(hid_t, const std::string&, const std::string&);                      \
  template Handle create_series<T>(hid_t, const std::string&, const std::vector<hsize_t>&,       \
                                   const std::string&);                                          \
  template void append<T>(hid_t, hsize_t, const T*, const std::string&, const std::string&);
SINEW_HDF5_INSTANTIATE(double)
SINEW_HDF5_INSTANTIATE(float)
SINEW_HDF5_INSTANTIATE(std::int32_t)
SINEW_HDF5_INSTANTIATE(std::int64_t)
SINEW_HDF5_INSTANTIATE(std::uint8_t)
#undef SINEW_HDF5_INSTANTIATE

}  // namespace sinew::formats::hdf5
