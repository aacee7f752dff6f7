#include "sinew/voxelizer/constraint_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <utility>

#include "sinew/voxelizer/distance.hpp"

namespace sinew::voxelizer {

namespace {

std::string mm(double metres) {
  return fmt::format("{:.3g} mm", metres * 1e3);
}

std::string surface_name(const BoundarySpec& b) {
  return b.surface.mesh ? b.surface.mesh->describe() : b.surface.name;
}

Vec3d position(const formats::Model& model, formats::Index n) {
  const auto p = model.node_position(n);
  return {p[0], p[1], p[2]};
}

// Signed height of p over triangle t of `mesh` along its outward normal (m); negative: behind it,
// where the simulator's sliding projection sends the node to the other side.
double height_over(const TriangleMesh& mesh, std::int32_t t, const Vec3d& p) {
  const auto& tri = mesh.triangles[static_cast<std::size_t>(t)];
  const Vec3d& a = mesh.vertices[static_cast<std::size_t>(tri[0])];
  const Vec3d& b = mesh.vertices[static_cast<std::size_t>(tri[1])];
  const Vec3d& c = mesh.vertices[static_cast<std::size_t>(tri[2])];
  const Vec3d n = cross(b - a, c - a);
  const double len = norm(n);
  if (!(len > 0)) return 0;
  return dot(p - closest_point_on_triangle(p, a, b, c), (1.0 / len) * n);
}

}  // namespace

std::string describe_selection(const BoundarySpec& b) {
  std::string text = b.kind == BoundarySpec::Kind::rigid ? "rigid" : "sliding";
  if (b.kind == BoundarySpec::Kind::sliding && b.has_surface)
    text += " on '" + surface_name(b) + "'";
  std::vector<std::string> parts;
  if (b.has_surface) {
    const std::string s = "'" + surface_name(b) + "'";
    if (b.inside) parts.push_back("inside " + s);
    if (b.within) parts.push_back("within " + mm(*b.within) + " of " + s);
  }
  for (std::size_t k = 0; k < parts.size(); ++k) text += (k ? " or " : ": ") + parts[k];
  if (b.box) text += parts.empty() ? ": in its box" : ", in its box";
  return text;
}

std::string describe_condition(const BoundarySpec& b) {
  return b.field + " (" + describe_selection(b) + ")";
}

ConstraintCheck check_constraints(const formats::Model& model,
                                  const std::vector<BoundaryCondition>& conditions,
                                  const std::vector<BoundarySpec>& specs,
                                  const ConstraintResult& bound) {
  ConstraintCheck out;
  const double tol = 1e-6 * model.grid.voxel_size;
  // Sliding nodes behind their surface, per condition: count, deepest node and depth.
  struct Behind {
    std::vector<formats::Index> nodes;
    formats::Index deepest = -1;
    double depth = 0;  // m
  };
  // Inside the surface (its own inside test: the pseudonormal or the winding number): an error.
  // Behind the closest triangle but outside the surface (a misoriented or folded triangle of a
  // messy mesh): a warning, the simulator's projection will still move these nodes through it.
  // An open surface (a glide surface derived from a face mask) has no inside to ask: behind its
  // closest triangle by more than half a voxel is an error there (issue 34: 88 such nodes beside
  // a mask's glide surface, up to 8 mm behind it at h = 4 mm, only warned of, inverted their
  // elements at step 0); less stays a warning (one node 0.44 mm behind the open MakerBot skull's
  // folded triangles, tests/voxelizer/real_pipeline_test.cpp).
  std::map<std::size_t, Behind> behind, misoriented;
  for (const auto& s : bound.sliding) {
    const auto c = static_cast<std::size_t>(bound.condition[static_cast<std::size_t>(s.node)]);
    const Vec3d p = position(model, s.node);
    const double height = height_over(conditions[c].surface->mesh(), s.rest_triangle, p);
    if (height >= -tol) continue;
    const SignedField& surface = *conditions[c].surface;
    const bool open_and_deep = !surface.closed() && -height > 0.5 * model.grid.voxel_size;
    auto& b = open_and_deep || surface.inside(p) ? behind[c] : misoriented[c];
    b.nodes.push_back(s.node);
    if (-height > b.depth) {
      b.depth = -height;
      b.deepest = s.node;
    }
  }
  if (!behind.empty()) {
    const auto& [c, b] = *behind.begin();
    const auto p = position(model, b.deepest);
    std::string msg = fmt::format(
        "this condition ({}) binds {} nodes (of its {}) that lie behind (inside) the surface they "
        "slide "
        "on, up to {} deep "
        "(node {} at ({:.4g}, {:.4g}, {:.4g}) mm). The simulator keeps a sliding node at its rest "
        "distance on the surface's outer side (physics-notes §5): it would move these nodes out "
        "through it, by twice their depth, at the first step, and invert their elements.{}",
        describe_selection(specs[c]), b.nodes.size(), bound.per_condition[c], mm(b.depth),
        b.deepest, p.x * 1e3, p.y * 1e3, p.z * 1e3,
        conditions[c].surface->closed()
            ? ""
            : " The surface is open (an open skin's offset: a face mask's): beside its edge, nodes "
              "lie behind its last triangles; keep this condition's box away from the edge.");
    std::string held;
    for (std::size_t r = c + 1; r < conditions.size(); ++r) {
      if (conditions[r].kind != BoundarySpec::Kind::rigid) continue;
      std::size_t n = 0;
      for (auto node : b.nodes)
        n += condition_selects(conditions[r], position(model, node)) ? 1 : 0;
      if (n > 0)
        held += fmt::format("{}{} comes after it and would hold {} of them",
                            held.empty() ? "" : "; ", describe_condition(specs[r]), n);
    }
    const std::string surface =
        specs[c].surface.mesh ? specs[c].surface.field : "'" + specs[c].surface.name + "'";
    msg += held.empty() ? " Hold them first" : " " + held + ": list it first";
    msg += fmt::format(
        ", or hold the nodes behind the surface first (a rigid condition inside {} listed before "
        "this one), restrict this condition to nodes outside the surface (box), or slide on a "
        "surface below them (glide_depth: the derived surface 'glide').",
        surface);
    for (auto it = std::next(behind.begin()); it != behind.end(); ++it)
      msg += fmt::format(" Also {}: {} nodes behind its surface.",
                         describe_condition(specs[it->first]), it->second.nodes.size());
    out.field = specs[c].field;
    out.error = msg;
  }

  for (const auto& [c, b] : misoriented) {
    const auto p = position(model, b.deepest);
    out.warnings.push_back(fmt::format(
        "{}: {} nodes outside the surface lie behind the outward normal of their closest triangle "
        "(misoriented or folded triangles), up to {} (node {} at ({:.4g}, {:.4g}, {:.4g}) mm); the "
        "simulator's sliding projection will move them to the other side of that triangle",
        describe_condition(specs[c]), b.nodes.size(), mm(b.depth), b.deepest, p.x * 1e3, p.y * 1e3,
        p.z * 1e3));
  }

  // Elements with rigid corners next to sliding ones, per (rigid, sliding) pair of conditions.
  std::map<std::pair<int, int>, std::int64_t> mixed;
  for (const auto& corners : model.element_nodes) {
    int rigid = -1, sliding = -1;
    for (auto n : corners) {
      const int c = bound.condition[static_cast<std::size_t>(n)];
      if (c < 0) continue;
      (conditions[static_cast<std::size_t>(c)].kind == BoundarySpec::Kind::rigid ? rigid
                                                                                 : sliding) = c;
    }
    if (rigid >= 0 && sliding >= 0 &&
        conditions[static_cast<std::size_t>(rigid)].surface ==
            conditions[static_cast<std::size_t>(sliding)].surface)
      ++mixed[{rigid, sliding}];
  }
  for (const auto& [pair, count] : mixed) {
    out.warnings.push_back(fmt::format(
        "{} elements have corners held by {} next to corners sliding on the same surface by {}: "
        "they cannot follow the tissue sliding past their rigid corners and may invert; slide on "
        "a surface below the held nodes instead (glide_depth; docs/voxelizer.md, \"Safe "
        "constraints\")",
        count, describe_condition(specs[static_cast<std::size_t>(pair.first)]),
        describe_condition(specs[static_cast<std::size_t>(pair.second)])));
  }
  return out;
}

}  // namespace sinew::voxelizer
