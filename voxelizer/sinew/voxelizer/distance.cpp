#include "sinew/voxelizer/distance.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Iterator>;
using Traits = CGAL::AABB_traits<Kernel, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;

}  // namespace

Vec3d closest_point_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + (vb * denom) * ab + (vc * denom) * ac;
}

struct DistanceQuery::Impl {
  std::vector<Triangle> triangles;
  std::vector<std::int32_t> index;  // tree triangle -> mesh triangle
  Tree tree;
  // Collinear triangles as segments (usually none: clean_mesh removes them).
  std::vector<std::array<Vec3d, 2>> segments;
  std::vector<std::int32_t> segment_index;

  // Improves hit with the segments, if any is closer.
  void check_segments(const Vec3d& p, Hit& hit) const {
    for (std::size_t s = 0; s < segments.size(); ++s) {
      const Vec3d a = segments[s][0], d = segments[s][1] - segments[s][0];
      const double len2 = squared_norm(d);
      const double u = len2 > 0 ? std::clamp(dot(p - a, d) / len2, 0.0, 1.0) : 0.0;
      const Vec3d c = a + u * d;
      const double dist = norm(p - c);
      if (dist < hit.distance) hit = {c, segment_index[s], dist};
    }
  }
};

DistanceQuery::DistanceQuery(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  check_triangle_indices(mesh);
  impl_->triangles.reserve(mesh.triangles.size());
  impl_->index.reserve(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    const Vec3d& a = mesh.vertices[t[0]];
    const Vec3d& b = mesh.vertices[t[1]];
    const Vec3d& c = mesh.vertices[t[2]];
    const Triangle tri(Point(a.x, a.y, a.z), Point(b.x, b.y, b.z), Point(c.x, c.y, c.z));
    // CGAL's point-triangle distance needs a supporting plane: a triangle with collinear corners
    // is kept as the segment between its two farthest corners and checked separately.
    if (tri.is_degenerate()) {
      const Vec3d e[3][2] = {{a, b}, {b, c}, {c, a}};
      int longest = 0;
      for (int k = 1; k < 3; ++k)
        if (squared_norm(e[k][1] - e[k][0]) > squared_norm(e[longest][1] - e[longest][0]))
          longest = k;
      impl_->segments.push_back({e[longest][0], e[longest][1]});
      impl_->segment_index.push_back(static_cast<std::int32_t>(i));
      continue;
    }
    impl_->triangles.push_back(tri);
    impl_->index.push_back(static_cast<std::int32_t>(i));
  }
  if (impl_->triangles.empty())
    throw GeometryError(mesh.source, "triangles",
                        "distance query on a mesh without a non-degenerate triangle");
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
  // Force the lazily built search structure now, so that later const queries never build.
  (void)impl_->tree.closest_point(impl_->triangles.front().vertex(0));
}

DistanceQuery::~DistanceQuery() = default;
DistanceQuery::DistanceQuery(DistanceQuery&&) noexcept = default;
DistanceQuery& DistanceQuery::operator=(DistanceQuery&&) noexcept = default;

DistanceQuery::Hit DistanceQuery::closest(const Vec3d& p) const {
  const Point q(p.x, p.y, p.z);
  const auto [point, id] = impl_->tree.closest_point_and_primitive(q);
  const Vec3d c{point.x(), point.y(), point.z()};
  const auto k = static_cast<std::size_t>(id - impl_->triangles.cbegin());
  Hit hit{c, impl_->index[k], norm(p - c)};
  if (!impl_->segments.empty()) impl_->check_segments(p, hit);
  return hit;
}

double DistanceQuery::distance(const Vec3d& p) const {
  if (!impl_->segments.empty()) return closest(p).distance;
  const Point q(p.x, p.y, p.z);
  return std::sqrt(impl_->tree.squared_distance(q));
}

void DistanceQuery::evaluate(const std::vector<Vec3d>& points, std::vector<double>& out) const {
  out.resize(points.size());
  const auto n = static_cast<std::int64_t>(points.size());
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t i = 0; i < n; ++i) out[i] = distance(points[i]);
}

}  // namespace sinew::voxelizer
