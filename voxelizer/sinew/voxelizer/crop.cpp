#include "sinew/voxelizer/crop.hpp"

#include <algorithm>
#include <cstdint>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {

bool crop_contains(const CropSpec& crop, const Vec3d& p) {
  if (crop.box && !crop.box->contains(p)) return false;
  if (crop.points.empty()) return true;
  for (const auto& [name, q] : crop.points)
    if (squared_norm(p - q) <= crop.distance * crop.distance) return true;
  return false;
}

BoundingBox crop_bounds(const CropSpec& crop, const BoundingBox& bounds, const std::string& file) {
  BoundingBox b = bounds;
  auto clip = [&](const Vec3d& lo, const Vec3d& hi) {
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = std::max(b.lo[d], lo[d]);
      b.hi[d] = std::min(b.hi[d], hi[d]);
    }
  };
  if (crop.box) clip(crop.box->lo, crop.box->hi);
  if (!crop.points.empty()) {
    const Vec3d r{crop.distance, crop.distance, crop.distance};
    Vec3d lo = crop.points.front().second - r, hi = crop.points.front().second + r;
    for (const auto& [name, q] : crop.points) {
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], q[d] - crop.distance);
        hi[d] = std::max(hi[d], q[d] + crop.distance);
      }
    }
    clip(lo, hi);
  }
  for (int d = 0; d < 3; ++d) {
    if (!(b.lo[d] < b.hi[d]))
      throw GeometryError(file, crop.field,
                          "the region of interest does not overlap the outer surface");
  }
  return b;
}

std::int64_t crop_fractions(VoxelFractions& f, const formats::VoxelGrid& grid,
                            const CropSpec& crop) {
  return drop_voxels(f, grid, [&](const Vec3d& c) { return !crop_contains(crop, c); });
}

std::vector<formats::Index> cut_nodes(const formats::Model& model, const CropSpec& crop) {
  std::vector<formats::Index> cut;
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    const auto& l = model.node_lattice[n];
    bool on_cut = false;
    // The 8 voxels around the node have base corners l − {0, 1}³.
    for (int c = 0; c < 8 && !on_cut; ++c) {
      const formats::Lattice v{l[0] - (c & 1), l[1] - ((c >> 1) & 1), l[2] - ((c >> 2) & 1)};
      on_cut = !crop_contains(crop, voxel_centre(model.grid, v));
    }
    if (on_cut) cut.push_back(static_cast<formats::Index>(n));
  }
  return cut;
}

TriangleMesh crop_mesh(const TriangleMesh& mesh, const CropSpec& crop) {
  TriangleMesh out;
  out.source = mesh.source;
  std::vector<std::int32_t> remap(mesh.vertices.size(), -1);
  std::vector<char> inside(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    inside[v] = crop_contains(crop, mesh.vertices[v]) ? 1 : 0;
  for (const auto& t : mesh.triangles) {
    if (!inside[static_cast<std::size_t>(t[0])] || !inside[static_cast<std::size_t>(t[1])] ||
        !inside[static_cast<std::size_t>(t[2])])
      continue;
    std::array<std::int32_t, 3> nt{};
    for (int k = 0; k < 3; ++k) {
      auto& r = remap[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
      if (r < 0) {
        r = static_cast<std::int32_t>(out.vertices.size());
        out.vertices.push_back(
            mesh.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])]);
      }
      nt[static_cast<std::size_t>(k)] = r;
    }
    out.triangles.push_back(nt);
  }
  return out;
}

}  // namespace sinew::voxelizer
