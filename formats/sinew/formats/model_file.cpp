#include "sinew/formats/model_file.hpp"

#include <hdf5.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/formats/validate.hpp"

namespace sinew::formats {

static_assert(sizeof(Lattice) == 3 * sizeof(std::int32_t), "Lattice must be three packed int32");
static_assert(sizeof(Point) == 3 * sizeof(double), "Point must be three packed doubles");
static_assert(sizeof(std::array<Index, 8>) == 8 * sizeof(Index), "hex8 node rows must be packed");
static_assert(sizeof(std::array<Index, 3>) == 3 * sizeof(Index), "triangles must be packed");

namespace {

// HDF5 reports failures on its error stack; we turn them into our exceptions instead of printing.
void silence_hdf5() {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

herr_t collect_error(unsigned n, const H5E_error2_t* err, void* data) {
  auto* out = static_cast<std::string*>(data);
  (void)n;
  if (err->desc && *err->desc) *out = err->desc;  // walking downward: keep the innermost
  return 0;
}

// The innermost message of HDF5's current error stack ("" when empty), clearing the stack.
std::string hdf5_detail() {
  std::string detail;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect_error, &detail);
  H5Eclear2(H5E_DEFAULT);
  return detail.empty() ? std::string() : " (HDF5: " + detail + ")";
}

// Owns one HDF5 identifier and closes it with the matching function.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(o.id_), closer_(o.closer_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      closer_ = o.closer_;
      o.id_ = -1;
    }
    return *this;
  }
  ~Handle() { reset(); }
  void reset() {
    if (id_ >= 0 && closer_) closer_(id_);
    id_ = -1;
  }
  // Closes now and reports whether closing worked (needed for the file, where close flushes).
  bool close() {
    const herr_t status = id_ >= 0 && closer_ ? closer_(id_) : 0;
    id_ = -1;
    return status >= 0;
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

Handle string_type() {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t.get(), H5T_VARIABLE);
  H5Tset_cset(t.get(), H5T_CSET_UTF8);
  return t;
}

template <typename T>
hid_t native_type();
template <>
hid_t native_type<std::int32_t>() {
  return H5T_NATIVE_INT32;
}
template <>
hid_t native_type<std::int64_t>() {
  return H5T_NATIVE_INT64;
}
template <>
hid_t native_type<double>() {
  return H5T_NATIVE_DOUBLE;
}

template <typename T>
hid_t file_type();
template <>
hid_t file_type<std::int32_t>() {
  return H5T_STD_I32LE;
}
template <>
hid_t file_type<std::int64_t>() {
  return H5T_STD_I64LE;
}
template <>
hid_t file_type<double>() {
  return H5T_IEEE_F64LE;
}

// ------------------------------------------------------------------------------------------------
// Writer

