#pragma once
// Analytic test meshes shared by the simulator's tests. (The simulator may not depend on the
// voxelizer: its sphere comes from common, as the voxelizer's primitives do.)
#include <array>
#include <cstdint>
#include <vector>

#include "sinew/common/icosphere.hpp"

namespace sinew::simulator::testing {

struct TriangleSoup {
  std::vector<std::array<double, 3>> vertices;         // m
  std::vector<std::array<std::int32_t, 3>> triangles;  // counter-clockwise seen from outside
};

// Icosphere: the unit icosphere of `levels` levels (20·4^levels triangles) scaled to the sphere of
// radius r about c.
inline TriangleSoup make_icosphere(int levels, double r, std::array<double, 3> c = {0, 0, 0}) {
  const UnitIcosphere sphere = make_unit_icosphere(levels);
  TriangleSoup s;
  for (const auto& p : sphere.vertices)
    s.vertices.push_back({c[0] + r * p.x, c[1] + r * p.y, c[2] + r * p.z});
  s.triangles = sphere.triangles;
  return s;
}

}  // namespace sinew::simulator::testing
