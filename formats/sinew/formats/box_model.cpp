#include "sinew/formats/box_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/common/error.hpp"
#include "sinew/common/version.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/validate.hpp"

namespace sinew::formats {

namespace {

[[noreturn]] void bad(const std::string& field, const std::string& problem) {
  throw ConfigError("", field, problem);
}

nlohmann::ordered_json spec_json(const BoxSpec& s) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["generator"] = "box";
  j["dims"] = {s.dims[0], s.dims[1], s.dims[2]};
  j["voxel_size"] = s.voxel_size;
  j["origin"] = {s.origin[0], s.origin[1], s.origin[2]};
  ordered_json mats = ordered_json::array();
  for (const auto& m : s.materials) {
    mats.push_back({{"name", m.name},
                    {"law", to_string(m.law)},
                    {"youngs_modulus", m.youngs_modulus},
                    {"poisson_ratio", m.poisson_ratio},
                    {"density", m.density}});
  }
  j["materials"] = mats;
  j["layer_boundaries"] = s.layer_boundaries;
  ordered_json muscles = ordered_json::array();
  for (const auto& m : s.muscles) {
    muscles.push_back({{"name", m.name},
                       {"material", m.material},
                       {"element_min", m.element_min},
                       {"element_max", m.element_max},
                       {"fibre", m.fibre},
                       {"fraction", m.fraction},
                       {"reference_stress", m.reference_stress},
                       {"optimal_stretch", m.optimal_stretch},
                       {"passive_p1", m.passive_p1},
                       {"passive_p2", m.passive_p2},
                       {"passive_linear_stretch", m.passive_linear_stretch}});
  }
  j["muscles"] = muscles;
  j["rigid_faces"] = s.rigid_faces;
  return j;
}

}  // namespace

Material make_neo_hookean_material_from_shear(std::string name, double shear_modulus,
                                              double poisson_ratio, double density) {
  Material m;
  m.name = std::move(name);
  m.youngs_modulus = 2 * shear_modulus * (1 + poisson_ratio);
  m.poisson_ratio = poisson_ratio;
  m.shear_modulus = shear_modulus;  // as given, not through E
  m.bulk_modulus = shear_and_bulk_modulus(m.youngs_modulus, poisson_ratio).bulk_modulus;
  m.density = density;
  return m;
}

