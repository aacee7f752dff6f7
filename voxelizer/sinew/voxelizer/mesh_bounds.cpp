#include "sinew/voxelizer/mesh_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sinew::voxelizer {
namespace {

std::string number(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

}  // namespace

std::string format_length(double metres, LengthUnit units) {
  return number(metres / metres_per_unit(units)) + " " + to_string(units);
}

std::optional<std::string> extent_problem(const TriangleMesh& mesh, LengthUnit units) {
  if (mesh.vertices.empty()) return std::nullopt;
  const BoundingBox b = bounding_box(mesh);
  const Vec3d size = b.hi - b.lo;
  const double longest = std::max({size.x, size.y, size.z});
  const double limit = kMaxExtentInUnits * metres_per_unit(units);
  if (longest <= limit) return std::nullopt;
  const char axis = longest == size.x ? 'x' : (longest == size.y ? 'y' : 'z');
  return "the mesh spans " + format_length(longest, units) + " along " + axis + " (" +
         format_length(size.x, units) + " x " + format_length(size.y, units) + " x " +
         format_length(size.z, units) + "), more than " + number(kMaxExtentInUnits) + " " +
         to_string(units) +
         " (the spec's units): a file in other units (give the mesh's `unit:` "
         "or `scale:`) or a damaged one (--force goes past this check)";
}

std::optional<std::string> element_count_problem(double expected_elements, std::int64_t limit,
                                                 double h, LengthUnit units) {
  if (!(expected_elements > static_cast<double>(limit))) return std::nullopt;
  return "the meshes would make about " + number(expected_elements) + " elements at voxel size " +
         format_length(h, units) + ", more than resolution.max_elements (" + std::to_string(limit) +
         "): check the meshes' units and scale, choose a larger voxel size, raise "
         "resolution.max_elements, or --force";
}

std::optional<std::string> volume_problem(const MeshDiagnostics& d, LengthUnit units) {
  if (!(d.enclosed_volume < 0)) return std::nullopt;
  const double unit3 = std::pow(metres_per_unit(units), 3);
  return "the mesh encloses a negative volume (" + number(d.enclosed_volume / unit3) + " " +
         to_string(units) + "³; " + std::to_string(d.boundary_edges) + " boundary, " +
         std::to_string(d.non_manifold_edges) + " non-manifold and " +
         std::to_string(d.inconsistently_oriented_edges) +
         " inconsistently oriented edges): it is inside out or broken, and its inside cannot "
         "be told (--force goes past this check)";
}

}  // namespace sinew::voxelizer
