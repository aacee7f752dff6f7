// The pipeline on real third-party meshes from ../shared/data/meshes (skipped when absent): the
// closed Stanford Armadillo, the Stanford Bunny with holes, the Lee Perry-Smith head scan with a
// derived inner surface, the messy MakerBot skull as the inner surface under an ellipsoidal skin.
// Credits: Stanford Computer Graphics Laboratory (Armadillo, Bunny); "Infinite" head scan by Lee
// Perry-Smith, CC BY 3.0, www.triplegangers.com; "Human Skull" by MakerBot (Thingiverse 622390),
// CC BY-SA 3.0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "pipeline_test_util.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/winding_number.hpp"

namespace sinew::voxelizer {
namespace {

std::filesystem::path mesh_path(const std::string& name) {
  return testing::shared_mesh_dir() / name;
}

#define SKIP_WITHOUT(name)                                                            \
  if (!std::filesystem::exists(mesh_path(name))) {                                    \
    GTEST_SKIP() << "no " << mesh_path(name) << " (../shared/data/meshes is absent)"; \
  }

double largest_extent(const TriangleMesh& m) {
  const auto b = bounding_box(m);
  return std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z});
}

// Enclosed volume after closing every hole with a fan around its rim's centroid (divergence
// theorem over the mesh plus the fans).
double hole_closed_volume(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  // Boundary edges: a directed edge without its reverse; the hole is bounded by the reversed edge.
  std::map<int, int> next;
  for (const auto& [e, c] : directed)
    if (!directed.count({e.second, e.first})) next[e.second] = e.first;
  auto det = [](const Vec3d& a, const Vec3d& b, const Vec3d& c) { return dot(a, cross(b, c)); };
  double v = 0;
  for (const auto& t : m.triangles) {
    v += det(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]) / 6;
  }
  std::map<int, bool> used;
  for (const auto& [start, unused] : next) {
    if (used[start]) continue;
    std::vector<int> loop;
    for (int a = start; !used[a] && next.count(a); a = next[a]) {
      used[a] = true;
      loop.push_back(a);
    }
    Vec3d c{0, 0, 0};
    for (int a : loop) c += m.vertices[a];
    c = (1.0 / loop.size()) * c;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = next[a];
      v += det(c, m.vertices[a], m.vertices[b]) / 6;
    }
  }
  return std::abs(v);
}

TEST(RealMeshes, ClosedArmadilloMatchesItsEnclosedVolume) {
  SKIP_WITHOUT("armadillo_100k.obj");
  auto mesh = load_mesh(mesh_path("armadillo_100k.obj"));
  const auto diag = clean_mesh(mesh, 0.0);
  ASSERT_TRUE(diag.closed);
  const double h = largest_extent(mesh) / 100;
  testing::TempDir dir;
  const auto r = testing::run_spec(
      "resolution: {voxel_size: " + std::to_string(h) +
          "}\nouter: " + mesh_path("armadillo_100k.obj").string() +
          "\nmaterials: {table: {rubber: {youngs_modulus: 1e5, poisson_ratio: 0.45, "
          "density: 1000}}}\nlayers: [{material: rubber}]\n",
      dir / "armadillo.yaml");
  const double exact = std::abs(diag.enclosed_volume);
  std::printf("armadillo: %lld elements, volume %.6g vs exact %.6g (%.3f%%)\n",
              static_cast<long long>(r.summary.elements), r.summary.tissue_volume, exact,
              100 * (r.summary.tissue_volume / exact - 1));
  EXPECT_NEAR(r.summary.tissue_volume / exact, 1.0, 0.01);
}

