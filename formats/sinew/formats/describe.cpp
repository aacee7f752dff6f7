#include "sinew/formats/describe.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sinew/common/error.hpp"

namespace sinew::formats {
namespace {

std::string at_mm(const Point& p) {
  return fmt::format("({:.4g}, {:.4g}, {:.4g}) mm", p[0] * 1e3, p[1] * 1e3, p[2] * 1e3);
}

// Index of lattice point l in a sorted lattice list (elements by base corner, or nodes), -1 when
// absent.
Index find_lattice(const std::vector<Lattice>& list, const Lattice& l) {
  const auto it = std::lower_bound(list.begin(), list.end(), l, lattice_less);
  return it != list.end() && *it == l ? Index(it - list.begin()) : -1;
}

// "-x 4999, +x none, ...": the ids of l's 6 lattice neighbours in `list`.
std::string neighbours_of(const std::vector<Lattice>& list, const Lattice& l) {
  static constexpr const char* kDirection[6] = {"-x", "+x", "-y", "+y", "-z", "+z"};
  std::vector<std::string> out;
  for (int d = 0; d < 6; ++d) {
    Lattice k = l;
    k[std::size_t(d / 2)] += d % 2 ? 1 : -1;
    const Index q = find_lattice(list, k);
    out.push_back(fmt::format("{} {}", kDirection[d], q < 0 ? "none" : std::to_string(q)));
  }
  return fmt::format("{}", fmt::join(out, ", "));
}

// Signed height of p over triangle t of s along its outward normal, m (negative: behind it).
double height_over(const Surface& s, Index t, const Point& p) {
  auto sub = [](const Point& a, const Point& b) {
    return Point{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  };
  auto dotp = [](const Point& a, const Point& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  const auto& tri = s.triangles[std::size_t(t)];
  const Point a = s.vertices[std::size_t(tri[0])], b = s.vertices[std::size_t(tri[1])],
              c = s.vertices[std::size_t(tri[2])];
  const Point ab = sub(b, a), ac = sub(c, a);
  Point n{ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
          ab[0] * ac[1] - ab[1] * ac[0]};
  const double len = std::sqrt(dotp(n, n));
  if (!(len > 0)) return 0;
  // Height over the triangle's plane: the side test the simulator's projection makes when the
  // closest point lies inside the triangle (physics/sliding.hpp).
  return dotp(sub(p, a), n) / len;
}

std::string constraint_of(const Model& m, Index n) {
  if (std::binary_search(m.rigid_nodes.begin(), m.rigid_nodes.end(), n)) return "rigid";
  if (m.jaw && std::binary_search(m.jaw->nodes.begin(), m.jaw->nodes.end(), n)) return "jaw";
  const auto it =
      std::lower_bound(m.sliding.begin(), m.sliding.end(), n,
                       [](const SlidingBinding& b, Index node) { return b.node < node; });
  if (it == m.sliding.end() || it->node != n) return "free";
  const Surface& s = m.surfaces[std::size_t(it->surface)];
  const double h = height_over(s, it->rest_triangle, m.node_position(n));
  return fmt::format(
      "sliding on '{}' (rest distance {:.4g} mm, rest triangle {}, {} its plane by "
      "{:.4g} mm{})",
      s.name, it->rest_distance * 1e3, it->rest_triangle, h < 0 ? "behind" : "above",
      std::abs(h) * 1e3,
      h < -1e-6 * m.grid.voxel_size ? ": the simulator moves it out to the surface's outer side"
                                    : "");
}

std::vector<std::string> sets_with(const std::vector<NamedSet>& sets, Index id) {
  std::vector<std::string> out;
  for (const auto& s : sets)
    if (std::binary_search(s.ids.begin(), s.ids.end(), id)) out.push_back(s.name);
  return out;
}

std::string list_or_none(const std::vector<std::string>& v) {
  return v.empty() ? "none" : fmt::format("{}", fmt::join(v, ", "));
}

}  // namespace

std::string describe_element(const Model& m, Index e, const std::string& file) {
  if (e < 0 || std::size_t(e) >= m.element_count())
    throw ConfigError(file, "--element",
                      fmt::format("element {} out of range [0, {})", e, m.element_count()));
  const auto& l = m.element_lattice[std::size_t(e)];
  const double h = m.grid.voxel_size;
  const Point base = m.node_position(m.element_nodes[std::size_t(e)][0]);
  const Point centre{base[0] + h / 2, base[1] + h / 2, base[2] + h / 2};
  std::string out = fmt::format("element {} of {}\n", e, m.element_count());
  out += fmt::format("  lattice      ({}, {}, {}) (base corner), voxel {:.4g} mm\n", l[0], l[1],
                     l[2], h * 1e3);
  out += fmt::format("  centre       {} = ({:.6g}, {:.6g}, {:.6g}) m\n", at_mm(centre), centre[0],
                     centre[1], centre[2]);
  double tissue = 0;
  out += "  materials\n";
  for (auto q = m.material_offsets[std::size_t(e)]; q < m.material_offsets[std::size_t(e) + 1];
       ++q) {
    const auto& mat = m.materials[std::size_t(m.material_ids[std::size_t(q)])];
    tissue += m.material_fractions[std::size_t(q)];
    out += fmt::format("    {:<20} fraction {:.4f}  (E = {:.4g} Pa, ν = {:.3g})\n", mat.name,
                       m.material_fractions[std::size_t(q)], mat.youngs_modulus, mat.poisson_ratio);
  }
  out += fmt::format("    tissue fraction {:.4f}\n", tissue);
  out += "  muscles\n";
  bool any_muscle = false;
  for (const auto& mu : m.muscles) {
    const auto it = std::lower_bound(mu.elements.begin(), mu.elements.end(), e);
    if (it == mu.elements.end() || *it != e) continue;
    const auto k = std::size_t(it - mu.elements.begin());
    any_muscle = true;
    out += fmt::format(
        "    {:<20} fraction {:.4f}, fibre ({:.4f}, {:.4f}, {:.4f}), σref {:.4g} Pa\n", mu.name,
        mu.fractions[k], mu.fibres[k][0], mu.fibres[k][1], mu.fibres[k][2], mu.reference_stress);
  }
  if (!any_muscle) out += "    none\n";
  out += "  corners\n";
  for (int c = 0; c < 8; ++c) {
    const Index n = m.element_nodes[std::size_t(e)][std::size_t(c)];
    out += fmt::format("    {} node {:<9} {}  {}\n", c, n, at_mm(m.node_position(n)),
                       constraint_of(m, n));
  }
  out += fmt::format("  neighbours   {}\n", neighbours_of(m.element_lattice, l));
  out += fmt::format("  element sets {}\n", list_or_none(sets_with(m.element_sets, e)));
  std::vector<std::string> bound;
  for (const auto& s : m.surfaces) {
    const auto k = std::count(s.embedding_element.begin(), s.embedding_element.end(), e);
    if (k > 0) bound.push_back(fmt::format("{} ({} vertices)", s.name, k));
  }
  out += fmt::format("  visual       {}\n", list_or_none(bound));
  return out;
}

std::string describe_node(const Model& m, Index n, const std::string& file) {
  if (n < 0 || std::size_t(n) >= m.node_count())
    throw ConfigError(file, "--node",
                      fmt::format("node {} out of range [0, {})", n, m.node_count()));
  const auto& l = m.node_lattice[std::size_t(n)];
  const Point p = m.node_position(n);
  std::string out = fmt::format("node {} of {}\n", n, m.node_count());
  out += fmt::format("  lattice      ({}, {}, {})\n", l[0], l[1], l[2]);
  out +=
      fmt::format("  position     {} = ({:.6g}, {:.6g}, {:.6g}) m\n", at_mm(p), p[0], p[1], p[2]);
  out += fmt::format("  constraint   {}\n", constraint_of(m, n));
  out += fmt::format("  node sets    {}\n", list_or_none(sets_with(m.node_sets, n)));
  out += "  elements (corner: element, dominant material, muscles)\n";
  for (int c = 0; c < 8; ++c) {
    // The element whose corner c is this node has its base at l − offset(c).
    Lattice b = l;
    for (int k = 0; k < 3; ++k) b[std::size_t(k)] -= kHexCorner[std::size_t(c)][std::size_t(k)];
    const Index e = find_lattice(m.element_lattice, b);
    if (e < 0) continue;
    std::string dominant = "-";
    double best = -1;
    for (auto q = m.material_offsets[std::size_t(e)]; q < m.material_offsets[std::size_t(e) + 1];
         ++q) {
      if (m.material_fractions[std::size_t(q)] > best) {
        best = m.material_fractions[std::size_t(q)];
        dominant = m.materials[std::size_t(m.material_ids[std::size_t(q)])].name;
      }
    }
    std::vector<std::string> muscles;
    for (const auto& mu : m.muscles)
      if (std::binary_search(mu.elements.begin(), mu.elements.end(), e)) muscles.push_back(mu.name);
    out += fmt::format("    {}: element {:<9} {} {:.4f}, muscles: {}\n", c, e, dominant, best,
                       list_or_none(muscles));
  }
  out += fmt::format("  neighbours   {}\n", neighbours_of(m.node_lattice, l));
  return out;
}

}  // namespace sinew::formats
