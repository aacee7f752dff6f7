#include "sinew/formats/model.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace sinew::formats {

const char* to_string(MaterialLaw law) {
  switch (law) {
    case MaterialLaw::neo_hookean_tled: return "neo_hookean_tled";
  }
  return "?";
}

MaterialLaw material_law_from_string(const std::string& name) {
  if (name == "neo_hookean_tled") return MaterialLaw::neo_hookean_tled;
  throw std::invalid_argument("unknown constitutive law '" + name + "' (known: neo_hookean_tled)");
}

Material make_neo_hookean_material(std::string name, double youngs_modulus, double poisson_ratio,
                                   double density) {
  Material m;
  m.name = std::move(name);
  m.law = MaterialLaw::neo_hookean_tled;
  m.youngs_modulus = youngs_modulus;
  m.poisson_ratio = poisson_ratio;
  m.shear_modulus = youngs_modulus / (2.0 * (1.0 + poisson_ratio));
  m.bulk_modulus = youngs_modulus / (3.0 * (1.0 - 2.0 * poisson_ratio));
  m.density = density;
  return m;
}

const char* to_string(ForceLengthCurve curve) {
  switch (curve) {
    case ForceLengthCurve::blemker2005: return "blemker2005";
  }
  return "?";
}

ForceLengthCurve force_length_curve_from_string(const std::string& name) {
  if (name == "blemker2005") return ForceLengthCurve::blemker2005;
  throw std::invalid_argument("unknown force-length curve '" + name + "' (known: blemker2005)");
}

const char* to_string(SurfaceRole role) {
  switch (role) {
    case SurfaceRole::sliding: return "sliding";
    case SurfaceRole::visual: return "visual";
  }
  return "?";
}

SurfaceRole surface_role_from_string(const std::string& name) {
  if (name == "sliding") return SurfaceRole::sliding;
  if (name == "visual") return SurfaceRole::visual;
  throw std::invalid_argument("unknown surface role '" + name + "' (known: sliding, visual)");
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
      throw std::invalid_argument("element lattice is not sorted (k, j, i) and unique at element " +
                                  std::to_string(e));
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
