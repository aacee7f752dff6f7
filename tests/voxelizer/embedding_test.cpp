// Embedding visual vertices: element + natural coordinates reproduce the rest position.
#include "sinew/voxelizer/embedding.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pipeline_test_util.hpp"

namespace sinew::voxelizer {
namespace {

TEST(Embedding, SkinVerticesReproduceTheirRestPositions) {
  const auto r = testing::run_spec(R"(
units: mm
resolution: {voxel_size: 0.7}
outer: {ellipsoid: {radii: [8, 6, 5]}, subdivisions: 4}
inner: {sphere: {radius: 3}, subdivisions: 3}
materials: {preset: warburton2013}
layers: [{material: dermis, thickness: 1.8}, {material: hypodermis}]
visual:
  - {name: skin, surface: outer}
  - {name: skull, surface: inner}
)",
                                   "embed.yaml");
  ASSERT_EQ(r.model.surfaces.size(), 2u);
  for (const auto& s : r.model.surfaces) {
    ASSERT_EQ(s.embedding_element.size(), s.vertices.size());
    double worst = 0;
    for (std::size_t v = 0; v < s.vertices.size(); ++v) {
      const auto x = embedded_position(r.model, s.embedding_element[v], s.embedding_local[v]);
      const auto& p = s.vertices[v];
      const double err = std::hypot(x[0] - p[0], x[1] - p[1], x[2] - p[2]);
      const double size = std::hypot(p[0], p[1], p[2]);
      worst = std::max(worst, err / size);
      for (double xi : s.embedding_local[v]) {
        EXPECT_LE(std::abs(xi), 1.0);
      }
    }
    EXPECT_LT(worst, 1e-6) << s.name;
  }
  EXPECT_EQ(r.summary.embedding_outside, 0);
}

TEST(Embedding, PointsOutsideGoToTheNearestElementClamped) {
  formats::Model m;
  m.grid.voxel_size = 0.5;
  m.grid.dims = {4, 4, 4};
  m.element_lattice = {{1, 1, 1}, {2, 1, 1}};
  formats::build_lattice_topology(m);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  std::vector<formats::Point> pts;
  for (int i = 0; i < 100; ++i) pts.push_back({u(rng), 0.5 + 0.5 * u(rng) - 0.25, 0.75});
  pts.push_back({1.9, 0.75, 0.75});  // 0.4 beyond the +x face of element 1
  pts.push_back({-20.0, 0.6, 0.7});   // far outside the grid: element 0, 20.5 beyond its -x face
  const auto e = embed_points(m, pts);
  for (std::size_t i = 0; i + 2 < pts.size(); ++i) {
    const auto x = embedded_position(m, e.element[i], e.local[i]);
    EXPECT_NEAR(x[0], pts[i][0], 1e-12);
    EXPECT_NEAR(x[1], pts[i][1], 1e-12);
    EXPECT_NEAR(x[2], pts[i][2], 1e-12);
  }
  EXPECT_EQ(e.outside, 2);
  const std::size_t near = pts.size() - 2, far = pts.size() - 1;
  EXPECT_EQ(e.element[near], 1);
  EXPECT_DOUBLE_EQ(e.local[near][0], 1.0);
  EXPECT_EQ(e.element[far], 0);
  EXPECT_DOUBLE_EQ(e.local[far][0], -1.0);
  EXPECT_NEAR(e.max_outside_distance, 20.5, 1e-12);
}

}  // namespace
}  // namespace sinew::voxelizer