TEST(RealMeshes, BunnyWithHolesVoxelizesToASolid) {
  SKIP_WITHOUT("stanford-bunny.obj");
  auto mesh = load_mesh(mesh_path("stanford-bunny.obj"));
  const auto diag = clean_mesh(mesh, 0.0);
  ASSERT_GT(diag.boundary_edges, 0);
  const double closed = hole_closed_volume(mesh);
  const double h = largest_extent(mesh) / 60;
  testing::TempDir dir;
  const auto r =
      testing::run_spec("resolution: {voxel_size: " + std::to_string(h) +
                            "}\nouter: " + mesh_path("stanford-bunny.obj").string() +
                            "\nmaterials: {table: {fur: {youngs_modulus: 1e4, poisson_ratio: 0.45, "
                            "density: 1000}}}\nlayers: [{material: fur}]\n",
                        dir / "bunny.yaml");
  std::printf("bunny: %lld elements, volume %.6g vs hole-closed %.6g (%.3f%%)\n",
              static_cast<long long>(r.summary.elements), r.summary.tissue_volume, closed,
              100 * (r.summary.tissue_volume / closed - 1));
  EXPECT_NEAR(r.summary.tissue_volume / closed, 1.0, 0.03);
  // A solid, not a shell: most elements are whole voxels.
  std::int64_t full = 0;
  const auto& m = r.model;
  for (std::size_t e = 0; e < m.element_count(); ++e) {
    double sum = 0;
    for (auto q = m.material_offsets[e]; q < m.material_offsets[e + 1]; ++q)
      sum += m.material_fractions[static_cast<std::size_t>(q)];
    full += sum > 0.999 ? 1 : 0;
  }
  EXPECT_GT(full, static_cast<std::int64_t>(m.element_count()) / 2);
}

TEST(RealMeshes, HeadScanWithDerivedInnerSurfaceGivesLayeredTissue) {
  SKIP_WITHOUT("lee_perry_smith_head.obj");
  testing::TempDir dir;
  // Scaled to a real head (0.45 units ear to ear -> 0.15 m), 6 mm of tissue over a derived inner
  // surface, the paper's layers, rigid inside and sliding within 1 mm of that surface.
  const auto r = testing::run_spec(
      "units: mm\nresolution: {voxel_size: 2}\n"
      "outer: {path: " +
          mesh_path("lee_perry_smith_head.obj").string() +
          ", unit: m, scale: 0.3333}\n"
          "tissue_thickness: 6\n" +
          testing::kPaperLayers + R"(boundary:
  - {type: rigid, inside: true}
  - {type: sliding, within: 1.0}
)",
      dir / "head.yaml");
  double area = 0;
  for (const auto& m : r.summary.meshes)
    if (m.role == "outer") area = m.diagnostics.area;
  const double sc = testing::material_volume(r.summary, "stratum_corneum");
  const double dermis = testing::material_volume(r.summary, "dermis");
  const double hypo = testing::material_volume(r.summary, "hypodermis");
  std::printf(
      "head: %lld elements, skin area %.4g m^2, SC %.4g (area x 0.02 mm = %.4g), dermis "
      "%.4g (area x 1.8 mm = %.4g), hypodermis %.4g m^3, rigid %lld, sliding %lld\n",
      static_cast<long long>(r.summary.elements), area, sc, area * 0.02e-3, dermis, area * 1.8e-3,
      hypo, static_cast<long long>(r.summary.rigid_nodes),
      static_cast<long long>(r.summary.sliding_nodes));
  // Thin layers follow the skin: volume ≈ area × thickness (curvature changes it by a few %).
  EXPECT_NEAR(sc / (area * 0.02e-3), 1.0, 0.05);
  EXPECT_NEAR(dermis / (area * 1.8e-3), 1.0, 0.1);
  EXPECT_GT(hypo, 0.5 * area * 4.18e-3);
  EXPECT_GT(r.summary.rigid_nodes, 0);
  EXPECT_GT(r.summary.sliding_nodes, 0);
  EXPECT_EQ(r.summary.embedding_outside, 0);
}

// The messy skull (3 components, holes, non-manifold edges, degenerate slivers) scaled to a real
// skull (2.52 units -> 0.151 m wide) as the inner surface; the skin an ellipsoid around it: the
// ellipsoid through the skull's farthest vertex (in its bounding box's proportions) grown by 10 mm
// per axis. The paper's dermis and hypodermis, rigid inside the skull, sliding within one voxel
// of it. skull: the scaled mesh cleaned as the voxelizer cleans it.
struct SkullScene {
  std::string spec;
  TriangleMesh skull;
};

