// Mesh loading (formats, units, transforms, node transforms), cleaning and diagnostics.
#include "sinew/voxelizer/mesh.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <string>

#include "sinew/common/error.hpp"
#include "test_shapes.hpp"

namespace sinew::voxelizer {
namespace {

using testing::make_box;
using testing::make_icosphere;
using testing::TempDir;

// Every vertex of `got` is within tol of some vertex of `want`, and vice versa.
void expect_same_vertex_set(const TriangleMesh& got, const TriangleMesh& want, double tol) {
  auto near_any = [tol](const Vec3d& p, const TriangleMesh& m) {
    return std::any_of(m.vertices.begin(), m.vertices.end(),
                       [&](const Vec3d& q) { return norm(p - q) <= tol; });
  };
  for (const Vec3d& p : got.vertices)
    EXPECT_TRUE(near_any(p, want)) << p.x << ' ' << p.y << ' ' << p.z;
  for (const Vec3d& p : want.vertices)
    EXPECT_TRUE(near_any(p, got)) << p.x << ' ' << p.y << ' ' << p.z;
}

TEST(MeshTransform, RotationOrderIsXThenYThenZ) {
  // (0,1,0): Rx(90) -> (0,0,1), then Ry(90) -> (1,0,0). The other order would give (0,0,1).
  const Vec3d r = rotation_matrix({90, 90, 0}) * Vec3d{0, 1, 0};
  EXPECT_NEAR(r.x, 1, 1e-15);
  EXPECT_NEAR(r.y, 0, 1e-15);
  EXPECT_NEAR(r.z, 0, 1e-15);
  // Rz(90): x -> y (right-handed).
  const Vec3d z = rotation_matrix({0, 0, 90}) * Vec3d{1, 0, 0};
  EXPECT_NEAR(z.y, 1, 1e-15);
}

TEST(MeshTransform, UnitScaleRotateThenTranslate) {
  MeshTransform t;
  t.unit = LengthUnit::mm;
  t.scale = 2;
  t.rotate_deg = {0, 0, 90};
  t.translate = {1, 2, 3};
  // 10 mm * 2 = 0.02 m along x, rotated to y, then moved.
  const Vec3d p = apply_transform(t, {10, 0, 0});
  EXPECT_NEAR(p.x, 1, 1e-15);
  EXPECT_NEAR(p.y, 2.02, 1e-15);
  EXPECT_NEAR(p.z, 3, 1e-15);
  EXPECT_DOUBLE_EQ(metres_per_unit(LengthUnit::cm), 0.01);
  EXPECT_EQ(parse_length_unit("cm"), LengthUnit::cm);
  EXPECT_THROW(parse_length_unit("inch"), ConfigError);
}

TEST(LoadMesh, ObjPlyStlWithUnitsAndTransform) {
  TempDir dir("sinew_mesh_test");
  const TriangleMesh box = make_box({0, 0, 0}, {10, 20, 30});  // file units (cm below)
  testing::write_obj(box, dir.path / "box.obj");
  testing::write_ply(box, dir.path / "box.ply");
  testing::write_stl(box, dir.path / "box.stl");
  MeshTransform t;
  t.unit = LengthUnit::cm;
  t.scale = 0.5;
  t.rotate_deg = {30, -45, 60};
  t.translate = {0.1, -0.2, 0.3};
  TriangleMesh want = box;
  apply_transform(t, want);
  for (const char* name : {"box.obj", "box.ply", "box.stl"}) {
    SCOPED_TRACE(name);
    TriangleMesh m = load_mesh(dir.path / name, t);
    EXPECT_EQ(m.source, (dir.path / name).string());
    // assimp stores float coordinates: 1e-7 relative of 0.3 m.
    expect_same_vertex_set(m, want, 1e-7);
    const MeshDiagnostics d = clean_mesh(m, 0.0);
    EXPECT_EQ(d.vertices, 8);
    EXPECT_EQ(d.triangles, 12);
    EXPECT_TRUE(d.closed);
    EXPECT_EQ(d.components, 1);
    EXPECT_EQ(d.inconsistently_oriented_edges, 0);
    // 5 cm x 10 cm x 15 cm, rotation preserves volume and orientation.
    EXPECT_NEAR(d.enclosed_volume, 0.05 * 0.10 * 0.15, 1e-9);
    EXPECT_NEAR(d.area, 2 * (0.05 * 0.10 + 0.10 * 0.15 + 0.05 * 0.15), 1e-8);
  }
}

// Through assimp's exporter (save_mesh) and back: glTF (text and binary), COLLADA, FBX, binary
// PLY and STL.
TEST(LoadMesh, ExportedFormatsRoundTrip) {
  TempDir dir("sinew_mesh_test_gltf");
  const TriangleMesh sphere = make_icosphere(0.25, 2, {1, 2, 3});
  for (const char* name : {"s.glb", "s.gltf", "s.dae", "s.fbx", "s.ply", "s.stl"}) {
    SCOPED_TRACE(name);
    save_mesh(sphere, dir.path / name);
    TriangleMesh m = load_mesh(dir.path / name);
    expect_same_vertex_set(m, sphere, 1e-6);
    const MeshDiagnostics d = clean_mesh(m, 0.0);
    EXPECT_EQ(d.triangles, 320);
    EXPECT_TRUE(d.closed);
    EXPECT_NEAR(d.enclosed_volume, testing::signed_volume(sphere), 1e-6);
  }
}

// A glTF file written by hand: one mesh (a unit box) used by two nodes, the second translated
// by (10, 0, 0) and the child of a node scaled by 2: both instances must be merged with their
// node transforms applied.
TEST(LoadMesh, GltfNodeTransformsAndInstancesAreApplied) {
  TempDir dir("sinew_mesh_test_nodes");
  const TriangleMesh box = make_box({0, 0, 0}, {1, 1, 1});
  std::string bytes;
  auto put = [&bytes](const void* p, std::size_t n) {
    bytes.append(static_cast<const char*>(p), n);
  };
  for (const Vec3d& v : box.vertices) {
    const float f[3] = {float(v.x), float(v.y), float(v.z)};
    put(f, sizeof f);
  }
  for (const auto& t : box.triangles) {
    const std::uint16_t i[3] = {std::uint16_t(t[0]), std::uint16_t(t[1]), std::uint16_t(t[2])};
    put(i, sizeof i);
  }
  {
    std::ofstream bin(dir.path / "box.bin", std::ios::binary);
    bin.write(bytes.data(), std::streamsize(bytes.size()));
  }
  std::ofstream(dir.path / "scene.gltf") << R"({
 "asset": {"version": "2.0"},
 "scene": 0,
 "scenes": [{"nodes": [0, 1]}],
 "nodes": [{"mesh": 0},
           {"scale": [2, 2, 2], "children": [2]},
           {"mesh": 0, "translation": [10, 0, 0]}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
 "buffers": [{"uri": "box.bin", "byteLength": 168}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96},
                 {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 1]},
               {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]
})";
  ASSERT_EQ(bytes.size(), 168u);
  TriangleMesh m = load_mesh(dir.path / "scene.gltf");
  const MeshDiagnostics d = clean_mesh(m, 0.0);
  EXPECT_EQ(d.triangles, 24);
  EXPECT_EQ(d.components, 2);
  EXPECT_TRUE(d.closed);
  // Unit box plus a box of side 2 at (20, 0, 0): volume 1 + 8.
  EXPECT_NEAR(d.enclosed_volume, 9, 1e-6);
  const BoundingBox b = bounding_box(m);
  EXPECT_NEAR(b.hi.x, 22, 1e-6);
  EXPECT_NEAR(b.lo.x, 0, 1e-6);
}

