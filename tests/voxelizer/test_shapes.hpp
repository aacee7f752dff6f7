#pragma once
// Closed, outward-oriented test meshes with known geometry (cube, icosphere, torus), and plain
// text writers for OBJ, ASCII PLY and ASCII STL, written independently of assimp so that loading
// them tests the importer. Shared by the voxelizer's geometry tests.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "sinew/voxelizer/primitives.hpp"

#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer::testing {

inline constexpr double kPi = 3.14159265358979323846;

// Axis-aligned box [lo, hi], 8 vertices, 12 triangles, outward.
inline TriangleMesh make_box(const Vec3d& lo, const Vec3d& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  // Faces as quads (outward, counter-clockwise), split into two triangles each.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  m.source = "box";
  return m;
}

// Icosahedron subdivided `levels` times, vertices on the sphere |x - centre| = radius;
// 20 * 4^levels triangles, outward.
inline TriangleMesh make_icosphere(double radius, int levels, const Vec3d& centre = {0, 0, 0}) {
  return make_sphere(centre, radius, levels);
}

// Torus around the z axis: tube centre circle radius R, tube radius r; nu x nv quads.
inline TriangleMesh make_torus(double R, double r, int nu, int nv) {
  TriangleMesh m;
  for (int i = 0; i < nu; ++i) {
    const double u = 2 * kPi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double w = 2 * kPi * j / nv;
      m.vertices.push_back({(R + r * std::cos(w)) * std::cos(u),
                            (R + r * std::cos(w)) * std::sin(u), r * std::sin(w)});
    }
  }
  auto id = [&](int i, int j) { return std::int32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  m.source = "torus";
  return m;
}

// Enclosed volume of a mesh (divergence theorem), for checks.
inline double signed_volume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles)
    v += dot(m.vertices[t[0]], cross(m.vertices[t[1]], m.vertices[t[2]])) / 6.0;
  return v;
}

inline void write_obj(const TriangleMesh& m, const std::filesystem::path& p) {
  std::ofstream f(p);
  f.precision(17);
  for (const auto& v : m.vertices) f << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& t : m.triangles)
    f << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
}

inline void write_ply(const TriangleMesh& m, const std::filesystem::path& p) {
  std::ofstream f(p);
  f.precision(17);
  f << "ply\nformat ascii 1.0\nelement vertex " << m.vertices.size()
    << "\nproperty double x\nproperty double y\nproperty double z\nelement face "
    << m.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : m.vertices) f << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& t : m.triangles) f << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
}

inline void write_stl(const TriangleMesh& m, const std::filesystem::path& p) {
  std::ofstream f(p);
  f.precision(17);
  f << "solid test\n";
  for (const auto& t : m.triangles) {
    const Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
    Vec3d n = cross(b - a, c - a);
    n = (1.0 / norm(n)) * n;
    f << " facet normal " << n.x << ' ' << n.y << ' ' << n.z << "\n  outer loop\n";
    for (const Vec3d& x : {a, b, c}) f << "   vertex " << x.x << ' ' << x.y << ' ' << x.z << '\n';
    f << "  endloop\n endfacet\n";
  }
  f << "endsolid test\n";
}

// A fresh empty directory under the system temp folder, removed by the destructor.
struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name) {
    path = std::filesystem::temp_directory_path() /
           (name + "_" + std::to_string(reinterpret_cast<std::uintptr_t>(this)));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

}  // namespace sinew::voxelizer::testing