SkullScene skull_scene(double voxel_size_mm) {
  const auto path = mesh_path("skull_a_makerbot_622390.stl");
  MeshTransform t;
  t.scale = 0.06;
  SkullScene s;
  s.skull = load_mesh(path, t);
  clean_mesh(s.skull, 0.0);
  const auto b = bounding_box(s.skull);
  const Vec3d c = 0.5 * (b.lo + b.hi), e = 0.5 * (b.hi - b.lo);
  double q = 0;
  for (const auto& v : s.skull.vertices) {
    const Vec3d d = v - c;
    q = std::max(q, d.x * d.x / (e.x * e.x) + d.y * d.y / (e.y * e.y) + d.z * d.z / (e.z * e.z));
  }
  const Vec3d radii = std::sqrt(q) * e + Vec3d{0.01, 0.01, 0.01};
  char text[512];
  std::snprintf(text, sizeof text,
                "units: mm\nresolution: {voxel_size: %g}\n"
                "outer: {ellipsoid: {centre: [%.6f, %.6f, %.6f], radii: [%.6f, %.6f, %.6f]}, "
                "subdivisions: 5}\n"
                "materials: {preset: warburton2013}\n"
                "layers: [{material: dermis, thickness: 1.8}, {material: hypodermis}]\n"
                "boundary: [{type: rigid, inside: true}, {type: sliding, within: %g}]\n",
                voxel_size_mm, 1e3 * c.x, 1e3 * c.y, 1e3 * c.z, 1e3 * radii.x, 1e3 * radii.y,
                1e3 * radii.z, voxel_size_mm);
  s.spec = text + ("inner: {path: " + path.string() + ", unit: m, scale: 0.06}\n");
  return s;
}

