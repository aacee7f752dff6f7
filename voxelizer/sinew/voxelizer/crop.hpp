#pragma once
// The region of interest (docs/voxelizer.md, "crop"): a model cropped to the face, so that a bust's
// shoulders do not double it. A voxel is kept when its centre lies in the region (CropSpec: in the
// box and within the distance of one of the named points); the grid covers only the region's
// bounds, so the cropped part costs no fraction queries. The cut — every node of a kept element
// that is a corner of a voxel whose centre lies outside the region — is held rigid, as the tissue
// beyond it would hold it. Visual surfaces keep the triangles whose three vertices lie in the
// region. Lengths in m.
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/voxelizer/fractions.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/spec.hpp"

namespace sinew::voxelizer {

bool crop_contains(const CropSpec& crop, const Vec3d& p);

// The region's bounding box intersected with `bounds` (the skin's); throws GeometryError (field
// crop) when they do not overlap.
BoundingBox crop_bounds(const CropSpec& crop, const BoundingBox& bounds, const std::string& file);

// Drops the voxels of `fractions` whose centre lies outside the region (order kept); returns how
// many were dropped.
std::int64_t crop_fractions(VoxelFractions& fractions, const formats::VoxelGrid& grid,
                            const CropSpec& crop);

// The nodes on the cut (sorted): corners of a voxel whose centre lies outside the region.
std::vector<formats::Index> cut_nodes(const formats::Model& model, const CropSpec& crop);

// The triangles of `mesh` whose three vertices lie in the region, unused vertices dropped.
TriangleMesh crop_mesh(const TriangleMesh& mesh, const CropSpec& crop);

}  // namespace sinew::voxelizer