class Writer {
 public:
  Writer(const std::string& path, const std::string& display) : display_(display) {
    Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
    H5Pset_obj_track_times(fcpl.get(), false);  // root group: no time stamps
    file_ = Handle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT), H5Fclose);
    if (!file_.valid()) fail("", "cannot create the file" + hdf5_detail());
    dcpl_ = Handle(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_obj_track_times(dcpl_.get(), false);
    gcpl_ = Handle(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
    H5Pset_obj_track_times(gcpl_.get(), false);
    ordered_gcpl_ = Handle(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
    H5Pset_obj_track_times(ordered_gcpl_.get(), false);
    H5Pset_link_creation_order(ordered_gcpl_.get(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED);
    strtype_ = string_type();
  }

  [[noreturn]] void fail(const std::string& dataset, const std::string& problem) const {
    throw IoError(display_, dataset, problem);
  }

  void close() {
    if (!file_.close()) fail("", "cannot close (flush) the file" + hdf5_detail());
  }

  // ordered: keep the links in creation order (named sets keep the order of the model).
  void group(const std::string& path, bool ordered = false) {
    Handle g(H5Gcreate2(file_.get(), path.c_str(), H5P_DEFAULT,
                        ordered ? ordered_gcpl_.get() : gcpl_.get(), H5P_DEFAULT),
             H5Gclose);
    if (!g.valid()) fail(path, "cannot create group" + hdf5_detail());
  }

  // rows × cols array (cols == 0: a 1-D array of `rows`; rows < 0: a scalar).
  template <typename T>
  void array(const std::string& path, const T* data, std::int64_t rows, int cols = 0) {
    Handle space = rows < 0 ? Handle(H5Screate(H5S_SCALAR), H5Sclose) : make_space(rows, cols);
    Handle ds(H5Dcreate2(file_.get(), path.c_str(), file_type<T>(), space.get(), H5P_DEFAULT,
                         dcpl_.get(), H5P_DEFAULT),
              H5Dclose);
    if (!ds.valid()) fail(path, "cannot create dataset" + hdf5_detail());
    if (rows != 0 &&
        H5Dwrite(ds.get(), native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
      fail(path, "cannot write dataset" + hdf5_detail());
    }
  }
  template <typename T>
  void array(const std::string& path, const std::vector<T>& v) {
    array(path, v.data(), static_cast<std::int64_t>(v.size()));
  }
  void scalar(const std::string& path, double v) { array(path, &v, -1); }

  void strings(const std::string& path, const std::vector<std::string>& values) {
    std::vector<const char*> ptrs;
    ptrs.reserve(values.size());
    for (const auto& s : values) ptrs.push_back(s.c_str());
    Handle space = make_space(static_cast<std::int64_t>(values.size()), 0);
    write_strings(path, space, ptrs);
  }
  void string(const std::string& path, const std::string& value) {
    std::vector<const char*> ptrs{value.c_str()};
    Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    write_strings(path, space, ptrs);
  }

  void root_attributes() {
    Handle scalar_space(H5Screate(H5S_SCALAR), H5Sclose);
    Handle a(H5Acreate2(file_.get(), "format", strtype_.get(), scalar_space.get(), H5P_DEFAULT,
                        H5P_DEFAULT),
             H5Aclose);
    const char* name = kModelFormatName;
    if (!a.valid() || H5Awrite(a.get(), strtype_.get(), &name) < 0) {
      fail("/format", "cannot write attribute" + hdf5_detail());
    }
    Handle v(H5Acreate2(file_.get(), "format_version", H5T_STD_I32LE, scalar_space.get(),
                        H5P_DEFAULT, H5P_DEFAULT),
             H5Aclose);
    const std::int32_t version = kModelFormatVersion;
    if (!v.valid() || H5Awrite(v.get(), H5T_NATIVE_INT32, &version) < 0) {
      fail("/format_version", "cannot write attribute" + hdf5_detail());
    }
  }

 private:
  static Handle make_space(std::int64_t rows, int cols) {
    const hsize_t dims[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
    return Handle(H5Screate_simple(cols > 0 ? 2 : 1, dims, nullptr), H5Sclose);
  }
  void write_strings(const std::string& path, const Handle& space,
                     const std::vector<const char*>& ptrs) {
    Handle ds(H5Dcreate2(file_.get(), path.c_str(), strtype_.get(), space.get(), H5P_DEFAULT,
                         dcpl_.get(), H5P_DEFAULT),
              H5Dclose);
    if (!ds.valid()) fail(path, "cannot create dataset" + hdf5_detail());
    if (!ptrs.empty() &&
        H5Dwrite(ds.get(), strtype_.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()) < 0) {
      fail(path, "cannot write dataset" + hdf5_detail());
    }
  }

  std::string display_;
  Handle file_, dcpl_, gcpl_, ordered_gcpl_, strtype_;
};

template <typename Range, typename Get>
auto column(const Range& items, Get get) {
  std::vector<decltype(get(items.front()))> out;
  out.reserve(items.size());
  for (const auto& item : items) out.push_back(get(item));
  return out;
}

void write_all(Writer& w, const Model& m) {
  w.root_attributes();

  w.group("/grid");
  w.array("/grid/origin", m.grid.origin.data(), 3);
  w.scalar("/grid/voxel_size", m.grid.voxel_size);
  w.array("/grid/dims", m.grid.dims.data(), 3);

  const auto n_count = static_cast<std::int64_t>(m.node_count());
  const auto e_count = static_cast<std::int64_t>(m.element_count());
  w.group("/nodes");
  w.array("/nodes/lattice", m.node_lattice.front().data(), n_count, 3);
  w.group("/elements");
  w.array("/elements/lattice", m.element_lattice.front().data(), e_count, 3);
  w.array("/elements/nodes", m.element_nodes.front().data(), e_count, 8);

  const auto& ms = m.materials;
  w.group("/materials");
  w.strings("/materials/name", column(ms, [](const Material& x) { return x.name; }));
  w.strings("/materials/law",
            column(ms, [](const Material& x) { return std::string(to_string(x.law)); }));
  w.array("/materials/youngs_modulus",
          column(ms, [](const Material& x) { return x.youngs_modulus; }));
  w.array("/materials/poisson_ratio",
          column(ms, [](const Material& x) { return x.poisson_ratio; }));
  w.array("/materials/shear_modulus",
          column(ms, [](const Material& x) { return x.shear_modulus; }));
  w.array("/materials/bulk_modulus", column(ms, [](const Material& x) { return x.bulk_modulus; }));
  w.array("/materials/density", column(ms, [](const Material& x) { return x.density; }));

  w.group("/element_materials");
  w.array("/element_materials/offsets", m.material_offsets);
  w.array("/element_materials/material", m.material_ids);
  w.array("/element_materials/fraction", m.material_fractions);

  const auto& mu = m.muscles;
  w.group("/muscles");
  w.strings("/muscles/name", column(mu, [](const Muscle& x) { return x.name; }));
  w.array("/muscles/material", column(mu, [](const Muscle& x) { return x.material; }));
  w.array("/muscles/reference_stress",
          column(mu, [](const Muscle& x) { return x.reference_stress; }));
  w.array("/muscles/optimal_stretch",
          column(mu, [](const Muscle& x) { return x.optimal_stretch; }));
  w.strings("/muscles/force_length",
            column(mu, [](const Muscle& x) { return std::string(to_string(x.force_length)); }));
  w.array("/muscles/passive_p1", column(mu, [](const Muscle& x) { return x.passive_p1; }));
  w.array("/muscles/passive_p2", column(mu, [](const Muscle& x) { return x.passive_p2; }));
  w.array("/muscles/passive_linear_stretch",
          column(mu, [](const Muscle& x) { return x.passive_linear_stretch; }));
  std::vector<Offset> offsets{0};
  std::vector<Index> elements;
  std::vector<double> fractions;
  std::vector<Point> fibres;
  for (const auto& x : mu) {
    elements.insert(elements.end(), x.elements.begin(), x.elements.end());
    fractions.insert(fractions.end(), x.fractions.begin(), x.fractions.end());
    fibres.insert(fibres.end(), x.fibres.begin(), x.fibres.end());
    offsets.push_back(static_cast<Offset>(elements.size()));
  }
  w.array("/muscles/offsets", offsets);
  w.array("/muscles/elements", elements);
  w.array("/muscles/fractions", fractions);
  w.array("/muscles/fibres", fibres.empty() ? nullptr : fibres.front().data(),
          static_cast<std::int64_t>(fibres.size()), 3);

  w.group("/constraints");
  w.array("/constraints/rigid_nodes", m.rigid_nodes);
  const auto& sl = m.sliding;
  w.array("/constraints/sliding_node", column(sl, [](const SlidingBinding& x) { return x.node; }));
  w.array("/constraints/sliding_surface",
          column(sl, [](const SlidingBinding& x) { return x.surface; }));
  w.array("/constraints/sliding_rest_distance",
          column(sl, [](const SlidingBinding& x) { return x.rest_distance; }));
  w.array("/constraints/sliding_rest_triangle",
          column(sl, [](const SlidingBinding& x) { return x.rest_triangle; }));

  const auto& su = m.surfaces;
  w.group("/surfaces");
  w.strings("/surfaces/name", column(su, [](const Surface& x) { return x.name; }));
  w.strings("/surfaces/role",
            column(su, [](const Surface& x) { return std::string(to_string(x.role)); }));
  std::vector<Offset> v_off{0}, t_off{0}, e_off{0};
  std::vector<Point> vertices, local;
  std::vector<std::array<Index, 3>> triangles;
  std::vector<Index> emb_element;
  for (const auto& s : su) {
    vertices.insert(vertices.end(), s.vertices.begin(), s.vertices.end());
    triangles.insert(triangles.end(), s.triangles.begin(), s.triangles.end());
    emb_element.insert(emb_element.end(), s.embedding_element.begin(), s.embedding_element.end());
    local.insert(local.end(), s.embedding_local.begin(), s.embedding_local.end());
    v_off.push_back(static_cast<Offset>(vertices.size()));
    t_off.push_back(static_cast<Offset>(triangles.size()));
    e_off.push_back(static_cast<Offset>(emb_element.size()));
  }
  w.array("/surfaces/vertex_offsets", v_off);
  w.array("/surfaces/vertices", vertices.empty() ? nullptr : vertices.front().data(),
          static_cast<std::int64_t>(vertices.size()), 3);
  w.array("/surfaces/triangle_offsets", t_off);
  w.array("/surfaces/triangles", triangles.empty() ? nullptr : triangles.front().data(),
          static_cast<std::int64_t>(triangles.size()), 3);
  w.array("/surfaces/embedding_offsets", e_off);
  w.array("/surfaces/embedding_element", emb_element);
  w.array("/surfaces/embedding_local", local.empty() ? nullptr : local.front().data(),
          static_cast<std::int64_t>(local.size()), 3);

  w.group("/node_sets", true);
  for (const auto& s : m.node_sets) w.array("/node_sets/" + s.name, s.ids);
  w.group("/element_sets", true);
  for (const auto& s : m.element_sets) w.array("/element_sets/" + s.name, s.ids);

  const auto& p = m.provenance;
  w.group("/provenance");
  w.string("/provenance/tool", p.tool);
  w.string("/provenance/tool_version", p.tool_version);
  w.string("/provenance/created", p.created);
  w.strings("/provenance/input_path", column(p.inputs, [](const InputFile& x) { return x.path; }));
  w.strings("/provenance/input_sha256",
            column(p.inputs, [](const InputFile& x) { return x.sha256; }));
  w.string("/provenance/parameters_json", p.parameters_json);
}

// ------------------------------------------------------------------------------------------------
// Reader

struct Shape {
  int rank = 0;  // 0: scalar
  hsize_t dims[2] = {0, 0};
};

std::string show_shape(const Shape& s) {
  if (s.rank == 0) return "scalar";
  if (s.rank == 1) return fmt::format("({})", s.dims[0]);
  return fmt::format("({}, {})", s.dims[0], s.dims[1]);
}

class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& dataset, const std::string& problem) const {
    throw FormatError(path_, dataset, problem);
  }
  [[noreturn]] void fail(const std::string& dataset, std::int64_t index,
                         const std::string& problem) const {
    throw FormatError(path_, dataset, problem).at(index);
  }

  void open() {
    {
      std::ifstream probe(path_, std::ios::binary);
      if (!probe) throw IoError(path_, "", std::string("cannot open: ") + std::strerror(errno));
    }
    const htri_t is_hdf5 = H5Fis_hdf5(path_.c_str());
    if (is_hdf5 <= 0) {
      H5Eclear2(H5E_DEFAULT);
      fail("", "not an HDF5 file (no HDF5 signature found)");
    }
    file_ = Handle(H5Fopen(path_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!file_.valid()) {
      fail("", "cannot open as HDF5, the file is truncated or corrupt" + hdf5_detail());
    }
  }

  // Checks the root attributes `format` and `format_version`.
  void check_format() {
    const std::string format = read_string_attribute("format");
    if (format != kModelFormatName) {
      fail("/format", fmt::format("format is '{}', expected '{}'", format, kModelFormatName));
    }
    if (H5Aexists(file_.get(), "format_version") <= 0) {
      H5Eclear2(H5E_DEFAULT);
      fail("/format_version", "missing root attribute (not a sinew model file?)");
    }
    Handle a(H5Aopen(file_.get(), "format_version", H5P_DEFAULT), H5Aclose);
    Handle t(H5Aget_type(a.get()), H5Tclose);
    Handle space(H5Aget_space(a.get()), H5Sclose);
    if (!t.valid() || H5Tget_class(t.get()) != H5T_INTEGER ||
        H5Sget_simple_extent_npoints(space.get()) != 1) {
      fail("/format_version", "must be one integer" + hdf5_detail());
    }
    std::int32_t version = 0;
    if (H5Aread(a.get(), H5T_NATIVE_INT32, &version) < 0)
      fail("/format_version", "cannot read" + hdf5_detail());
    if (version != kModelFormatVersion) {
      fail("/format_version",
           fmt::format("unsupported format version {} (this build reads version {})", version,
                       kModelFormatVersion));
    }
  }

  // Opens a dataset, checking that it exists, has the expected type class and element size,
  // and the expected rank and number of columns (cols == 0: 1-D; rank_expected 0: scalar).
  Handle open_dataset(const std::string& path, H5T_class_t cls, std::size_t size, int rank_expected,
                      hsize_t cols, Shape& shape, const char* dtype_name) {
    if (!exists(path)) fail(path, "missing dataset");
    Handle ds(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!ds.valid()) fail(path, "cannot open, not a dataset" + hdf5_detail());
    Handle type(H5Dget_type(ds.get()), H5Tclose);
    const H5T_class_t got = H5Tget_class(type.get());
    bool ok = got == cls;
    if (ok && cls != H5T_STRING) ok = H5Tget_size(type.get()) == size;
    if (ok && cls == H5T_INTEGER) ok = H5Tget_sign(type.get()) == H5T_SGN_2;
    if (!ok) fail(path, fmt::format("wrong dtype, expected {}", dtype_name));
    Handle space(H5Dget_space(ds.get()), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank < 0 || rank > 2) fail(path, fmt::format("wrong shape, rank {}", rank));
    shape.rank = rank;
    H5Sget_simple_extent_dims(space.get(), shape.dims, nullptr);
    const std::string want = rank_expected == 0   ? "scalar"
                             : rank_expected == 1 ? "(n)"
                                                  : fmt::format("(n, {})", cols);
    if (rank != rank_expected || (rank == 2 && shape.dims[1] != cols)) {
      fail(path, fmt::format("wrong shape {}, expected {}", show_shape(shape), want));
    }
    return ds;
  }

  // 1-D array (cols == 0) or rows × cols array, flattened.
  template <typename T>
  std::vector<T> array(const std::string& path, hsize_t cols = 0) {
    Shape shape;
    const H5T_class_t cls = std::is_floating_point_v<T> ? H5T_FLOAT : H5T_INTEGER;
    const char* name = std::is_same_v<T, double> ? "float64" : (sizeof(T) == 8 ? "int64" : "int32");
    Handle ds = open_dataset(path, cls, sizeof(T), cols == 0 ? 1 : 2, cols, shape, name);
    if (shape.dims[0] > static_cast<hsize_t>(std::numeric_limits<Index>::max())) {
      fail(path, fmt::format("{} rows, more than 32-bit ids can address", shape.dims[0]));
    }
    const std::size_t count = static_cast<std::size_t>(shape.dims[0]) * (cols == 0 ? 1 : cols);
    std::vector<T> out;
    try {
      out.resize(count);
    } catch (const std::bad_alloc&) {
      fail(path, fmt::format("cannot allocate memory for {} values", count));
    }
    if (count > 0 &&
        H5Dread(ds.get(), native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) {
      fail(path, "cannot read" + hdf5_detail());
    }
    return out;
  }
  // An array with exactly `n` entries (for the fixed-size grid vectors).
  template <typename T>
  std::vector<T> fixed(const std::string& path, std::size_t n) {
    auto v = array<T>(path);
    if (v.size() != n) fail(path, fmt::format("wrong shape ({}), expected ({})", v.size(), n));
    return v;
  }
  double scalar(const std::string& path) {
    Shape shape;
    Handle ds = open_dataset(path, H5T_FLOAT, sizeof(double), 0, 0, shape, "float64");
    double v = 0;
    if (H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v) < 0) {
      fail(path, "cannot read" + hdf5_detail());
    }
    return v;
  }

  std::vector<std::string> strings(const std::string& path) {
    Shape shape;
    Handle ds = open_dataset(path, H5T_STRING, 0, 1, 0, shape, "string");
    return read_strings(path, ds, static_cast<std::size_t>(shape.dims[0]));
  }
  std::string string(const std::string& path) {
    Shape shape;
    Handle ds = open_dataset(path, H5T_STRING, 0, 0, 0, shape, "string");
    return read_strings(path, ds, 1).front();
  }

  // Names of the datasets in a group, in creation order when the group tracks it (files of this
  // writer), else in name order.
  std::vector<std::string> members(const std::string& group) {
    if (!exists(group)) fail(group, "missing group");
    Handle g(H5Gopen2(file_.get(), group.c_str(), H5P_DEFAULT), H5Gclose);
    if (!g.valid()) fail(group, "cannot open, not a group" + hdf5_detail());
    Handle gcpl(H5Gget_create_plist(g.get()), H5Pclose);
    unsigned flags = 0;
    H5Pget_link_creation_order(gcpl.get(), &flags);
    const H5_index_t index = (flags & H5P_CRT_ORDER_INDEXED) ? H5_INDEX_CRT_ORDER : H5_INDEX_NAME;
    std::vector<std::string> names;
    auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
      static_cast<std::vector<std::string>*>(data)->emplace_back(name);
      return 0;
    };
    if (H5Literate(g.get(), index, H5_ITER_INC, nullptr, cb, &names) < 0) {
      fail(group, "cannot list members" + hdf5_detail());
    }
    return names;
  }

 private:
  bool exists(const std::string& path) {
    // H5Lexists needs every intermediate group to exist, so walk the path.
    std::size_t pos = 0;
    while (pos != std::string::npos) {
      pos = path.find('/', pos + 1);
      const std::string prefix = path.substr(0, pos);
      if (H5Lexists(file_.get(), prefix.c_str(), H5P_DEFAULT) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
      }
    }
    return true;
  }

  std::string read_string_attribute(const char* name) {
    if (H5Aexists(file_.get(), name) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      fail(std::string("/") + name, "missing root attribute (not a sinew model file?)");
    }
    Handle a(H5Aopen(file_.get(), name, H5P_DEFAULT), H5Aclose);
    Handle t(H5Aget_type(a.get()), H5Tclose);
    Handle space(H5Aget_space(a.get()), H5Sclose);
    if (!t.valid() || H5Tget_class(t.get()) != H5T_STRING ||
        H5Sget_simple_extent_npoints(space.get()) != 1) {
      fail(std::string("/") + name, "must be one string");
    }
    if (H5Tis_variable_str(t.get()) > 0) {
      Handle mem = string_type();
      char* value = nullptr;
      if (H5Aread(a.get(), mem.get(), &value) < 0)
        fail(std::string("/") + name, "cannot read" + hdf5_detail());
      std::string out = value ? value : "";
      H5free_memory(value);
      return out;
    }
    const std::size_t size = H5Tget_size(t.get());
    std::vector<char> buf(size + 1, '\0');
    Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), size + 1);
    if (H5Aread(a.get(), mem.get(), buf.data()) < 0)
      fail(std::string("/") + name, "cannot read" + hdf5_detail());
    return std::string(buf.data());
  }

  std::vector<std::string> read_strings(const std::string& path, const Handle& ds, std::size_t n) {
    std::vector<std::string> out;
    out.reserve(n);
    if (n == 0) return out;
    Handle type(H5Dget_type(ds.get()), H5Tclose);
    if (H5Tis_variable_str(type.get()) > 0) {
      Handle mem = string_type();
      std::vector<char*> ptrs(n, nullptr);
      if (H5Dread(ds.get(), mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()) < 0) {
        fail(path, "cannot read" + hdf5_detail());
      }
      for (char* p : ptrs) out.emplace_back(p ? p : "");
      Handle space(H5Dget_space(ds.get()), H5Sclose);
      H5Dvlen_reclaim(mem.get(), space.get(), H5P_DEFAULT, ptrs.data());
      return out;
    }
    // Fixed-length strings (as other tools may write them): NUL- or space-padded.
    const std::size_t size = H5Tget_size(type.get());
    Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), size + 1);
    std::vector<char> buf(n * (size + 1), '\0');
    if (H5Dread(ds.get(), mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0) {
      fail(path, "cannot read" + hdf5_detail());
    }
    for (std::size_t i = 0; i < n; ++i) out.emplace_back(buf.data() + i * (size + 1));
    return out;
  }

  std::string path_;
  Handle file_;
};