TEST(LoadMesh, BadInputGivesTypedErrors) {
  TempDir dir("sinew_mesh_test_bad");
  EXPECT_THROW(load_mesh(dir.path / "missing.obj"), IoError);
  EXPECT_THROW(load_mesh(dir.path), IoError);
  std::ofstream(dir.path / "garbage.xyz123") << "this is not a mesh\n";
  EXPECT_THROW(load_mesh(dir.path / "garbage.xyz123"), FormatError);
  std::ofstream(dir.path / "points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_THROW(load_mesh(dir.path / "points.obj"), GeometryError);
  std::ofstream(dir.path / "nan.obj") << "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n";
  try {
    load_mesh(dir.path / "nan.obj");
    ADD_FAILURE() << "NaN coordinate accepted";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("nan.obj"), std::string::npos) << e.what();
    EXPECT_EQ(e.index(), 1);
  }
  MeshTransform zero;
  zero.scale = 0;
  testing::write_obj(make_box({0, 0, 0}, {1, 1, 1}), dir.path / "box.obj");
  EXPECT_THROW(load_mesh(dir.path / "box.obj", zero), GeometryError);
}

// Texture coordinates ride on the triangle corners: a seam (one position, two (u, v)) stays one
// vertex, each corner keeps its own (u, v) through a mirroring transform, cleaning (a degenerate
// triangle dropped) and the indexed table the model file stores.
TEST(LoadMesh, TextureCoordinatesFollowTheTriangleCorners) {
  TempDir dir("sinew_mesh_test_uv");
  // Two triangles sharing the edge 1-2 (seam: different vt on each side), and a degenerate one.
  std::ofstream(dir.path / "seam.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                          "vt 0 0\nvt 0.5 0\nvt 0 0.5\nvt 0.75 0.75\n"
                                          "vt 1 0.5\nvt 0.5 1\nvt 0.1 0.1\n"
                                          "f 1/1 2/2 3/3\nf 2/5 4/4 3/6\nf 1/7 1/7 2/7\n";
  TriangleMesh m = load_mesh(dir.path / "seam.obj");
  ASSERT_EQ(m.vertices.size(), 4u);  // the seam's vertices are not split
  ASSERT_EQ(m.corner_uvs.size(), m.triangles.size());
  auto uv_at = [&](const TriangleMesh& mesh, std::size_t t, const Vec3d& p) {
    for (int k = 0; k < 3; ++k)
      if (norm(mesh.vertices[static_cast<std::size_t>(mesh.triangles[t][k])] - p) < 1e-12)
        return mesh.corner_uvs[t][k];
    ADD_FAILURE() << "triangle " << t << " has no corner at " << p.x << ' ' << p.y;
    return std::array<double, 2>{-1, -1};
  };
  clean_mesh(m, 0.0);
  ASSERT_EQ(m.triangles.size(), 2u);  // the degenerate one and its texture corners are gone
  ASSERT_EQ(m.corner_uvs.size(), 2u);
  EXPECT_EQ(uv_at(m, 0, {1, 0, 0}), (std::array<double, 2>{0.5, 0}));
  EXPECT_EQ(uv_at(m, 1, {1, 0, 0}), (std::array<double, 2>{1, 0.5}));
  EXPECT_EQ(uv_at(m, 1, {1, 1, 0}), (std::array<double, 2>{0.75, 0.75}));
  const auto indexed = indexed_uvs(m);
  EXPECT_EQ(indexed.uvs.size(), 6u);
  ASSERT_EQ(indexed.triangles.size(), 2u);
  for (std::size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(indexed.uvs[static_cast<std::size_t>(indexed.triangles[t][k])], m.corner_uvs[t][k]);
  // A mirroring transform flips the triangles; each corner keeps its (u, v).
  MeshTransform mirror;
  mirror.scale = -1;
  TriangleMesh f = load_mesh(dir.path / "seam.obj", mirror);
  clean_mesh(f, 0.0);
  EXPECT_EQ(uv_at(f, 1, {-1, -1, 0}), (std::array<double, 2>{0.75, 0.75}));
  EXPECT_EQ(uv_at(f, 1, {0, -1, 0}), (std::array<double, 2>{0.5, 1}));
  // A file without texture coordinates has none.
  testing::write_obj(make_box({0, 0, 0}, {1, 1, 1}), dir.path / "box.obj");
  EXPECT_TRUE(load_mesh(dir.path / "box.obj").corner_uvs.empty());
}

TEST(CleanMesh, WeldsSoupAndCountsEverything) {
  // The box as a soup (each triangle with its own corners), plus: a collinear triangle, a
  // triangle with a repeated corner, and an exact duplicate triangle.
  const TriangleMesh box = make_box({0, 0, 0}, {1, 2, 3});
  TriangleMesh soup;
  for (const auto& t : box.triangles) {
    const auto base = std::int32_t(soup.vertices.size());
    for (int k = 0; k < 3; ++k) soup.vertices.push_back(box.vertices[t[k]]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  soup.triangles.push_back(soup.triangles[0]);  // duplicate
  soup.vertices.push_back({0.5, 0, 0});         // on the edge (0,0,0)-(1,0,0)
  const auto mid = std::int32_t(soup.vertices.size() - 1);
  soup.triangles.push_back({0, mid, 1});  // vertices 0 = (0,0,0), and (1,0,0) is a corner too
  soup.triangles.push_back({2, 2, 3});    // repeated corner
  // Find the soup indices of (0,0,0) and (1,0,0) for the collinear triangle.
  std::int32_t i000 = -1, i100 = -1;
  for (std::int32_t i = 0; i < mid; ++i) {
    if (norm(soup.vertices[i] - Vec3d{0, 0, 0}) == 0) i000 = i;
    if (norm(soup.vertices[i] - Vec3d{1, 0, 0}) == 0) i100 = i;
  }
  ASSERT_GE(i000, 0);
  ASSERT_GE(i100, 0);
  soup.triangles[soup.triangles.size() - 2] = {i000, mid, i100};

  TriangleMesh m = soup;
  const MeshDiagnostics d = clean_mesh(m, 0.0);
  EXPECT_EQ(d.duplicate_vertices_merged, 36 - 8);
  EXPECT_EQ(d.degenerate_triangles_removed, 2);
  EXPECT_EQ(d.duplicate_triangles_removed, 1);
  EXPECT_EQ(d.unreferenced_vertices_removed, 1);  // the edge midpoint
  EXPECT_EQ(d.vertices, 8);
  EXPECT_EQ(d.triangles, 12);
  EXPECT_EQ(d.boundary_edges, 0);
  EXPECT_EQ(d.non_manifold_edges, 0);
  EXPECT_EQ(d.inconsistently_oriented_edges, 0);
  EXPECT_EQ(d.components, 1);
  EXPECT_TRUE(d.closed);
  EXPECT_NEAR(d.area, 2 * (2 + 6 + 3), 1e-12);
  EXPECT_NEAR(d.enclosed_volume, 6, 1e-12);
  // The raw soup shares no box edge: the 36 box edges minus the 3 the duplicate covers twice
  // are boundary edges at least.
  const MeshDiagnostics raw = describe_mesh(soup);
  EXPECT_GE(raw.boundary_edges, 33);
  EXPECT_FALSE(raw.closed);
}

TEST(CleanMesh, WeldToleranceJoinsNearbyVerticesOnly) {
  TriangleMesh m = make_icosphere(1.0, 1);
  // Duplicate vertex 0, moved by 1e-9, used by the first triangle.
  m.vertices.push_back(m.vertices[0] + Vec3d{1e-9, 0, 0});
  for (int k = 0; k < 3; ++k)
    if (m.triangles[0][k] == 0) m.triangles[0][k] = std::int32_t(m.vertices.size() - 1);
  TriangleMesh exact = m;
  const MeshDiagnostics d0 = clean_mesh(exact, 0.0);
  EXPECT_EQ(d0.duplicate_vertices_merged, 0);
  EXPECT_EQ(d0.boundary_edges, 4);  // two edges at the split vertex, on both sides
  EXPECT_EQ(d0.non_manifold_edges, 0);
  EXPECT_FALSE(d0.closed);
  TriangleMesh welded = m;
  const MeshDiagnostics d1 = clean_mesh(welded, 1e-6);
  EXPECT_EQ(d1.duplicate_vertices_merged, 1);
  EXPECT_TRUE(d1.closed);
  EXPECT_EQ(d1.vertices, 42);
  EXPECT_THROW(clean_mesh(welded, -1.0), GeometryError);
}

TEST(CleanMesh, ReportsHolesFinsFlipsAndComponents) {
  TriangleMesh m = make_box({0, 0, 0}, {1, 1, 1});
  m.triangles.erase(m.triangles.begin(), m.triangles.begin() + 2);  // open the bottom face
  EXPECT_EQ(describe_mesh(m).boundary_edges, 4);
  // A fin on edge (1,1,1)-(0,1,1)... any existing edge: 6 -> 7 with a new vertex.
  m.vertices.push_back({0.5, 2, 2});
  m.triangles.push_back({6, 7, 8});
  MeshDiagnostics d = describe_mesh(m);
  EXPECT_EQ(d.non_manifold_edges, 1);
  EXPECT_EQ(d.boundary_edges, 4 + 2);
  // A flipped triangle: its three edges are traversed like their neighbours'.
  TriangleMesh f = make_box({0, 0, 0}, {1, 1, 1});
  std::swap(f.triangles[5][1], f.triangles[5][2]);
  EXPECT_EQ(describe_mesh(f).inconsistently_oriented_edges, 3);
  // Two separate boxes.
  TriangleMesh two = make_box({0, 0, 0}, {1, 1, 1});
  const TriangleMesh other = make_box({2, 0, 0}, {3, 1, 1});
  for (auto t : other.triangles) {
    for (auto& i : t) i += 8;
    two.triangles.push_back(t);
  }
  two.vertices.insert(two.vertices.end(), other.vertices.begin(), other.vertices.end());
  d = describe_mesh(two);
  EXPECT_EQ(d.components, 2);
  EXPECT_TRUE(d.closed);
  EXPECT_NEAR(d.enclosed_volume, 2, 1e-12);
}

}  // namespace
}  // namespace sinew::voxelizer
