#include "sinew/formats/model.hpp"

#include <algorithm>
#include <initializer_list>
#include <string>
#include <utility>

#include "sinew/common/error.hpp"

namespace sinew::formats {

namespace {

// The string names of an enumeration, in the order the "known:" list of errors shows them.
template <typename Enum>
using NameTable = std::initializer_list<std::pair<Enum, const char*>>;

const NameTable<MaterialLaw> kLawNames = {{MaterialLaw::neo_hookean_tled, "neo_hookean_tled"}};
const NameTable<ForceLengthCurve> kCurveNames = {{ForceLengthCurve::blemker2005, "blemker2005"}};
const NameTable<SurfaceRole> kRoleNames = {{SurfaceRole::sliding, "sliding"},
                                           {SurfaceRole::visual, "visual"}};

template <typename Enum>
const char* name_of(const NameTable<Enum>& names, Enum value) {
  for (const auto& [v, name] : names)
    if (v == value) return name;
  return "?";
}

// FormatError without file or field: the names come from a model file or a spec, and the caller
// (model_file.cpp, the voxelizer) knows which and adds them.
template <typename Enum>
Enum parse_name(const NameTable<Enum>& names, const std::string& name, const char* what) {
  std::string known;
  for (const auto& [v, n] : names) {
    if (name == n) return v;
    known.append(known.empty() ? "" : ", ").append(n);
  }
  throw FormatError("", "",
                    std::string("unknown ") + what + " '" + name + "' (known: " + known + ")");
}

}  // namespace

const char* to_string(MaterialLaw law) {
  return name_of(kLawNames, law);
}
MaterialLaw material_law_from_string(const std::string& name) {
  return parse_name(kLawNames, name, "constitutive law");
}

ShearAndBulkModulus shear_and_bulk_modulus(double youngs_modulus, double poisson_ratio) {
  return {youngs_modulus / (2.0 * (1.0 + poisson_ratio)),
          youngs_modulus / (3.0 * (1.0 - 2.0 * poisson_ratio))};
}

Material make_neo_hookean_material(std::string name, double youngs_modulus, double poisson_ratio,
                                   double density) {
  Material m;
  m.name = std::move(name);
  m.law = MaterialLaw::neo_hookean_tled;
  m.youngs_modulus = youngs_modulus;
  m.poisson_ratio = poisson_ratio;
  const auto moduli = shear_and_bulk_modulus(youngs_modulus, poisson_ratio);
  m.shear_modulus = moduli.shear_modulus;
  m.bulk_modulus = moduli.bulk_modulus;
  m.density = density;
  return m;
}

const char* to_string(ForceLengthCurve curve) {
  return name_of(kCurveNames, curve);
}
ForceLengthCurve force_length_curve_from_string(const std::string& name) {
  return parse_name(kCurveNames, name, "force-length curve");
}

const char* to_string(SurfaceRole role) {
  return name_of(kRoleNames, role);
}
SurfaceRole surface_role_from_string(const std::string& name) {
  return parse_name(kRoleNames, name, "surface role");
}

bool lattice_less(const Lattice& a, const Lattice& b) {
  if (a[2] != b[2]) return a[2] < b[2];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[0] < b[0];
}

void build_lattice_topology(Model& model) {
  const auto& elements = model.element_lattice;
  for (std::size_t e = 1; e < elements.size(); ++e) {
    if (!lattice_less(elements[e - 1], elements[e])) {
      throw FormatError(
          "", "",
          "element lattice is not sorted (k, j, i) and unique at element " + std::to_string(e));
    }
  }
  std::vector<Lattice> nodes;
  nodes.reserve(elements.size() * 8);
  for (const auto& base : elements) {
    for (const auto& d : kHexCorner) {
      nodes.push_back({base[0] + d[0], base[1] + d[1], base[2] + d[2]});
    }
  }
  std::sort(nodes.begin(), nodes.end(), lattice_less);
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  model.element_nodes.resize(elements.size());
  for (std::size_t e = 0; e < elements.size(); ++e) {
    for (int a = 0; a < 8; ++a) {
      const auto& d = kHexCorner[static_cast<std::size_t>(a)];
      const Lattice p{elements[e][0] + d[0], elements[e][1] + d[1], elements[e][2] + d[2]};
      const auto it = std::lower_bound(nodes.begin(), nodes.end(), p, lattice_less);
      model.element_nodes[e][static_cast<std::size_t>(a)] = static_cast<Index>(it - nodes.begin());
    }
  }
  model.node_lattice = std::move(nodes);
}

}  // namespace sinew::formats