// Checks a CSR offsets array over `groups` groups into `total` entries: size groups + 1, starts
// at 0, never decreases, ends at total.
void check_offsets(const Reader& r, const std::string& path, const std::vector<Offset>& off,
                   std::size_t groups, std::size_t total, const std::string& entries) {
  if (off.size() != groups + 1) {
    r.fail(path, fmt::format("wrong shape ({}), expected ({}) (one more than the number of entries "
                             "in the table)",
                             off.size(), groups + 1));
  }
  if (off[0] != 0) r.fail(path, 0, fmt::format("first offset must be 0, got {}", off[0]));
  for (std::size_t i = 1; i < off.size(); ++i) {
    if (off[i] < off[i - 1]) {
      r.fail(path, static_cast<std::int64_t>(i),
             fmt::format("offsets decrease: {} after {}", off[i], off[i - 1]));
    }
  }
  if (off.back() != static_cast<Offset>(total)) {
    r.fail(
        path, static_cast<std::int64_t>(groups),
        fmt::format("last offset {} differs from the {} rows of {}", off.back(), total, entries));
  }
}

template <typename T>
void expect_rows(const Reader& r, const std::string& path, const std::vector<T>& v,
                 std::size_t rows, const std::string& why) {
  if (v.size() != rows)
    r.fail(path, fmt::format("wrong shape ({}), expected ({}) ({})", v.size(), rows, why));
}

