// The pipeline on real third-party meshes from ../shared/data/meshes (skipped when absent): the
// closed Stanford Armadillo, the Stanford Bunny with holes, the Lee Perry-Smith head scan with a
// derived inner surface. Credits: Stanford Computer Graphics Laboratory (Armadillo, Bunny);
// "Infinite" head scan by Lee Perry-Smith, CC BY 3.0, www.triplegangers.com.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "pipeline_test_util.hpp"
#include "sinew/voxelizer/mesh.hpp"

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
          R"(tissue_thickness: 6
materials: {preset: warburton2013}
layers:
  - {material: stratum_corneum, thickness: 0.02}
  - {material: dermis, thickness: 1.8}
  - {material: hypodermis}
boundary:
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

}  // namespace
}  // namespace sinew::voxelizer
