#include "sinew/simulator/engine/constraint_report.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <utility>

#include "sinew/simulator/physics/sliding.hpp"

namespace sinew::simulator {
namespace {

bool listed(const std::vector<Index>& nodes, Index node) {
  return std::find(nodes.begin(), nodes.end(), node) != nodes.end();
}

std::string mm(double metres) {
  return fmt::format("{:.3g} mm", metres * 1e3);
}

}  // namespace

NodeConstraints node_constraints(const PreparedModel& p, const Setup& setup,
                                 const std::vector<Index>& model_rigid, Index node) {
  NodeConstraints out;
  if (listed(p.rigid, node)) {
    out.items.push_back(std::binary_search(model_rigid.begin(), model_rigid.end(), node)
                            ? "rigid (the model's rigid nodes)"
                            : "rigid (fixed by the scene)");
  }
  const auto it = std::find(p.slide_node.begin(), p.slide_node.end(), node);
  if (it != p.slide_node.end() && *it == node) {
    const auto k = std::size_t(it - p.slide_node.begin());
    const auto& s = p.surfaces[std::size_t(p.slide_surface[k])];
    std::string item =
        fmt::format("sliding on '{}' (rest distance {}", s.name, mm(p.slide_distance[k]));
    const auto t = p.slide_triangle[k];
    if (t >= 0 && std::size_t(t) < s.triangles.size()) {
      using V = Vec3<double>;
      auto vertex = [&](int c) {
        const auto& v = s.vertices[std::size_t(s.triangles[std::size_t(t)][std::size_t(c)])];
        return V{v[0], v[1], v[2]};
      };
      const auto& r = p.rest[std::size_t(node)];
      const V x{r[0], r[1], r[2]};
      const V a = vertex(0), b = vertex(1), c = vertex(2);
      const double height = dot(x - physics::closest_point_on_triangle(x, a, b, c),
                                physics::triangle_normal(a, b, c));
      if (height < -1e-6 * p.h) {
        out.behind = true;
        item += fmt::format(
            "; it lay {} behind (inside) that surface at rest, and the sliding projection moves "
            "it out to the outer side, {} in one step",
            mm(-height), mm(-2 * height));
      }
    }
    out.items.push_back(item + ")");
  }
  auto labelled = [](const std::string& label, const char* what, std::size_t k) {
    return label.empty() ? fmt::format("{} {}", what, k) : label;
  };
  if (setup.effects.loads) {
    for (std::size_t k = 0; k < setup.prescribed.size(); ++k)
      if (listed(setup.prescribed[k].nodes, node))
        out.items.push_back("prescribed by " +
                            labelled(setup.prescribed[k].label, "prescribed displacement", k));
    for (std::size_t k = 0; k < setup.forces.size(); ++k)
      if (listed(setup.forces[k].nodes, node))
        out.items.push_back("loaded by " + labelled(setup.forces[k].label, "nodal force", k));
  }
  if (setup.jaw && listed(setup.jaw->nodes, node))
    out.items.push_back("moved with the jaw (the scene's jaw: curves)");
  for (std::size_t k = 0; k < setup.sliding_planes.size(); ++k)
    if (listed(setup.sliding_planes[k].nodes, node))
      out.items.push_back("on the plane of " +
                          labelled(setup.sliding_planes[k].label, "sliding plane", k));
  return out;
}

std::string element_constraints(const PreparedModel& p, const Setup& setup,
                                const std::vector<Index>& model_rigid, Index element,
                                bool& behind) {
  behind = false;
  // Corners with the same constraints are listed together: "nodes 5, 6 sliding on 'floor' (...)".
  std::vector<std::pair<std::string, std::vector<Index>>> groups;
  for (const Index n : p.element_nodes[std::size_t(element)]) {
    const NodeConstraints c = node_constraints(p, setup, model_rigid, n);
    if (c.items.empty()) continue;
    behind = behind || c.behind;
    std::string what;
    for (std::size_t k = 0; k < c.items.size(); ++k) what += (k ? ", " : "") + c.items[k];
    const auto g =
        std::find_if(groups.begin(), groups.end(), [&](const auto& e) { return e.first == what; });
    if (g == groups.end())
      groups.push_back({what, {n}});
    else
      g->second.push_back(n);
  }
  std::string text;
  for (const auto& [what, nodes] : groups)
    text += fmt::format("{}{} {} {}", text.empty() ? "" : "; ", nodes.size() > 1 ? "nodes" : "node",
                        fmt::join(nodes, ", "), what);
  return text;
}

}  // namespace sinew::simulator
