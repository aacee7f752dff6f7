#include "sinew/simulator/hdf5_io.hpp"

#include <fmt/format.h>

#include <mutex>

#include "sinew/common/error.hpp"

namespace sinew::simulator::h5 {

namespace {

// The HDF5 error stack's innermost message, appended to ours.
herr_t walk(unsigned, const H5E_error2_t* err, void* out) {
  auto* s = static_cast<std::string*>(out);
  if (s->empty() && err->desc) *s = err->desc;
  return 0;
}

std::string last_error() {
  std::string s;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk, &s);
  return s.empty() ? "" : " (" + s + ")";
}

IoError fail(const std::string& file, const std::string& name, const std::string& what) {
  return IoError(file, name, what + last_error());
}

template <typename T>
hid_t native();
template <>
hid_t native<double>() {
  return H5T_NATIVE_DOUBLE;
}
template <>
hid_t native<float>() {
  return H5T_NATIVE_FLOAT;
}
template <>
hid_t native<std::int32_t>() {
  return H5T_NATIVE_INT32;
}
template <>
hid_t native<std::int64_t>() {
  return H5T_NATIVE_INT64;
}
template <>
hid_t native<std::uint8_t>() {
  return H5T_NATIVE_UINT8;
}

template <typename T>
void write_any(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const T* data,
               const std::string& file, hid_t file_type) {
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
               Handle::Kind::dataspace);
  if (!space.valid()) throw fail(file, name, "cannot create a dataspace");
  Handle ds(H5Dcreate2(loc, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
            Handle::Kind::dataset);
  if (!ds.valid()) throw fail(file, name, "cannot create the dataset");
  hsize_t count = 1;
  for (auto d : dims) count *= d;
  if (count > 0 && H5Dwrite(ds, native<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    throw fail(file, name, "cannot write");
  }
}

}  // namespace

Handle& Handle::operator=(Handle&& o) noexcept {
  if (this != &o) {
    close();
    id_ = o.id_;
    kind_ = o.kind_;
    o.id_ = -1;
  }
  return *this;
}

void Handle::close() {
  if (id_ < 0) return;
  switch (kind_) {
    case Kind::file:
      H5Fclose(id_);
      break;
    case Kind::group:
      H5Gclose(id_);
      break;
    case Kind::dataset:
      H5Dclose(id_);
      break;
    case Kind::dataspace:
      H5Sclose(id_);
      break;
    case Kind::attribute:
      H5Aclose(id_);
      break;
    case Kind::plist:
      H5Pclose(id_);
      break;
    case Kind::datatype:
      H5Tclose(id_);
      break;
  }
  id_ = -1;
}

void quiet_errors() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

Handle create_file(const std::string& path) {
  quiet_errors();
  Handle f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), Handle::Kind::file);
  if (!f.valid()) throw fail(path, "", "cannot create the HDF5 file");
  return f;
}

Handle open_file(const std::string& path, bool writable) {
  quiet_errors();
  Handle f(H5Fopen(path.c_str(), writable ? H5F_ACC_RDWR : H5F_ACC_RDONLY, H5P_DEFAULT),
           Handle::Kind::file);
  if (!f.valid()) throw fail(path, "", "cannot open as an HDF5 file");
  return f;
}

Handle create_group(hid_t loc, const std::string& name, const std::string& file) {
  Handle g(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
           Handle::Kind::group);
  if (!g.valid()) throw fail(file, name, "cannot create the group");
  return g;
}

Handle open_group(hid_t loc, const std::string& name, const std::string& file) {
  Handle g(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), Handle::Kind::group);
  if (!g.valid()) throw FormatError(file, name, "missing group" + last_error());
  return g;
}

bool exists(hid_t loc, const std::string& name) {
  // Walk the path so a missing intermediate group is "absent", not an error.
  std::size_t pos = 0;
  while (true) {
    pos = name.find('/', pos + 1);
    const auto part = name.substr(0, pos);
    if (!part.empty() && part != "/" && H5Lexists(loc, part.c_str(), H5P_DEFAULT) <= 0)
      return false;
    if (pos == std::string::npos) return true;
  }
}

