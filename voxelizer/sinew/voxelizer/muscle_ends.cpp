#include "sinew/voxelizer/muscle_ends.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <map>
#include <utility>

namespace sinew::voxelizer {
namespace {

// The outer mesh's boundary edges (used by exactly one triangle) as segments.
std::vector<std::pair<Vec3d, Vec3d>> boundary_segments(const TriangleMesh& mesh) {
  std::map<std::pair<std::int32_t, std::int32_t>, int> uses;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const auto a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>((k + 1) % 3)];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  std::vector<std::pair<Vec3d, Vec3d>> out;
  for (const auto& [edge, n] : uses) {
    if (n == 1) {
      out.emplace_back(mesh.vertices[static_cast<std::size_t>(edge.first)],
                       mesh.vertices[static_cast<std::size_t>(edge.second)]);
    }
  }
  return out;
}

double segment_distance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double len2 = dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * ab));
}

Vec3d element_centre(const formats::Model& m, formats::Index e) {
  Vec3d c{0, 0, 0};
  for (const auto n : m.element_nodes[static_cast<std::size_t>(e)]) {
    const auto p = m.node_position(n);
    c = c + 0.125 * Vec3d{p[0], p[1], p[2]};
  }
  return c;
}

}  // namespace

std::vector<FreeMuscleEnd> free_muscle_ends(const formats::Model& model,
                                            const std::vector<MuscleEnd>& ends,
                                            const TriangleMesh& outer, double reach) {
  const auto edges = boundary_segments(outer);
  if (edges.empty()) return {};
  std::vector<char> held(model.node_count(), 0);
  for (const auto n : model.rigid_nodes) held[static_cast<std::size_t>(n)] = 1;
  for (const auto& s : model.sliding) held[static_cast<std::size_t>(s.node)] = 1;
  if (model.jaw) {
    for (const auto n : model.jaw->nodes) held[static_cast<std::size_t>(n)] = 1;
  }
  auto edge_distance = [&](const Vec3d& p) {
    double d = std::numeric_limits<double>::infinity();
    for (const auto& [a, b] : edges) d = std::min(d, segment_distance(p, a, b));
    return d;
  };
  std::vector<FreeMuscleEnd> out;
  for (const auto& end : ends) {
    FreeMuscleEnd f{end.muscle, end.end, std::numeric_limits<double>::infinity(), {0, 0, 0}};
    for (const auto e : end.elements) {
      const Vec3d c = element_centre(model, e);
      const double d = edge_distance(c);
      if (d < f.edge_distance) f.edge_distance = d, f.where = c;
    }
    if (!(f.edge_distance <= reach)) continue;
    // The rim there: the nodes within `reach` of the edge and within 3 reach of the end's voxel
    // nearest it. Held along at least half of it, the edge does not follow the muscle (a deep
    // node held here and there does not stop it: the sample head's skin cut open into a mask, its
    // deep 8 mm held, held 3 of the 98 rim nodes by the frontalis's origin, and the muscle pulled
    // the mask's top 3 mm down while the brows rose 0.9 mm).
    for (std::size_t n = 0; n < model.node_count(); ++n) {
      const auto q = model.node_position(formats::Index(n));
      const Vec3d p{q[0], q[1], q[2]};
      if (norm(p - f.where) > 3 * reach || edge_distance(p) > reach) continue;
      ++f.rim;
      f.rim_held += held[n] != 0;
    }
    if (2 * f.rim_held < f.rim) out.push_back(f);
  }
  return out;
}

std::string free_muscle_end_warning(const FreeMuscleEnd& f) {
  return fmt::format(
      "muscle {}: its {} lies {:.1f} mm from the skin's free edge (the outer mesh is open), where "
      "{} of the edge's {} nodes nearby are held: it will pull that edge in instead of moving the "
      "face; hold the edge there, e.g. a rigid box around ({:.1f}, {:.1f}, {:.1f}) mm "
      "(docs/faces.md, \"An open face mask\")",
      f.muscle, f.end, 1e3 * f.edge_distance, f.rim_held, f.rim, 1e3 * f.where.x, 1e3 * f.where.y,
      1e3 * f.where.z);
}

}  // namespace sinew::voxelizer
