// Material volume fractions: the exact cube-plane volume, and concentric spheres standing in for
// skull and skin with the paper's layers (0.02 mm, 1.8 mm, the rest) against exact shell volumes.
#include "sinew/voxelizer/fractions.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "pipeline_test_util.hpp"
#include "sinew/voxelizer/primitives.hpp"
#include "sinew/voxelizer/self_intersection.hpp"

namespace sinew::voxelizer {
namespace {

using testing::material_volume;
using testing::run_spec;

double ball(double r) {
  return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

TEST(CubeFraction, ClosedFormsAndSymmetry) {
  // Axis-aligned plane: a linear fraction.
  EXPECT_NEAR(cube_fraction_below({1, 0, 0}, 0.3), 0.3, 1e-15);
  EXPECT_NEAR(cube_fraction_below({-1, 0, 0}, -0.7), 0.3, 1e-15);  // -x < -0.7  <=> x > 0.7
  // Corner tetrahedron: x + y + z < t for t <= 1 has volume t³/6.
  EXPECT_NEAR(cube_fraction_below({1, 1, 1}, 0.6), 0.036, 1e-15);
  // Half the cube by symmetry, for any normal, through the centre.
  EXPECT_NEAR(cube_fraction_below({0.3, -0.5, 0.8}, 0.3 * 0.5 - 0.5 * 0.5 + 0.8 * 0.5), 0.5, 1e-14);
  // 2-D case: x + y < 0.5 (z free) is a triangle of area 1/8.
  EXPECT_NEAR(cube_fraction_below({1, 1, 0}, 0.5), 0.125, 1e-15);
  EXPECT_EQ(cube_fraction_below({0, 0, 0}, 0.1), 1.0);
  EXPECT_EQ(cube_fraction_below({0, 0, 0}, -0.1), 0.0);
  EXPECT_EQ(cube_fraction_below({1, 2, 3}, -1), 0.0);
  EXPECT_EQ(cube_fraction_below({1, 2, 3}, 7), 1.0);
}

TEST(CubeFraction, MatchesSampling) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1), s(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3d n{s(rng), s(rng), s(rng)};
    const double tau = s(rng) * 1.5;
    // Midpoint rule on a 64³ grid: error O(1/64) at the plane, well under 0.02.
    int below = 0;
    const int m = 64;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j)
        for (int k = 0; k < m; ++k) {
          const Vec3d p{(i + 0.5) / m, (j + 0.5) / m, (k + 0.5) / m};
          below += dot(n, p) < tau ? 1 : 0;
        }
    EXPECT_NEAR(cube_fraction_below(n, tau), below / double(m * m * m), 0.02);
  }
}

// Skull r1 = 3 mm, skin r2 = 6 mm, layers 0.02 mm, 1.8 mm, rest; icospheres of 20,480 triangles
// (their volume differs from the sphere's by 0.1%, counted in the 1% budget).
std::string spheres_spec(double voxel_mm) {
  return R"(
units: mm
resolution: {voxel_size: )" +
         std::to_string(voxel_mm) + R"(}
outer: {sphere: {radius: 6}, subdivisions: 5}
inner: {sphere: {radius: 3}, subdivisions: 5}
)" + testing::kPaperLayers;
}

struct Shells {
  double sc, dermis, hypo;
};
Shells exact_shells() {
  return {ball(6) - ball(5.98), ball(5.98) - ball(4.18), ball(4.18) - ball(3)};
}

TEST(Fractions, ConcentricSpheresMatchExactShellVolumesAt1mm) {
  const auto r = run_spec(spheres_spec(1.0), "spheres.yaml");
  const Shells ex = exact_shells();
  const double mm3 = 1e-9;
  const double sc = material_volume(r.summary, "stratum_corneum") / mm3;
  const double d = material_volume(r.summary, "dermis") / mm3;
  const double hy = material_volume(r.summary, "hypodermis") / mm3;
  EXPECT_NEAR(sc / ex.sc, 1.0, 0.01) << "stratum corneum " << sc << " vs " << ex.sc;
  EXPECT_NEAR(d / ex.dermis, 1.0, 0.01) << "dermis " << d << " vs " << ex.dermis;
  EXPECT_NEAR(hy / ex.hypo, 1.0, 0.01) << "hypodermis " << hy << " vs " << ex.hypo;
  // The 0.02 mm layer is 50 times thinner than a voxel, yet it has its fraction in every voxel the
  // skin crosses, never a whole voxel.
  const auto& m = r.model;
  double max_sc = 0;
  for (std::size_t e = 0; e < m.element_count(); ++e) {
    for (auto q = m.material_offsets[e]; q < m.material_offsets[e + 1]; ++q) {
      if (m.materials[static_cast<std::size_t>(m.material_ids[static_cast<std::size_t>(q)])].name ==
          "stratum_corneum") {
        max_sc = std::max(max_sc, m.material_fractions[static_cast<std::size_t>(q)]);
      }
    }
  }
  EXPECT_GT(max_sc, 0.0);
  EXPECT_LT(max_sc, 0.05);
}