void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const double* data,
           const std::string& file) {
  write_any(loc, name, dims, data, file, H5T_IEEE_F64LE);
}
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const float* data,
           const std::string& file) {
  write_any(loc, name, dims, data, file, H5T_IEEE_F32LE);
}
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
           const std::int32_t* data, const std::string& file) {
  write_any(loc, name, dims, data, file, H5T_STD_I32LE);
}
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
           const std::int64_t* data, const std::string& file) {
  write_any(loc, name, dims, data, file, H5T_STD_I64LE);
}
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
           const std::uint8_t* data, const std::string& file) {
  write_any(loc, name, dims, data, file, H5T_STD_U8LE);
}

Handle open_dataset(hid_t loc, const std::string& name, const std::string& file) {
  Handle ds(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), Handle::Kind::dataset);
  if (!ds.valid()) throw FormatError(file, name, "missing dataset" + last_error());
  return ds;
}

std::vector<hsize_t> shape(hid_t loc, const std::string& name, const std::string& file) {
  auto ds = open_dataset(loc, name, file);
  Handle space(H5Dget_space(ds), Handle::Kind::dataspace);
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 0) throw fail(file, name, "cannot read the shape");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  return dims;
}

template <typename T>
std::vector<T> read(hid_t loc, const std::string& name, const std::string& file,
                    std::int64_t expected) {
  const auto dims = shape(loc, name, file);
  hsize_t n = 1;
  for (auto d : dims) n *= d;
  if (expected >= 0 && n != static_cast<hsize_t>(expected)) {
    throw FormatError(file, name, fmt::format("expected {} values, found {}", expected, n));
  }
  std::vector<T> out(n);
  auto ds = open_dataset(loc, name, file);
  if (n > 0 && H5Dread(ds, native<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) {
    throw fail(file, name, "cannot read");
  }
  return out;
}
template std::vector<double> read<double>(hid_t, const std::string&, const std::string&,
                                          std::int64_t);
template std::vector<float> read<float>(hid_t, const std::string&, const std::string&,
                                        std::int64_t);
template std::vector<std::int32_t> read<std::int32_t>(hid_t, const std::string&, const std::string&,
                                                      std::int64_t);
template std::vector<std::int64_t> read<std::int64_t>(hid_t, const std::string&, const std::string&,
                                                      std::int64_t);
template std::vector<std::uint8_t> read<std::uint8_t>(hid_t, const std::string&, const std::string&,
                                                      std::int64_t);

Handle create_series(hid_t loc, const std::string& name, const std::vector<hsize_t>& tail,
                     hid_t file_type, const std::string& file) {
  std::vector<hsize_t> dims{0}, maxdims{H5S_UNLIMITED}, chunk{1};
  for (auto t : tail) {
    dims.push_back(t);
    maxdims.push_back(t);
    chunk.push_back(t == 0 ? 1 : t);
  }
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data()),
               Handle::Kind::dataspace);
  Handle plist(H5Pcreate(H5P_DATASET_CREATE), Handle::Kind::plist);
  H5Pset_chunk(plist, static_cast<int>(chunk.size()), chunk.data());
  Handle ds(H5Dcreate2(loc, name.c_str(), file_type, space, H5P_DEFAULT, plist, H5P_DEFAULT),
            Handle::Kind::dataset);
  if (!ds.valid()) throw fail(file, name, "cannot create the extendible dataset");
  return ds;
}

void append(hid_t dataset, hsize_t frame, hid_t mem_type, const void* data, const std::string& file,
            const std::string& name) {
  Handle space(H5Dget_space(dataset), Handle::Kind::dataspace);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  dims[0] = frame + 1;
  if (H5Dset_extent(dataset, dims.data()) < 0) throw fail(file, name, "cannot extend");
  Handle fspace(H5Dget_space(dataset), Handle::Kind::dataspace);
  std::vector<hsize_t> start(dims.size(), 0), count = dims;
  start[0] = frame;
  count[0] = 1;
  H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
  Handle mspace(H5Screate_simple(rank, count.data(), nullptr), Handle::Kind::dataspace);
  if (H5Dwrite(dataset, mem_type, mspace, fspace, H5P_DEFAULT, data) < 0)
    throw fail(file, name, "cannot write a frame");
}

