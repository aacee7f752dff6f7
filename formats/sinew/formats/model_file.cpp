#include "sinew/formats/model_file.hpp"

#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/file_kind.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/validate.hpp"

namespace sinew::formats {

static_assert(sizeof(Lattice) == 3 * sizeof(std::int32_t), "Lattice must be three packed int32");
static_assert(sizeof(Point) == 3 * sizeof(double), "Point must be three packed doubles");
static_assert(sizeof(std::array<Index, 8>) == 8 * sizeof(Index), "hex8 node rows must be packed");
static_assert(sizeof(std::array<Index, 3>) == 3 * sizeof(Index), "triangles must be packed");
static_assert(sizeof(TexCoord) == 2 * sizeof(double), "texture coordinates must be packed");

namespace {

// ------------------------------------------------------------------------------------------------
// Writer: the model's datasets, dataset by dataset, through the HDF5 layer (hdf5_file.hpp). Errors
// name `display` (the final path), not the temporary file written.

class Writer {
 public:
  Writer(const std::string& path, const std::string& display)
      : display_(display), file_(hdf5::create_file(path, display)) {}

  void close() { hdf5::close_file(file_, display_); }

  // ordered: keep the links in creation order (named sets keep the order of the model).
  void group(const std::string& path, bool ordered = false) {
    hdf5::create_group(file_, path, display_, ordered);
  }

  // rows × cols array (cols == 0: a 1-D array of `rows`; rows < 0: a scalar).
  template <typename T>
  void array(const std::string& path, const T* data, std::int64_t rows, int cols = 0) {
    std::vector<hsize_t> dims;
    if (rows >= 0) dims.push_back(static_cast<hsize_t>(rows));
    if (rows >= 0 && cols > 0) dims.push_back(static_cast<hsize_t>(cols));
    hdf5::write(file_, path, dims, data, display_);
  }
  template <typename T>
  void array(const std::string& path, const std::vector<T>& v) {
    array(path, v.data(), static_cast<std::int64_t>(v.size()));
  }
  void scalar(const std::string& path, double v) { array(path, &v, -1); }

  void strings(const std::string& path, const std::vector<std::string>& values) {
    hdf5::write_strings(file_, path, values, display_);
  }
  void string(const std::string& path, const std::string& value) {
    hdf5::write_string(file_, path, value, display_);
  }

  void root_attributes() {
    hdf5::set_attribute(file_, "format", kModelFormatName, display_, hdf5::StringKind::variable);
    hdf5::set_attribute(file_, "format_version", std::int32_t{kModelFormatVersion}, display_);
  }

 private:
  std::string display_;
  hdf5::Handle file_;
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

  // The jaw (version 3): present only when the model has one.
  if (m.jaw) {
    const Jaw& j = *m.jaw;
    w.group("/jaw");
    w.array("/jaw/nodes", j.nodes);
    w.array("/jaw/pivot", std::vector<double>(j.pivot.begin(), j.pivot.end()));
    w.array("/jaw/axis", std::vector<double>(j.axis.begin(), j.axis.end()));
    w.array("/jaw/forward", std::vector<double>(j.forward.begin(), j.forward.end()));
    w.array("/jaw/incisal", std::vector<double>(j.incisal.begin(), j.incisal.end()));
    if (!j.lip_pairs.empty())
      w.array("/jaw/lip_pairs", j.lip_pairs.front().data(),
              static_cast<std::int64_t>(j.lip_pairs.size()), 2);
  }

