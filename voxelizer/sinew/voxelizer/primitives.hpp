#pragma once
// Closed, outward-oriented triangle meshes of simple shapes, for examples, tests and benchmarks
// (the spec's `sphere`, `ellipsoid`, `box`, `cylinder` mesh sources). Units: those of the
// arguments (the spec applies its transform afterwards).
#include "sinew/common/math.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

// Icosphere: the icosahedron, each triangle split into 4 `subdivisions` times, vertices pushed to
// the ellipsoid (x-c)²/rx² + (y-c)²/ry² + (z-c)²/rz² = 1. 20·4^subdivisions triangles.
TriangleMesh make_ellipsoid(const Vec3d& centre, const Vec3d& radii, int subdivisions);
TriangleMesh make_sphere(const Vec3d& centre, double radius, int subdivisions);
// Box [lo, hi] with each face split into n × n quads (n = 2^subdivisions), 2 triangles each.
TriangleMesh make_box(const Vec3d& lo, const Vec3d& hi, int subdivisions);
// Capped cylinder along z: radius, half_length; 8·2^subdivisions segments around, rings along z.
TriangleMesh make_cylinder(const Vec3d& centre, double radius, double half_length,
                           int subdivisions);

}  // namespace sinew::voxelizer