TEST(Fractions, RevoxelisingAgreesAndElementCountsScaleAsHToMinus3) {
  const double h = 1.0;
  std::vector<VoxelizeResult> runs;
  for (double f : {1.0, 0.5, 0.25}) runs.push_back(run_spec(spheres_spec(h * f), "spheres.yaml"));
  for (const char* name : {"stratum_corneum", "dermis", "hypodermis"}) {
    const double v0 = material_volume(runs[0].summary, name);
    for (std::size_t i = 1; i < runs.size(); ++i) {
      EXPECT_NEAR(material_volume(runs[i].summary, name) / v0, 1.0, 0.01)
          << name << " at h/" << (1 << i);
    }
  }
  // Elements: the tissue volume / h³ plus a boundary shell ∝ h⁻², so the ratio per halving tends
  // to 8 from below; fit the exponent between h/2 and h/4.
  const double e1 = static_cast<double>(runs[1].summary.elements);
  const double e2 = static_cast<double>(runs[2].summary.elements);
  const double exponent = std::log2(e2 / e1);
  EXPECT_NEAR(exponent, 3.0, 0.25) << e1 << " -> " << e2;
  // The shell's exact volume / h³ bounds the count from below.
  const double tissue = ball(6) - ball(3);
  EXPECT_GT(e2, tissue / std::pow(0.25, 3));
}

TEST(Fractions, RegionsOverrideLayersByPrecedence) {
  // A cube of side 10 mm with a 2 mm skin layer, an inner box region and a nested sphere region:
  // the later (sphere) wins where they overlap.
  const auto r = run_spec(R"(
units: mm
resolution: {voxel_size: 0.5}
outer: {box: {min: [0, 0, 0], max: [10, 10, 10]}}
materials:
  table:
    skin: {youngs_modulus: 1e5, poisson_ratio: 0.45, density: 1000}
    core: {youngs_modulus: 1e4, poisson_ratio: 0.45, density: 1000}
    ball: {youngs_modulus: 1e6, poisson_ratio: 0.45, density: 1000}
layers:
  - {material: skin, thickness: 2}
  - {material: core}
regions:
  - {name: slab, box: {min: [2, 2, 2], max: [8, 8, 5]}, material: ball}
  - {name: sphere, mesh: {sphere: {centre: [5, 5, 5], radius: 1.5}, subdivisions: 5}, material: skin}
)",
                          "box.yaml");
  const double mm3 = 1e-9;
  const double sphere = ball(1.5) * 0.99946;  // the icosphere's own volume (20,480 triangles)
  // skin = the 2 mm shell + the sphere, ball = the slab minus the sphere's lower half.
  EXPECT_NEAR(material_volume(r.summary, "skin") / mm3, 1000 - 216 + sphere, 0.01 * (784 + sphere));
  EXPECT_NEAR(material_volume(r.summary, "ball") / mm3, 6 * 6 * 3 - sphere / 2, 0.01 * 108);
  EXPECT_NEAR(material_volume(r.summary, "core") / mm3, 216 - 108 - sphere / 2, 0.01 * 100);
}

// Two overlapping boxes written as one mesh: closed, manifold, outward, a positive enclosed
// volume, yet folded over itself, and there the sign of the closest feature's pseudonormal is wrong
// (a point of box A just outside box B's face that lies inside A is called outside). The
// voxelizer detects the self-intersection and uses the winding number: the tissue is the union,
// A 20 mm cube and B 20 x 10 x 10 mm overlapping it by 10 x 10 x 10 mm: 8000 + 2000 - 1000 mm^3.
// One box, and the two boxes apart, do not intersect themselves.
TEST(SelfIntersection, FoldedMeshIsFilledByTheWindingNumber) {
  auto merged = [](const TriangleMesh& a, const TriangleMesh& b) {
    TriangleMesh m = a;
    const auto n = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
    for (auto t : b.triangles) m.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
    return m;
  };
  const TriangleMesh a = make_box({0, 0, 0}, {20, 20, 20}, 0);
  const TriangleMesh b = make_box({10, 5, 5}, {30, 15, 15}, 0);
  EXPECT_FALSE(self_intersects(a));
  EXPECT_FALSE(self_intersects(merged(a, make_box({40, 0, 0}, {50, 10, 10}, 0))));
  EXPECT_TRUE(self_intersects(merged(a, b)));

  const testing::TempDir dir;
  testing::write_obj(merged(a, b), dir / "folded.obj");
  const auto r = testing::run_spec(
      "units: mm\nresolution: {voxel_size: 2.5, max_subdivision: 2}\nouter: {path: " +
          (dir / "folded.obj").string() + ", unit: mm}\nmaterials: {table: {soft: " +
          "{youngs_modulus: 1.0e4, poisson_ratio: 0.45, density: 1000}}}\n" +
          "layers: [{material: soft}]\n",
      dir / "folded.yaml");
  EXPECT_NEAR(r.summary.tissue_volume * 1e9, 9000.0, 0.01 * 9000.0);
}

}  // namespace
}  // namespace sinew::voxelizer
