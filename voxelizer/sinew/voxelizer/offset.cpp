#include "sinew/voxelizer/offset.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <chrono>
#include <cmath>
#include <mutex>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/winding_number.hpp"

namespace sinew::voxelizer {

TriangleMesh inward_offset_surface(const TriangleMesh& skin, double thickness, double voxel_size) {
  if (skin.triangles.empty())
    throw GeometryError(skin.source, "triangles", "cannot offset a mesh without triangles");
  if (!(thickness > 0) || !std::isfinite(thickness))
    throw GeometryError(skin.source, "thickness", "must be a positive number of metres");
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw GeometryError(skin.source, "voxel_size", "must be a positive number of metres");
  const BoundingBox box = bounding_box(skin);
  const Vec3d ext = box.hi - box.lo;
  const double across = std::max({ext.x, ext.y, ext.z}) / voxel_size;
  if (!(across < 2147483647.0 / 4))
    throw GeometryError(skin.source, "voxel_size",
                        "grid would need " + std::to_string(across) + " voxels across");

  const auto start = std::chrono::steady_clock::now();
  auto seconds = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  static std::once_flag init;
  std::call_once(init, [] { openvdb::initialize(); });

  // Coordinates relative to the box centre keep float precision where the grid lives.
  const Vec3d origin = 0.5 * (box.lo + box.hi);
  std::vector<openvdb::Vec3s> points;
  points.reserve(skin.vertices.size());
  for (const Vec3d& v : skin.vertices) {
    const Vec3d x = v - origin;
    points.emplace_back(float(x.x), float(x.y), float(x.z));
  }
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(skin.triangles.size());
  for (const auto& t : skin.triangles)
    triangles.emplace_back(openvdb::Index32(t[0]), openvdb::Index32(t[1]), openvdb::Index32(t[2]));
  const std::vector<openvdb::Vec4I> no_quads;
  const auto xform = openvdb::math::Transform::createLinearTransform(voxel_size);
  const double h = voxel_size;
  // The level set keeps |G| < 2 voxels, G = phi + thickness (phi: signed distance, negative
  // inside). OpenVDB's unsigned distances U away from the surface are distances to propagated
  // triangles, not always the nearest: never below the true distance, but above it by up to 0.6
  // voxel at 6 voxels' depth on a sphere. So U only picks candidates: U < thickness - kept is
  // safely positive, and above it an allowance growing with depth covers the overestimate. The
  // kept values are exact (DistanceQuery).
  const double kept = 2 * h;
  const double above = kept + h + 0.25 * thickness;
  const float band = static_cast<float>((thickness + above) / h + 1);
  const openvdb::FloatGrid::Ptr unsigned_distance =
      openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(*xform, points, triangles,
                                                                      no_quads, band);

  std::vector<openvdb::Coord> coords;
  std::vector<Vec3d> where;
  for (auto it = unsigned_distance->cbeginValueOn(); it; ++it) {
    const double u = *it;
    if (u < thickness - kept - 0.01 * h || u > thickness + above) continue;
    const openvdb::Coord c = it.getCoord();
    coords.push_back(c);
    where.push_back(origin + Vec3d{c.x() * h, c.y() * h, c.z() * h});
  }
  log::debug("offset: {} narrow-band voxels, {} near the offset surface ({:.2f} s)",
             unsigned_distance->activeVoxelCount(), coords.size(), seconds());
  // Outside the skin G = dist + thickness > kept: only inside candidates need a distance.
  const WindingNumber winding(skin);
  std::vector<std::uint8_t> inside;
  winding.classify(where, inside);
  std::vector<openvdb::Coord> inner_coords;
  std::vector<Vec3d> inner_where;
  for (std::size_t i = 0; i < coords.size(); ++i) {
    if (!inside[i]) continue;
    inner_coords.push_back(coords[i]);
    inner_where.push_back(where[i]);
  }
  log::debug("offset: {} candidates inside ({:.2f} s)", inner_coords.size(), seconds());
  const DistanceQuery distance(skin);
  std::vector<double> dist;
  distance.evaluate(inner_where, dist);
  log::debug("offset: exact distances ({:.2f} s)", seconds());

  const float background = static_cast<float>(kept);
  openvdb::FloatGrid::Ptr level = openvdb::FloatGrid::create(background);
  level->setTransform(xform->copy());
  level->setGridClass(openvdb::GRID_LEVEL_SET);
  auto acc = level->getAccessor();
  for (std::size_t i = 0; i < inner_coords.size(); ++i) {
    const double g = thickness - dist[i];
    if (std::abs(g) < kept) acc.setValue(inner_coords[i], static_cast<float>(g));
  }
  openvdb::tools::signedFloodFill(level->tree());

  std::vector<openvdb::Vec3s> out_points;
  std::vector<openvdb::Vec3I> out_triangles;
  std::vector<openvdb::Vec4I> out_quads;
  openvdb::tools::volumeToMesh(*level, out_points, out_triangles, out_quads, 0.0, 0.0);
  log::debug("offset: meshed, {} points ({:.2f} s)", out_points.size(), seconds());

  TriangleMesh result;
  result.source = skin.source.empty() ? "inward offset" : skin.source + " (inward offset)";
  result.vertices.reserve(out_points.size());
  for (const auto& p : out_points) result.vertices.push_back(origin + Vec3d{p.x(), p.y(), p.z()});
  for (const auto& t : out_triangles)
    result.triangles.push_back({std::int32_t(t[0]), std::int32_t(t[1]), std::int32_t(t[2])});
  for (const auto& q : out_quads) {
    result.triangles.push_back({std::int32_t(q[0]), std::int32_t(q[1]), std::int32_t(q[2])});
    result.triangles.push_back({std::int32_t(q[0]), std::int32_t(q[2]), std::int32_t(q[3])});
  }
  if (result.triangles.empty())
    throw GeometryError(skin.source, "thickness",
                        "inward offset by " + std::to_string(thickness) +
                            " m leaves nothing: the tissue is thinner than twice that everywhere");
  // Outward orientation: positive enclosed volume.
  double volume = 0;
  for (const auto& t : result.triangles)
    volume += dot(result.vertices[t[0]] - origin,
                  cross(result.vertices[t[1]] - origin, result.vertices[t[2]] - origin));
  if (volume < 0)
    for (auto& t : result.triangles) std::swap(t[1], t[2]);
  return result;
}

}  // namespace sinew::voxelizer
