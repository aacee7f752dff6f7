#pragma once
// Exact unsigned distance from a point to a triangle mesh and the closest point on it, through a
// CGAL AABB tree (Simple_cartesian<double>) with its distance-query acceleration. Exact means the
// true Euclidean distance to the nearest triangle up to double rounding, not a sampled field.
// Units: those of the mesh (m).
#include <cstdint>
#include <memory>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

// Closest point on triangle (a, b, c) to p (Ericson, "Real-Time Collision Detection", 5.1.5).
sinew::Vec3d closest_point_on_triangle(const sinew::Vec3d& p, const sinew::Vec3d& a,
                                       const sinew::Vec3d& b, const sinew::Vec3d& c);

class DistanceQuery {
 public:
  // Copies the triangles and builds the tree (and its acceleration structure) now, so that
  // queries are const and thread-safe. Degenerate triangles are allowed: a collinear one counts as
  // the segment between its two farthest corners, checked linearly for every query (clean_mesh
  // removes them). Throws GeometryError if the mesh has no non-degenerate triangle.
  explicit DistanceQuery(const TriangleMesh& mesh);
  ~DistanceQuery();
  DistanceQuery(DistanceQuery&&) noexcept;
  DistanceQuery& operator=(DistanceQuery&&) noexcept;
  DistanceQuery(const DistanceQuery&) = delete;
  DistanceQuery& operator=(const DistanceQuery&) = delete;

  // point: closest point on the mesh (m); triangle: its triangle index in the mesh given to the
  // constructor; distance: |p - point| (m).
  struct Hit {
    sinew::Vec3d point;
    std::int32_t triangle;
    double distance;
  };
  Hit closest(const sinew::Vec3d& p) const;
  double distance(const sinew::Vec3d& p) const;
  // out[i] = distance(points[i]) (out is resized); OpenMP-parallel, thread-count independent.
  void evaluate(const std::vector<sinew::Vec3d>& points, std::vector<double>& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sinew::voxelizer