template <std::size_t C, typename T>
std::vector<std::array<T, C>> rows_of(const std::vector<T>& flat) {
  std::vector<std::array<T, C>> out(flat.size() / C);
  for (std::size_t i = 0; i < out.size(); ++i)
    for (std::size_t c = 0; c < C; ++c) out[i][c] = flat[i * C + c];
  return out;
}

Model read_all(Reader& r) {
  Model m;
  {
    const auto origin = r.fixed<double>("/grid/origin", 3);
    m.grid.origin = {origin[0], origin[1], origin[2]};
    m.grid.voxel_size = r.scalar("/grid/voxel_size");
    const auto dims = r.fixed<std::int32_t>("/grid/dims", 3);
    m.grid.dims = {dims[0], dims[1], dims[2]};
  }
  m.node_lattice = rows_of<3>(r.array<std::int32_t>("/nodes/lattice", 3));
  m.element_lattice = rows_of<3>(r.array<std::int32_t>("/elements/lattice", 3));
  m.element_nodes = rows_of<8>(r.array<std::int32_t>("/elements/nodes", 8));
  const std::size_t e_count = m.element_lattice.size();
  expect_rows(r, "/elements/nodes", m.element_nodes, e_count,
              "one row per element of /elements/lattice");

  {
    const auto names = r.strings("/materials/name");
    const std::size_t n = names.size();
    const auto laws = r.strings("/materials/law");
    const auto e = r.array<double>("/materials/youngs_modulus");
    const auto nu = r.array<double>("/materials/poisson_ratio");
    const auto mu = r.array<double>("/materials/shear_modulus");
    const auto kappa = r.array<double>("/materials/bulk_modulus");
    const auto rho = r.array<double>("/materials/density");
    const std::string why = "one per material of /materials/name";
    expect_rows(r, "/materials/law", laws, n, why);
    expect_rows(r, "/materials/youngs_modulus", e, n, why);
    expect_rows(r, "/materials/poisson_ratio", nu, n, why);
    expect_rows(r, "/materials/shear_modulus", mu, n, why);
    expect_rows(r, "/materials/bulk_modulus", kappa, n, why);
    expect_rows(r, "/materials/density", rho, n, why);
    for (std::size_t i = 0; i < n; ++i) {
      Material mat;
      mat.name = names[i];
      try {
        mat.law = material_law_from_string(laws[i]);
      } catch (const std::invalid_argument& ex) {
        r.fail("/materials/law", static_cast<std::int64_t>(i), ex.what());
      }
      mat.youngs_modulus = e[i];
      mat.poisson_ratio = nu[i];
      mat.shear_modulus = mu[i];
      mat.bulk_modulus = kappa[i];
      mat.density = rho[i];
      m.materials.push_back(mat);
    }
  }

  m.material_offsets = r.array<std::int64_t>("/element_materials/offsets");
  m.material_ids = r.array<std::int32_t>("/element_materials/material");
  m.material_fractions = r.array<double>("/element_materials/fraction");
  check_offsets(r, "/element_materials/offsets", m.material_offsets, e_count, m.material_ids.size(),
                "/element_materials/material");
  expect_rows(r, "/element_materials/fraction", m.material_fractions, m.material_ids.size(),
              "one per row of /element_materials/material");

  {
    const auto names = r.strings("/muscles/name");
    const std::size_t n = names.size();
    const auto material = r.array<std::int32_t>("/muscles/material");
    const auto sref = r.array<double>("/muscles/reference_stress");
    const auto lopt = r.array<double>("/muscles/optimal_stretch");
    const auto curve = r.strings("/muscles/force_length");
    const auto p1 = r.array<double>("/muscles/passive_p1");
    const auto p2 = r.array<double>("/muscles/passive_p2");
    const auto xstar = r.array<double>("/muscles/passive_linear_stretch");
    const std::string why = "one per muscle of /muscles/name";
    expect_rows(r, "/muscles/material", material, n, why);
    expect_rows(r, "/muscles/reference_stress", sref, n, why);
    expect_rows(r, "/muscles/optimal_stretch", lopt, n, why);
    expect_rows(r, "/muscles/force_length", curve, n, why);
    expect_rows(r, "/muscles/passive_p1", p1, n, why);
    expect_rows(r, "/muscles/passive_p2", p2, n, why);
    expect_rows(r, "/muscles/passive_linear_stretch", xstar, n, why);
    const auto off = r.array<std::int64_t>("/muscles/offsets");
    const auto elements = r.array<std::int32_t>("/muscles/elements");
    const auto fractions = r.array<double>("/muscles/fractions");
    const auto fibres = rows_of<3>(r.array<double>("/muscles/fibres", 3));
    check_offsets(r, "/muscles/offsets", off, n, elements.size(), "/muscles/elements");
    expect_rows(r, "/muscles/fractions", fractions, elements.size(),
                "one per row of /muscles/elements");
    expect_rows(r, "/muscles/fibres", fibres, elements.size(), "one per row of /muscles/elements");
    for (std::size_t i = 0; i < n; ++i) {
      Muscle mu;
      mu.name = names[i];
      mu.material = material[i];
      mu.reference_stress = sref[i];
      mu.optimal_stretch = lopt[i];
      try {
        mu.force_length = force_length_curve_from_string(curve[i]);
      } catch (const std::invalid_argument& ex) {
        r.fail("/muscles/force_length", static_cast<std::int64_t>(i), ex.what());
      }
      mu.passive_p1 = p1[i];
      mu.passive_p2 = p2[i];
      mu.passive_linear_stretch = xstar[i];
      const auto b = static_cast<std::size_t>(off[i]), en = static_cast<std::size_t>(off[i + 1]);
      mu.elements.assign(elements.begin() + static_cast<std::ptrdiff_t>(b),
                         elements.begin() + static_cast<std::ptrdiff_t>(en));
      mu.fractions.assign(fractions.begin() + static_cast<std::ptrdiff_t>(b),
                          fractions.begin() + static_cast<std::ptrdiff_t>(en));
      mu.fibres.assign(fibres.begin() + static_cast<std::ptrdiff_t>(b),
                       fibres.begin() + static_cast<std::ptrdiff_t>(en));
      m.muscles.push_back(std::move(mu));
    }
  }

  {
    m.rigid_nodes = r.array<std::int32_t>("/constraints/rigid_nodes");
    const auto node = r.array<std::int32_t>("/constraints/sliding_node");
    const auto surface = r.array<std::int32_t>("/constraints/sliding_surface");
    const auto distance = r.array<double>("/constraints/sliding_rest_distance");
    const auto triangle = r.array<std::int32_t>("/constraints/sliding_rest_triangle");
    const std::string why = "one per row of /constraints/sliding_node";
    expect_rows(r, "/constraints/sliding_surface", surface, node.size(), why);
    expect_rows(r, "/constraints/sliding_rest_distance", distance, node.size(), why);
    expect_rows(r, "/constraints/sliding_rest_triangle", triangle, node.size(), why);
    for (std::size_t i = 0; i < node.size(); ++i) {
      m.sliding.push_back({node[i], surface[i], distance[i], triangle[i]});
    }
  }

  {
    const auto names = r.strings("/surfaces/name");
    const std::size_t n = names.size();
    const auto roles = r.strings("/surfaces/role");
    expect_rows(r, "/surfaces/role", roles, n, "one per surface of /surfaces/name");
    const auto v_off = r.array<std::int64_t>("/surfaces/vertex_offsets");
    const auto vertices = rows_of<3>(r.array<double>("/surfaces/vertices", 3));
    const auto t_off = r.array<std::int64_t>("/surfaces/triangle_offsets");
    const auto triangles = rows_of<3>(r.array<std::int32_t>("/surfaces/triangles", 3));
    const auto e_off = r.array<std::int64_t>("/surfaces/embedding_offsets");
    const auto emb_element = r.array<std::int32_t>("/surfaces/embedding_element");
    const auto emb_local = rows_of<3>(r.array<double>("/surfaces/embedding_local", 3));
    check_offsets(r, "/surfaces/vertex_offsets", v_off, n, vertices.size(), "/surfaces/vertices");
    check_offsets(r, "/surfaces/triangle_offsets", t_off, n, triangles.size(),
                  "/surfaces/triangles");
    check_offsets(r, "/surfaces/embedding_offsets", e_off, n, emb_element.size(),
                  "/surfaces/embedding_element");
    expect_rows(r, "/surfaces/embedding_local", emb_local, emb_element.size(),
                "one per row of /surfaces/embedding_element");
    auto slice = [](const auto& v, const std::vector<Offset>& off, std::size_t i) {
      using V = std::decay_t<decltype(v)>;
      return V(v.begin() + static_cast<std::ptrdiff_t>(off[i]),
               v.begin() + static_cast<std::ptrdiff_t>(off[i + 1]));
    };
    for (std::size_t i = 0; i < n; ++i) {
      Surface s;
      s.name = names[i];
      try {
        s.role = surface_role_from_string(roles[i]);
      } catch (const std::invalid_argument& ex) {
        r.fail("/surfaces/role", static_cast<std::int64_t>(i), ex.what());
      }
      s.vertices = slice(vertices, v_off, i);
      s.triangles = slice(triangles, t_off, i);
      s.embedding_element = slice(emb_element, e_off, i);
      s.embedding_local = slice(emb_local, e_off, i);
      m.surfaces.push_back(std::move(s));
    }
  }

  for (const auto& name : r.members("/node_sets")) {
    m.node_sets.push_back({name, r.array<std::int32_t>("/node_sets/" + name)});
  }
  for (const auto& name : r.members("/element_sets")) {
    m.element_sets.push_back({name, r.array<std::int32_t>("/element_sets/" + name)});
  }

  {
    auto& p = m.provenance;
    p.tool = r.string("/provenance/tool");
    p.tool_version = r.string("/provenance/tool_version");
    p.created = r.string("/provenance/created");
    const auto paths = r.strings("/provenance/input_path");
    const auto digests = r.strings("/provenance/input_sha256");
    expect_rows(r, "/provenance/input_sha256", digests, paths.size(),
                "one per row of /provenance/input_path");
    for (std::size_t i = 0; i < paths.size(); ++i) p.inputs.push_back({paths[i], digests[i]});
    p.parameters_json = r.string("/provenance/parameters_json");
  }
  return m;
}

}  // namespace

void write_model(const Model& model, const std::string& path) {
  validate_model(model, path);
  silence_hdf5();
  const std::string tmp = path + ".tmp-" + std::to_string(static_cast<long>(getpid()));
  try {
    Writer w(tmp, path);
    write_all(w, model);
    w.close();
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw IoError(
        path, "",
        std::string("cannot rename the temporary file into place: ") + std::strerror(err));
  }
}

Model read_model(const std::string& path) {
  silence_hdf5();
  Reader r(path);
  r.open();
  r.check_format();
  Model m = read_all(r);
  validate_model(m, path);
  return m;
}

std::string current_utc_iso8601() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buf;
}

}  // namespace sinew::formats