Model make_box_model(const BoxSpec& spec) {
  const auto& d = spec.dims;
  for (std::size_t a = 0; a < 3; ++a) {
    if (d[a] < 1) bad("dims", fmt::format("every dimension must be at least 1, got {}", d[a]));
  }
  const std::int64_t nx = d[0], ny = d[1], nz = d[2];
  if ((nx + 1) * (ny + 1) * (nz + 1) > std::numeric_limits<Index>::max()) {
    bad("dims", "too many nodes for 32-bit ids");
  }
  const double h = spec.voxel_size;
  if (!std::isfinite(h) || !(h > 0)) bad("voxel_size", fmt::format("must be positive, got {}", h));
  if (spec.materials.empty()) bad("materials", "at least one material is needed");
  if (spec.layer_boundaries.size() + 1 != spec.materials.size()) {
    bad("layer_boundaries",
        fmt::format("{} materials need {} layer boundaries, got {}", spec.materials.size(),
                    spec.materials.size() - 1, spec.layer_boundaries.size()));
  }
  // Boundaries in voxel units, snapped onto voxel faces when within 1e-9 voxel (round-off of b /
  // h).
  std::vector<double> bounds{0.0};
  for (std::size_t i = 0; i < spec.layer_boundaries.size(); ++i) {
    double b = spec.layer_boundaries[i] / h;
    if (std::abs(b - std::round(b)) < 1e-9) b = std::round(b);
    if (!std::isfinite(b) || !(b > bounds.back()) || !(b < static_cast<double>(nz))) {
      bad("layer_boundaries",
          fmt::format("boundary {} ({} m) must increase strictly inside (0, {} m)", i,
                      spec.layer_boundaries[i], static_cast<double>(nz) * h));
    }
    bounds.push_back(b);
  }
  bounds.push_back(static_cast<double>(nz));

  Model m;
  m.grid.origin = spec.origin;
  m.grid.voxel_size = h;
  m.grid.dims = d;
  m.materials = spec.materials;

  const auto node_id = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return static_cast<Index>(i + (nx + 1) * (j + (ny + 1) * k));
  };
  m.node_lattice.reserve(static_cast<std::size_t>((nx + 1) * (ny + 1) * (nz + 1)));
  for (std::int32_t k = 0; k <= d[2]; ++k)
    for (std::int32_t j = 0; j <= d[1]; ++j)
      for (std::int32_t i = 0; i <= d[0]; ++i) m.node_lattice.push_back({i, j, k});

  const auto e_count = static_cast<std::size_t>(nx * ny * nz);
  m.element_lattice.reserve(e_count);
  m.element_nodes.reserve(e_count);
  m.material_offsets.reserve(e_count + 1);
  m.material_offsets.push_back(0);
  const std::size_t layers = spec.materials.size();
  std::vector<std::vector<Index>> layer_elements(layers);
  for (std::int32_t k = 0; k < d[2]; ++k) {
    // This voxel row's share of each layer; the same for every (i, j).
    std::vector<std::pair<Index, double>> shares;
    for (std::size_t l = 0; l < layers; ++l) {
      const double overlap =
          std::min<double>(bounds[l + 1], k + 1) - std::max<double>(bounds[l], k);
      if (overlap > 0) shares.emplace_back(static_cast<Index>(l), overlap);
    }
    for (std::int32_t j = 0; j < d[1]; ++j) {
      for (std::int32_t i = 0; i < d[0]; ++i) {
        const auto e = static_cast<Index>(m.element_lattice.size());
        m.element_lattice.push_back({i, j, k});
        std::array<Index, 8> nodes{};
        for (std::size_t a = 0; a < 8; ++a) {
          nodes[a] = node_id(i + kHexCorner[a][0], j + kHexCorner[a][1], k + kHexCorner[a][2]);
        }
        m.element_nodes.push_back(nodes);
        for (const auto& [mat, f] : shares) {
          m.material_ids.push_back(mat);
          m.material_fractions.push_back(f);
          layer_elements[static_cast<std::size_t>(mat)].push_back(e);
        }
        m.material_offsets.push_back(static_cast<Offset>(m.material_ids.size()));
      }
    }
  }

  for (std::size_t mi = 0; mi < spec.muscles.size(); ++mi) {
    const auto& ms = spec.muscles[mi];
    const std::string field = fmt::format("muscles[{}]", mi);
    for (std::size_t a = 0; a < 3; ++a) {
      if (ms.element_min[a] < 0 || ms.element_min[a] >= ms.element_max[a] ||
          ms.element_max[a] > d[a]) {
        bad(field,
            fmt::format(
                "muscle '{}': element box [{}, {}) along axis {} is empty or outside [0, {})",
                ms.name, ms.element_min[a], ms.element_max[a], a, d[a]));
      }
    }
    const double len = std::sqrt(ms.fibre[0] * ms.fibre[0] + ms.fibre[1] * ms.fibre[1] +
                                 ms.fibre[2] * ms.fibre[2]);
    if (!std::isfinite(len) || !(len > 0))
      bad(field, "muscle '" + ms.name + "': fibre direction is zero");
    const Point fibre{ms.fibre[0] / len, ms.fibre[1] / len, ms.fibre[2] / len};
    Muscle mu;
    mu.name = ms.name;
    mu.material = ms.material;
    mu.reference_stress = ms.reference_stress;
    mu.optimal_stretch = ms.optimal_stretch;
    mu.passive_p1 = ms.passive_p1;
    mu.passive_p2 = ms.passive_p2;
    mu.passive_linear_stretch = ms.passive_linear_stretch;
    for (std::int32_t k = ms.element_min[2]; k < ms.element_max[2]; ++k)
      for (std::int32_t j = ms.element_min[1]; j < ms.element_max[1]; ++j)
        for (std::int32_t i = ms.element_min[0]; i < ms.element_max[0]; ++i) {
          mu.elements.push_back(static_cast<Index>(i + nx * (j + ny * k)));
          mu.fractions.push_back(ms.fraction);
          mu.fibres.push_back(fibre);
        }
    m.muscles.push_back(std::move(mu));
  }

  // Face node sets, in the order of kBoxFaces.
  for (std::size_t f = 0; f < 6; ++f) {
    const std::size_t axis = f / 2;
    const std::int32_t value = (f % 2 == 0) ? 0 : d[axis];
    NamedSet set{kBoxFaces[f], {}};
    for (std::size_t n = 0; n < m.node_lattice.size(); ++n) {
      if (m.node_lattice[n][axis] == value) set.ids.push_back(static_cast<Index>(n));
    }
    m.node_sets.push_back(std::move(set));
  }
  for (const auto& face : spec.rigid_faces) {
    const auto it = std::find_if(kBoxFaces.begin(), kBoxFaces.end(),
                                 [&](const char* name) { return face == name; });
    if (it == kBoxFaces.end()) {
      bad("rigid_faces", "unknown face '" + face + "' (x_min, x_max, y_min, y_max, z_min, z_max)");
    }
    const auto& ids = m.node_sets[static_cast<std::size_t>(it - kBoxFaces.begin())].ids;
    m.rigid_nodes.insert(m.rigid_nodes.end(), ids.begin(), ids.end());
  }
  std::sort(m.rigid_nodes.begin(), m.rigid_nodes.end());
  m.rigid_nodes.erase(std::unique(m.rigid_nodes.begin(), m.rigid_nodes.end()), m.rigid_nodes.end());

  NamedSet all{"all", {}};
  all.ids.resize(e_count);
  for (std::size_t e = 0; e < e_count; ++e) all.ids[e] = static_cast<Index>(e);
  m.element_sets.push_back(std::move(all));
  for (std::size_t l = 0; l < layers; ++l) {
    m.element_sets.push_back({"material_" + spec.materials[l].name, layer_elements[l]});
  }
  for (const auto& mu : m.muscles) m.element_sets.push_back({"muscle_" + mu.name, mu.elements});
  for (const auto& set : m.element_sets) {
    if (!is_valid_set_name(set.name)) {
      bad("materials",
          "element set name '" + set.name + "' is not valid (a name with '/' or non-ASCII?)");
    }
  }

  m.provenance.tool = "sinew::formats::make_box_model";
  m.provenance.tool_version = kVersion;
  m.provenance.created = spec.created.empty() ? current_utc_iso8601() : spec.created;
  m.provenance.parameters_json = spec_json(spec).dump();

  // Materials, muscles, names: the one validator decides (as a ConfigError: the spec is at fault).
  try {
    validate_model(m, "");
  } catch (const FormatError& e) {
    ConfigError error("", e.field(), e.problem());
    if (e.index()) error.at(*e.index());
    throw error;
  }
  return m;
}

}  // namespace sinew::formats