TEST(RealMeshes, MessySkullGivesAUsableInnerSurface) {
  SKIP_WITHOUT("skull_a_makerbot_622390.stl");
  // The file as it is: the counts of ../shared/data/meshes/README.md.
  const auto raw = describe_mesh(load_mesh(mesh_path("skull_a_makerbot_622390.stl")));
  EXPECT_EQ(raw.components, 3);
  EXPECT_EQ(raw.boundary_edges, 11);
  EXPECT_EQ(raw.non_manifold_edges, 25);
  EXPECT_EQ(raw.triangles, 31355);

  const double h = 4e-3;
  const auto scene = skull_scene(1e3 * h);
  const auto& skull = scene.skull;
  const auto b = bounding_box(skull);
  const Vec3d e = 0.5 * (b.hi - b.lo);
  testing::TempDir dir;
  const auto r = testing::run_spec(scene.spec, dir / "skull.yaml");
  const auto& m = r.model;

  // The summary reports what cleaning found: the 74 degenerate triangles go, and with them 18 of
  // the 25 non-manifold edges (those the degenerate slivers shared); holes and components stay.
  double outer_volume = 0;
  MeshDiagnostics inner;
  for (const auto& mr : r.summary.meshes) {
    if (mr.role == "outer") outer_volume = mr.diagnostics.enclosed_volume;
    if (mr.role == "inner") inner = mr.diagnostics;
  }
  EXPECT_EQ(inner.degenerate_triangles_removed, 74);
  EXPECT_EQ(inner.triangles, 31355 - 74);
  EXPECT_EQ(inner.components, 3);
  EXPECT_EQ(inner.boundary_edges, 11);
  EXPECT_EQ(inner.non_manifold_edges, 7);
  EXPECT_FALSE(inner.closed);

  // The skull's volume by the winding number on a grid of 4 mm cells (midpoint rule); its holes
  // are a few edges wide, so the divergence-theorem volume of the summary must agree with it.
  const WindingNumber w(skull);
  const double g = 4e-3;
  const int nx = static_cast<int>(std::ceil(2 * e.x / g)),
            ny = static_cast<int>(std::ceil(2 * e.y / g)),
            nz = static_cast<int>(std::ceil(2 * e.z / g));
  std::vector<Vec3d> grid;
  grid.reserve(static_cast<std::size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        grid.push_back(b.lo + Vec3d{(i + 0.5) * g, (j + 0.5) * g, (k + 0.5) * g});
  std::vector<std::uint8_t> in;
  w.classify(grid, in);
  double skull_volume = 0;
  Vec3d centroid{0, 0, 0};
  for (std::size_t i = 0; i < grid.size(); ++i)
    if (in[i]) {
      skull_volume += g * g * g;
      centroid += grid[i];
    }
  centroid = (g * g * g / skull_volume) * centroid;

  const double expected = outer_volume - skull_volume;
  std::printf(
      "skull: %lld elements, %lld nodes, grid %dx%dx%d; skull volume %.6g m^3 (winding grid) vs "
      "%.6g (divergence); tissue %.6g vs skin %.6g - skull = %.6g (%.3f%%); rigid %lld, sliding "
      "%lld\n",
      static_cast<long long>(r.summary.elements), static_cast<long long>(r.summary.nodes),
      r.summary.dims[0], r.summary.dims[1], r.summary.dims[2], skull_volume, inner.enclosed_volume,
      r.summary.tissue_volume, outer_volume, expected,
      100 * (r.summary.tissue_volume / expected - 1), static_cast<long long>(r.summary.rigid_nodes),
      static_cast<long long>(r.summary.sliding_nodes));
  EXPECT_NEAR(skull_volume / inner.enclosed_volume, 1.0, 0.01);
  // Tissue = skin minus skull: the skull is inside, holes and all, and no tissue leaks into it.
  // 2%: at h = 4 mm the fractions of the voxels the skull crosses (teeth, orbits, thin arches a
  // few mm across) come from one linearisation per half-voxel leaf; the skull's volume is 55% of
  // the tissue's, so tissue leaking into it through a hole would show at once.
  EXPECT_NEAR(r.summary.tissue_volume / expected, 1.0, 0.02);

  // No element lies wholly inside the skull: a grid point inside it and farther than a voxel
  // diagonal from its triangles has its whole voxel inside, which must carry no tissue. And the
  // skull's centroid (deep in the cranium) is in no element.
  ASSERT_GT(w(centroid), 0.99);
  auto voxel_of = [&](const Vec3d& p) {
    return formats::Lattice{static_cast<std::int32_t>(std::floor((p.x - m.grid.origin[0]) / h)),
                            static_cast<std::int32_t>(std::floor((p.y - m.grid.origin[1]) / h)),
                            static_cast<std::int32_t>(std::floor((p.z - m.grid.origin[2]) / h))};
  };
  const std::set<formats::Lattice> elements(m.element_lattice.begin(), m.element_lattice.end());
  std::vector<Vec3d> deep;
  for (std::size_t i = 0; i < grid.size(); ++i)
    if (in[i]) deep.push_back(grid[i]);
  std::vector<double> d;
  DistanceQuery(skull).evaluate(deep, d);
  std::int64_t probed = 0, buried = 0;
  for (std::size_t i = 0; i < deep.size(); ++i) {
    if (d[i] <= std::sqrt(3.0) * h) continue;
    ++probed;
    buried += elements.count(voxel_of(deep[i]));
  }
  std::printf("skull: %lld voxels deep inside the skull probed, %lld carry tissue\n",
              static_cast<long long>(probed), static_cast<long long>(buried));
  EXPECT_GT(probed, 1000);
  EXPECT_EQ(buried, 0) << "of " << probed << " voxels deep inside the skull carry tissue";
  EXPECT_EQ(elements.count(voxel_of(centroid)), 0u)
      << "the voxel at the skull's centroid carries tissue";

  // Rigid nodes are inside the skull, sliding nodes within one voxel of it; both exist.
  EXPECT_GT(r.summary.rigid_nodes, 0);
  EXPECT_GT(r.summary.sliding_nodes, 0);
  std::int64_t rigid_outside = 0;
  for (const auto n : m.rigid_nodes) {
    const auto p = m.node_position(n);
    rigid_outside += w.inside(Vec3d{p[0], p[1], p[2]}) ? 0 : 1;
  }
  EXPECT_EQ(rigid_outside, 0);
  double max_rest = 0;
  for (const auto& s : m.sliding) max_rest = std::max(max_rest, s.rest_distance);
  EXPECT_LE(max_rest, h * (1 + 1e-9));

  // The model validates on writing and reading back.
  formats::write_model(m, (dir / "skull.h5").string());
  const auto back = formats::read_model((dir / "skull.h5").string());
  EXPECT_EQ(back.element_count(), m.element_count());
}

// Holes and non-manifold edges make the winding number do the work; the model must still not
// depend on the thread count (at 8 mm to keep it short: the same code paths, 1/4 of the crossed
// voxels).
TEST(RealMeshes, MessySkullModelIsDeterministic) {
  SKIP_WITHOUT("skull_a_makerbot_622390.stl");
  const auto scene = skull_scene(8);
  testing::TempDir dir;
  auto one = testing::run_spec(scene.spec, dir / "skull.yaml", 1);
  auto two = testing::run_spec(scene.spec, dir / "skull.yaml", 2);
  ASSERT_GT(one.model.element_count(), 0u);
  one.model.provenance.created.clear();
  two.model.provenance.created.clear();
  EXPECT_TRUE(one.model == two.model) << "the skull model differs between 1 and 2 threads";
}

}  // namespace
}  // namespace sinew::voxelizer
