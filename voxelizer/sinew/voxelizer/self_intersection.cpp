#include "sinew/voxelizer/self_intersection.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <cstddef>
#include <vector>

namespace sinew::voxelizer {

bool self_intersects(const TriangleMesh& mesh) {
  // Exact predicates: two triangles that only touch along a shared edge must not count, and
  // rounding in the intersection tests would make them.
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<Kernel::Point_3> points;
  points.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices) points.emplace_back(v.x, v.y, v.z);
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    faces.push_back({static_cast<std::size_t>(t[0]), static_cast<std::size_t>(t[1]),
                     static_cast<std::size_t>(t[2])});
  }
  if (faces.empty() || !PMP::is_polygon_soup_a_polygon_mesh(faces)) return false;
  CGAL::Surface_mesh<Kernel::Point_3> sm;
  PMP::polygon_soup_to_polygon_mesh(points, faces, sm);
  return PMP::does_self_intersect(sm);
}

}  // namespace sinew::voxelizer