void set_frames(hid_t dataset, hsize_t frames, const std::string& file, const std::string& name) {
  Handle space(H5Dget_space(dataset), Handle::Kind::dataspace);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  dims[0] = frames;
  if (H5Dset_extent(dataset, dims.data()) < 0)
    throw fail(file, name, "cannot change the frame count");
}

void set_attribute(hid_t obj, const std::string& name, const std::string& value,
                   const std::string& file) {
  Handle type(H5Tcopy(H5T_C_S1), Handle::Kind::datatype);
  H5Tset_size(type, value.empty() ? 1 : value.size());
  H5Tset_strpad(type, H5T_STR_NULLPAD);
  Handle space(H5Screate(H5S_SCALAR), Handle::Kind::dataspace);
  if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
  Handle attr(H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT),
              Handle::Kind::attribute);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  if (!attr.valid() || H5Awrite(attr, type, padded.data()) < 0)
    throw fail(file, name, "cannot write the attribute");
}

namespace {
template <typename T>
void set_numeric(hid_t obj, const std::string& name, T value, hid_t file_type,
                 const std::string& file) {
  Handle space(H5Screate(H5S_SCALAR), Handle::Kind::dataspace);
  if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
  Handle attr(H5Acreate2(obj, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT),
              Handle::Kind::attribute);
  if (!attr.valid() || H5Awrite(attr, native<T>(), &value) < 0)
    throw fail(file, name, "cannot write the attribute");
}
template <typename T>
T get_numeric(hid_t obj, const std::string& name, const std::string& file) {
  Handle attr(H5Aopen(obj, name.c_str(), H5P_DEFAULT), Handle::Kind::attribute);
  T v{};
  if (!attr.valid() || H5Aread(attr, native<T>(), &v) < 0)
    throw FormatError(file, name, "missing or unreadable attribute");
  return v;
}
}  // namespace

void set_attribute(hid_t obj, const std::string& name, double value, const std::string& file) {
  set_numeric(obj, name, value, H5T_IEEE_F64LE, file);
}
void set_attribute(hid_t obj, const std::string& name, std::int64_t value,
                   const std::string& file) {
  set_numeric(obj, name, value, H5T_STD_I64LE, file);
}
double double_attribute(hid_t obj, const std::string& name, const std::string& file) {
  return get_numeric<double>(obj, name, file);
}
std::int64_t int_attribute(hid_t obj, const std::string& name, const std::string& file) {
  return get_numeric<std::int64_t>(obj, name, file);
}
bool has_attribute(hid_t obj, const std::string& name) {
  return H5Aexists(obj, name.c_str()) > 0;
}

std::string string_attribute(hid_t obj, const std::string& name, const std::string& file) {
  Handle attr(H5Aopen(obj, name.c_str(), H5P_DEFAULT), Handle::Kind::attribute);
  if (!attr.valid()) throw FormatError(file, name, "missing attribute");
  Handle type(H5Aget_type(attr), Handle::Kind::datatype);
  if (H5Tget_class(type) != H5T_STRING || H5Tis_variable_str(type) > 0) {
    throw FormatError(file, name, "expected a fixed-length string attribute");
  }
  const auto size = H5Tget_size(type);
  std::string s(size, '\0');
  Handle mem(H5Tcopy(H5T_C_S1), Handle::Kind::datatype);
  H5Tset_size(mem, size);
  H5Tset_strpad(mem, H5T_STR_NULLPAD);
  if (H5Aread(attr, mem, s.data()) < 0) throw fail(file, name, "cannot read the attribute");
  s.resize(s.find('\0') == std::string::npos ? s.size() : s.find('\0'));
  return s;
}

void flush(hid_t file, const std::string& path) {
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) throw fail(path, "", "cannot flush to disk");
}

}  // namespace sinew::simulator::h5
