#include "sinew/voxelizer/primitives.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include "sinew/common/icosphere.hpp"

namespace sinew::voxelizer {

TriangleMesh make_ellipsoid(const Vec3d& centre, const Vec3d& radii, int subdivisions) {
  UnitIcosphere sphere = make_unit_icosphere(subdivisions);
  TriangleMesh mesh;
  mesh.vertices.reserve(sphere.vertices.size());
  for (const auto& p : sphere.vertices) {
    mesh.vertices.push_back(
        {centre.x + radii.x * p.x, centre.y + radii.y * p.y, centre.z + radii.z * p.z});
  }
  mesh.triangles = std::move(sphere.triangles);
  mesh.source = "ellipsoid";
  return mesh;
}

TriangleMesh make_sphere(const Vec3d& centre, double radius, int subdivisions) {
  TriangleMesh m = make_ellipsoid(centre, {radius, radius, radius}, subdivisions);
  m.source = "sphere";
  return m;
}

TriangleMesh make_box(const Vec3d& lo, const Vec3d& hi, int subdivisions) {
  const int n = 1 << subdivisions;
  TriangleMesh mesh;
  mesh.source = "box";
  std::map<std::array<int, 3>, int> index;
  auto vertex = [&](std::array<int, 3> g) {
    const auto it = index.find(g);
    if (it != index.end()) return it->second;
    Vec3d p;
    for (int d = 0; d < 3; ++d) p[d] = lo[d] + (hi[d] - lo[d]) * g[d] / n;
    mesh.vertices.push_back(p);
    const int id = static_cast<int>(mesh.vertices.size()) - 1;
    index.emplace(g, id);
    return id;
  };
  // For each axis and side, a grid of quads; (u, v) axes chosen so (u × v) points outward.
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          std::array<int, 3> g00{}, g10{}, g11{}, g01{};
          for (auto* g : {&g00, &g10, &g11, &g01}) (*g)[axis] = side * n;
          g00[u] = a, g00[w] = b;
          g10[u] = a + 1, g10[w] = b;
          g11[u] = a + 1, g11[w] = b + 1;
          g01[u] = a, g01[w] = b + 1;
          const int i00 = vertex(g00), i10 = vertex(g10), i11 = vertex(g11), i01 = vertex(g01);
          if (side == 1) {
            mesh.triangles.push_back({i00, i10, i11});
            mesh.triangles.push_back({i00, i11, i01});
          } else {
            mesh.triangles.push_back({i00, i11, i10});
            mesh.triangles.push_back({i00, i01, i11});
          }
        }
      }
    }
  }
  return mesh;
}

TriangleMesh make_cylinder(const Vec3d& centre, double radius, double half_length,
                           int subdivisions) {
  const int around = 8 << subdivisions;
  const int rings =
      std::max(1, static_cast<int>(std::ceil(around * half_length / (std::numbers::pi * radius))));
  TriangleMesh mesh;
  mesh.source = "cylinder";
  for (int r = 0; r <= rings; ++r) {
    const double z = centre.z - half_length + 2.0 * half_length * r / rings;
    for (int a = 0; a < around; ++a) {
      const double phi = 2.0 * std::numbers::pi * a / around;
      mesh.vertices.push_back(
          {centre.x + radius * std::cos(phi), centre.y + radius * std::sin(phi), z});
    }
  }
  auto id = [&](int r, int a) { return r * around + (a % around); };
  for (int r = 0; r < rings; ++r) {
    for (int a = 0; a < around; ++a) {
      mesh.triangles.push_back({id(r, a), id(r, a + 1), id(r + 1, a + 1)});
      mesh.triangles.push_back({id(r, a), id(r + 1, a + 1), id(r + 1, a)});
    }
  }
  const int bottom = static_cast<int>(mesh.vertices.size());
  mesh.vertices.push_back({centre.x, centre.y, centre.z - half_length});
  const int top = bottom + 1;
  mesh.vertices.push_back({centre.x, centre.y, centre.z + half_length});
  for (int a = 0; a < around; ++a) {
    mesh.triangles.push_back({bottom, id(0, a + 1), id(0, a)});
    mesh.triangles.push_back({top, id(rings, a), id(rings, a + 1)});
  }
  return mesh;
}

}  // namespace sinew::voxelizer