  const auto& su = m.surfaces;
  w.group("/surfaces");
  w.strings("/surfaces/name", column(su, [](const Surface& x) { return x.name; }));
  w.strings("/surfaces/role",
            column(su, [](const Surface& x) { return std::string(to_string(x.role)); }));
  std::vector<Offset> v_off{0}, t_off{0}, e_off{0}, uv_off{0}, uvt_off{0};
  std::vector<Point> vertices, local;
  std::vector<std::array<Index, 3>> triangles, uv_triangles;
  std::vector<Index> emb_element;
  std::vector<TexCoord> uvs;
  for (const auto& s : su) {
    vertices.insert(vertices.end(), s.vertices.begin(), s.vertices.end());
    triangles.insert(triangles.end(), s.triangles.begin(), s.triangles.end());
    emb_element.insert(emb_element.end(), s.embedding_element.begin(), s.embedding_element.end());
    local.insert(local.end(), s.embedding_local.begin(), s.embedding_local.end());
    uvs.insert(uvs.end(), s.uvs.begin(), s.uvs.end());
    uv_triangles.insert(uv_triangles.end(), s.uv_triangles.begin(), s.uv_triangles.end());
    v_off.push_back(static_cast<Offset>(vertices.size()));
    t_off.push_back(static_cast<Offset>(triangles.size()));
    e_off.push_back(static_cast<Offset>(emb_element.size()));
    uv_off.push_back(static_cast<Offset>(uvs.size()));
    uvt_off.push_back(static_cast<Offset>(uv_triangles.size()));
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
  w.array("/surfaces/uv_offsets", uv_off);
  w.array("/surfaces/uvs", uvs.empty() ? nullptr : uvs.front().data(),
          static_cast<std::int64_t>(uvs.size()), 2);
  w.array("/surfaces/uv_triangle_offsets", uvt_off);
  w.array("/surfaces/uv_triangles", uv_triangles.empty() ? nullptr : uv_triangles.front().data(),
          static_cast<std::int64_t>(uv_triangles.size()), 3);

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

// The model file's reads, each a strict read of the HDF5 layer (exact dtype and shape); fail()
// raises the FormatError of the checks below, naming the file.
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

  void open() { file_ = hdf5::open_checked(path_); }

  // Checks the root attributes `format` and `format_version`; returns the version (one of
  // kModelFormatOldestVersion ... kModelFormatVersion).
  int check_format() {
    const auto require = [&](const char* name) {
      if (!hdf5::has_attribute(file_, name)) {
        fail(std::string("/") + name, "missing root attribute (not a sinew model file?)");
      }
    };
    if (hdf5::has_attribute(file_, "format") && !has_format(file_, path_, kModelFormatName)) {
      throw wrong_kind(file_, path_, "a sinew model file",
                       "give a model written by sinew-voxelize or sinew-generate");
    }
    require("format");
    const std::string format = hdf5::string_attribute(file_, "format", path_);
    if (format != kModelFormatName) {
      fail("/format", fmt::format("format is '{}', expected '{}'", format, kModelFormatName));
    }
    require("format_version");
    const std::int64_t version = hdf5::int_attribute(file_, "format_version", path_);
    if (version < kModelFormatOldestVersion || version > kModelFormatVersion) {
      fail("/format_version",
           fmt::format("unsupported format version {} (this build reads versions {} to {})",
                       version, kModelFormatOldestVersion, kModelFormatVersion));
    }
    return static_cast<int>(version);
  }

  // 1-D array (cols == 0) or rows × cols array, flattened.
  template <typename T>
  std::vector<T> array(const std::string& path, hsize_t cols = 0) {
    return hdf5::read_array<T>(file_, path, path_, cols);
  }
  // An array with exactly `n` entries (for the fixed-size grid vectors).
  template <typename T>
  std::vector<T> fixed(const std::string& path, std::size_t n) {
    auto v = array<T>(path);
    if (v.size() != n) fail(path, fmt::format("wrong shape ({}), expected ({})", v.size(), n));
    return v;
  }
  double scalar(const std::string& path) { return hdf5::read_scalar<double>(file_, path, path_); }
  std::vector<std::string> strings(const std::string& path) {
    return hdf5::read_strings(file_, path, path_);
  }
  std::string string(const std::string& path) { return hdf5::read_string(file_, path, path_); }
  bool has(const std::string& path) const { return hdf5::exists(file_, path); }
  // Names of the datasets in a group, in creation order when the group tracks it (files of this
  // writer), else in name order.
  std::vector<std::string> members(const std::string& group) {
    return hdf5::members(file_, group, path_);
  }

 private:
  std::string path_;
  hdf5::Handle file_;
};

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

Model read_all(Reader& r, int version) {
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
      } catch (const FormatError& ex) {
        r.fail("/materials/law", static_cast<std::int64_t>(i), ex.problem());
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
      } catch (const FormatError& ex) {
        r.fail("/muscles/force_length", static_cast<std::int64_t>(i), ex.problem());
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

  // The jaw: since version 3, and only in models that have one.
  if (version >= 3 && r.has("/jaw")) {
    Jaw j;
    j.nodes = r.array<std::int32_t>("/jaw/nodes");
    const auto point = [&](const char* path) {
      const auto v = r.fixed<double>(path, 3);
      return Point{v[0], v[1], v[2]};
    };
    j.pivot = point("/jaw/pivot");
    j.axis = point("/jaw/axis");
    j.forward = point("/jaw/forward");
    j.incisal = point("/jaw/incisal");
    if (r.has("/jaw/lip_pairs"))
      j.lip_pairs = rows_of<2>(r.array<std::int32_t>("/jaw/lip_pairs", 2));
    m.jaw = std::move(j);
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
      } catch (const FormatError& ex) {
        r.fail("/surfaces/role", static_cast<std::int64_t>(i), ex.problem());
      }
      s.vertices = slice(vertices, v_off, i);
      s.triangles = slice(triangles, t_off, i);
      s.embedding_element = slice(emb_element, e_off, i);
      s.embedding_local = slice(emb_local, e_off, i);
      m.surfaces.push_back(std::move(s));
    }
    // Texture coordinates: since version 2 (a version 1 surface has none).
    if (version >= 2) {
      const auto uv_off = r.array<std::int64_t>("/surfaces/uv_offsets");
      const auto uvs = rows_of<2>(r.array<double>("/surfaces/uvs", 2));
      const auto uvt_off = r.array<std::int64_t>("/surfaces/uv_triangle_offsets");
      const auto uv_triangles = rows_of<3>(r.array<std::int32_t>("/surfaces/uv_triangles", 3));
      check_offsets(r, "/surfaces/uv_offsets", uv_off, n, uvs.size(), "/surfaces/uvs");
      check_offsets(r, "/surfaces/uv_triangle_offsets", uvt_off, n, uv_triangles.size(),
                    "/surfaces/uv_triangles");
      for (std::size_t i = 0; i < n; ++i) {
        m.surfaces[i].uvs = slice(uvs, uv_off, i);
        m.surfaces[i].uv_triangles = slice(uv_triangles, uvt_off, i);
      }
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
  write_atomically(path, [&](const std::string& tmp) {
    Writer w(tmp, path);
    write_all(w, model);
    w.close();
  });
}

Model read_model(const std::string& path) {
  Reader r(path);
  r.open();
  const int version = r.check_format();
  Model m = read_all(r, version);
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
