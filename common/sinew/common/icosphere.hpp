#pragma once
// The unit icosphere, shared by the voxelizer's sphere and ellipsoid primitives and by the
// simulator's test meshes (the simulator may not depend on the voxelizer; both depend on common).
#include <array>
#include <cstdint>
#include <vector>

#include "sinew/common/math.hpp"

namespace sinew {

struct UnitIcosphere {
  std::vector<Vec3d> vertices;                         // on the unit sphere about the origin
  std::vector<std::array<std::int32_t, 3>> triangles;  // counter-clockwise seen from outside
};

// An icosahedron inscribed in the unit sphere, each triangle split into four `levels` times (at its
// edge midpoints, pushed out onto the sphere): 20·4^levels triangles, 10·4^levels + 2 vertices.
UnitIcosphere make_unit_icosphere(int levels);

}  // namespace sinew
