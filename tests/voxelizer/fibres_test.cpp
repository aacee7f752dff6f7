// Muscle fibre fields: harmonic fibres (Choi & Blemker 2013) of a straight muscle follow its axis.
#include "sinew/voxelizer/fibres.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "pipeline_test_util.hpp"
#include "sinew/common/error.hpp"

namespace sinew::voxelizer {
namespace {

double angle_deg(const formats::Point& f, const Vec3d& axis) {
  const double c = std::abs(f[0] * axis.x + f[1] * axis.y + f[2] * axis.z) /
                   std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  return std::acos(std::min(1.0, c)) * 180.0 / std::numbers::pi;
}

TEST(HarmonicFibres, LatticeBarGivesTheExactAxis) {
  // A 20 × 3 × 3 bar of voxels, u = 0 at i = 0, u = 1 at i = 19: u is linear in i.
  std::vector<formats::Lattice> voxels;
  std::vector<DirichletTag> tags;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 20; ++i) {
        voxels.push_back({i, j, k});
        tags.push_back(i == 0 ? DirichletTag::origin
                              : (i == 19 ? DirichletTag::insertion : DirichletTag::free));
      }
  const auto r = harmonic_fibres(voxels, tags, "bar");
  for (std::size_t v = 0; v < voxels.size(); ++v) {
    EXPECT_NEAR(r.potential[v], voxels[v][0] / 19.0, 1e-8);
    EXPECT_NEAR(r.fibres[v].x, 1.0, 1e-8);
  }
  EXPECT_EQ(r.fallback, 0);
}

TEST(HarmonicFibres, MissingInsertionIsAnError) {
  std::vector<formats::Lattice> voxels{{0, 0, 0}, {1, 0, 0}};
  std::vector<DirichletTag> tags{DirichletTag::origin, DirichletTag::free};
  EXPECT_THROW(harmonic_fibres(voxels, tags, "m"), GeometryError);
}

TEST(HarmonicFibres, StraightMuscleAlignsWithItsAxisAwayFromItsEnds) {
  // A cylinder of radius 2.5 mm, 30 mm long, tilted in the x-z plane, inside a block of tissue;
  // origin and insertion are boxes around its two ends.
  const auto r = testing::run_spec(R"(
units: mm
resolution: {voxel_size: 0.75}
outer: {box: {min: [-25, -8, -25], max: [25, 8, 25]}}
materials: {preset: warburton2013}
layers: [{material: hypodermis}]
muscles:
  - name: straight
    mesh: {cylinder: {radius: 2.5, half_length: 15}, subdivisions: 3, rotate_deg: [0, 30, 0]}
    material: muscle
    fibres:
      type: harmonic
      origin: {surface: {sphere: {centre: [-7.5, 0, -12.99], radius: 0.5}, subdivisions: 3}, distance: 4}
      insertion: {surface: {sphere: {centre: [7.5, 0, 12.99], radius: 0.5}, subdivisions: 3}, distance: 4}
)",
                                   "muscle.yaml");
  ASSERT_EQ(r.model.muscles.size(), 1u);
  const auto& mu = r.model.muscles[0];
  ASSERT_GT(mu.elements.size(), 200u);
  // Axis after rotating z by 30° about y: (sin 30°, 0, cos 30°).
  const Vec3d axis{0.5, 0, std::sqrt(3.0) / 2};
  double worst = 0;
  int counted = 0;
  for (std::size_t j = 0; j < mu.elements.size(); ++j) {
    const auto p = r.model.element_lattice[static_cast<std::size_t>(mu.elements[j])];
    const Vec3d c{r.model.grid.origin[0] + (p[0] + 0.5) * r.model.grid.voxel_size,
                  r.model.grid.origin[1] + (p[1] + 0.5) * r.model.grid.voxel_size,
                  r.model.grid.origin[2] + (p[2] + 0.5) * r.model.grid.voxel_size};
    const double along = dot(c, axis) * 1e3;  // mm from the centre along the axis
    if (std::abs(along) > 9.0 || mu.fractions[j] < 0.5) continue;  // away from the ends
    worst = std::max(worst, angle_deg(mu.fibres[j], axis));
    ++counted;
  }
  std::printf("straight muscle: worst fibre angle %.2f degrees over %d voxels\n", worst, counted);
  EXPECT_GT(counted, 50);
  EXPECT_LT(worst, 5.0) << "worst fibre angle to the axis, degrees";
}

}  // namespace
}  // namespace sinew::voxelizer
