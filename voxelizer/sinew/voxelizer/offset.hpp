#pragma once
// The inner surface an artist did not model: the surface lying at inward distance `thickness`
// below the skin,
//   S_d = { x : inside(x) and dist(x, skin) = d },
// the zero level of phi(x) + d on a regular grid, where phi is the signed distance (negative
// inside). dist is computed in an OpenVDB narrow band (meshToUnsignedDistanceField) and refined
// exactly (DistanceQuery) near S_d; the sign comes from the generalized winding number
// (WindingNumber, w >= 1/2), never from a flood fill, so skins with holes work. The level set is
// meshed with OpenVDB's volumeToMesh (no adaptivity), quads split into triangles, oriented
// outward (positive enclosed volume).
// Units: metres. Accuracy: vertices lie within about one voxel_size of S_d (tri-linear
// interpolation of the sampled field); features thinner than 2 * thickness vanish.
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

// skin: the outer surface (m), ideally closed and outward-oriented; holes are tolerated.
// thickness > 0 (m): inward offset distance. voxel_size > 0 (m): grid spacing of the level set.
// Throws GeometryError on an empty skin, non-positive or NaN thickness or voxel_size, a grid that
// would need more than 2^31 voxels across, or an empty result (thickness exceeds the tissue's
// half-thickness everywhere).
TriangleMesh inward_offset_surface(const TriangleMesh& skin, double thickness, double voxel_size);

}  // namespace sinew::voxelizer
