// Generalized winding number: closed forms, holes, soups, hierarchical vs brute force.
#include "sinew/voxelizer/winding_number.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <random>

#include "sinew/common/error.hpp"
#include "test_shapes.hpp"

namespace sinew::voxelizer {
namespace {

using testing::kPi;
using testing::make_box;
using testing::make_icosphere;
using testing::make_torus;

// Bound on |hierarchical - exact| at the default beta = 2 (measured up to 6e-3, see the header).
constexpr double kBeta2Error = 1e-2;

TEST(SolidAngle, OctantTriangleIsAnEighthOfTheSphere) {
  // From the origin the triangle (e_x, e_y, e_z) covers one octant: 4 pi / 8. Its normal
  // (1,1,1) points away from the origin, so the sign is positive.
  EXPECT_NEAR(triangle_solid_angle({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}), kPi / 2, 1e-14);
  EXPECT_NEAR(triangle_solid_angle({1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 0, 0}), -kPi / 2, 1e-14);
  // In the plane, on the triangle or beside it: nothing.
  EXPECT_EQ(triangle_solid_angle({1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0.2, 0.2, 0}), 0.0);
  EXPECT_EQ(triangle_solid_angle({1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {2, 2, 0}), 0.0);
}

TEST(WindingNumber, SphereInsideOutsideAndSurface) {
  const TriangleMesh sphere = make_icosphere(1.0, 4);  // 5120 triangles
  const WindingNumber w(sphere);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 300; ++i) {
    Vec3d dir{u(rng), u(rng), u(rng)};
    dir = (1.0 / norm(dir)) * dir;
    const double r_in = 0.95 * std::abs(u(rng)), r_out = 1.02 + 3 * std::abs(u(rng));
    EXPECT_NEAR(w(r_in * dir), 1.0, kBeta2Error);
    EXPECT_NEAR(w.exact(r_in * dir), 1.0, 1e-12);
    EXPECT_TRUE(w.inside(r_in * dir));
    EXPECT_NEAR(w(r_out * dir), 0.0, kBeta2Error);
    EXPECT_NEAR(w.exact(r_out * dir), 0.0, 1e-12);
    EXPECT_FALSE(w.inside(r_out * dir));
  }
  // On a face (its centroid): exactly half.
  for (int t = 0; t < 5120; t += 97) {
    const auto& tri = sphere.triangles[t];
    const Vec3d c =
        (1.0 / 3.0) * (sphere.vertices[tri[0]] + sphere.vertices[tri[1]] + sphere.vertices[tri[2]]);
    EXPECT_NEAR(w(c), 0.5, kBeta2Error);
    EXPECT_NEAR(w.exact(c), 0.5, 1e-12);
  }
}

TEST(WindingNumber, TorusHoleIsOutside) {
  const TriangleMesh torus = make_torus(1.0, 0.3, 96, 48);
  const WindingNumber w(torus, 4.0);
  EXPECT_NEAR(w({0, 0, 0}), 0.0, 1e-3);       // the hole
  EXPECT_NEAR(w({0, 0, 0.5}), 0.0, 1e-3);     // above the hole
  EXPECT_NEAR(w({1.0, 0, 0}), 1.0, 1e-3);     // tube centre
  EXPECT_NEAR(w({0, -1.2, 0.1}), 1.0, 1e-3);  // in the tube
  EXPECT_NEAR(w({0, 1.35, 0}), 0.0, 1e-3);    // outside the tube
}

TEST(WindingNumber, OpenBoxMatchesSolidAngleOfTheMissingFace) {
  // Cube [-1, 1]^3 without its top face (z = 1). Below the hole, w = 1 - Omega/(4 pi); above
  // it, w = Omega/(4 pi), where Omega = 4 atan(a b / (d sqrt(a^2 + b^2 + d^2))) is the solid
  // angle of the 2 x 2 face seen from distance d on its axis (a = b = 1).
  TriangleMesh box = make_box({-1, -1, -1}, {1, 1, 1});
  // make_box's faces in order: z-lo, z-hi, ...: drop the z-hi quad (triangles 2 and 3).
  box.triangles.erase(box.triangles.begin() + 2, box.triangles.begin() + 4);
  const WindingNumber w(box);
  auto omega = [](double d) { return 4 * std::atan(1.0 / (d * std::sqrt(2 + d * d))); };
  EXPECT_NEAR(omega(1.0) / (4 * kPi), 1.0 / 6, 1e-15);  // a face seen from the centre
  auto expect_w = [&w](const Vec3d& p, double want) {
    EXPECT_NEAR(w.exact(p), want, 1e-12) << p.z;
    EXPECT_NEAR(w(p), want, kBeta2Error) << p.z;
    EXPECT_EQ(w.inside(p), want >= 0.5) << p.z;
  };
  for (double z : {-0.5, 0.0, 0.5, 0.9, 0.99}) expect_w({0, 0, z}, 1 - omega(1 - z) / (4 * kPi));
  for (double z : {1.01, 1.1, 1.5, 3.0}) expect_w({0, 0, z}, omega(z - 1) / (4 * kPi));
  EXPECT_NEAR(w.exact({0, 0, 1}), 0.5, 1e-12);  // in the hole
}

TEST(WindingNumber, OverlappingSoupAndFlippedComponent) {
  // Two overlapping spheres: 2 in the overlap, 1 in either; a flipped sphere counts -1.
  TriangleMesh soup = make_icosphere(1.0, 3);
  const TriangleMesh b = make_icosphere(1.0, 3, {1, 0, 0});
  const auto base = std::int32_t(soup.vertices.size());
  soup.vertices.insert(soup.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) soup.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  const WindingNumber w(soup, 4.0);
  EXPECT_NEAR(w({0.5, 0, 0}), 2.0, 1e-3);
  EXPECT_NEAR(w({-0.5, 0, 0}), 1.0, 1e-3);
  EXPECT_NEAR(w({1.5, 0, 0}), 1.0, 1e-3);
  EXPECT_TRUE(w.inside({0.5, 0, 0}));
  TriangleMesh flipped = make_icosphere(1.0, 3);
  for (auto& t : flipped.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(WindingNumber(flipped)({0.1, 0.2, 0.3}), -1.0, kBeta2Error);
}

// The acceptance check for the hierarchy, on random points in and around a 20,480-triangle
// sphere with bumps and a torus, plus points within 1e-3 of their surfaces: at beta = 4 the
// hierarchical value is within 1e-3 of the brute-force sum everywhere; at the default beta = 2
// within 1e-2; and classify() agrees with the exact w >= 1/2 wherever |w - 1/2| > 1e-3.
TEST(WindingNumber, HierarchicalAgreesWithBruteForce) {
  TriangleMesh bumpy = make_icosphere(1.0, 5);
  for (Vec3d& v : bumpy.vertices)
    v = (1 + 0.1 * std::sin(5 * v.x) * std::sin(4 * v.y) * std::sin(3 * v.z)) * v;
  const TriangleMesh torus = make_torus(0.6, 0.25, 96, 48);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  double worst2 = 0, worst4 = 0;
  for (const TriangleMesh* m : std::array<const TriangleMesh*, 2>{&bumpy, &torus}) {
    const WindingNumber w2(*m), w4(*m, 4.0);
    std::vector<Vec3d> points(1000);
    for (auto& p : points) p = {u(rng), u(rng), u(rng)};
    for (int i = 0; i < 250; ++i) {
      const Vec3d& v = m->vertices[(i * 7919) % m->vertices.size()];
      points.push_back(v + Vec3d{1e-3 * u(rng), 1e-3 * u(rng), 1e-3 * u(rng)});
    }
    std::vector<double> fast2, fast4;
    std::vector<std::uint8_t> in;
    w2.evaluate(points, fast2);
    w4.evaluate(points, fast4);
    w2.classify(points, in);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double exact = w2.exact(points[i]);
      worst2 = std::max(worst2, std::abs(fast2[i] - exact));
      worst4 = std::max(worst4, std::abs(fast4[i] - exact));
      ASSERT_LT(std::abs(fast4[i] - exact), 1e-3) << i;
      ASSERT_LT(std::abs(fast2[i] - exact), kBeta2Error) << i;
      if (std::abs(exact - 0.5) > 1e-3) {
        ASSERT_EQ(in[i] == 1, exact >= 0.5) << i;
      }
    }
  }
  RecordProperty("max_abs_diff_beta2", std::to_string(worst2));
  RecordProperty("max_abs_diff_beta4", std::to_string(worst4));
  std::printf("hierarchical vs brute force: max |diff| = %.3g at beta 2, %.3g at beta 4\n", worst2,
              worst4);
}

TEST(WindingNumber, EvaluateIsIndependentOfThreadCount) {
  const TriangleMesh torus = make_torus(1.0, 0.3, 64, 32);
  const WindingNumber w(torus);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<Vec3d> points(5000);
  for (auto& p : points) p = {u(rng), u(rng), u(rng)};
  std::vector<double> one, two;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  w.evaluate(points, one);
  omp_set_num_threads(3);
  w.evaluate(points, two);
  omp_set_num_threads(saved);
  ASSERT_EQ(one.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(one[i], two[i]) << i;  // bitwise
    ASSERT_EQ(one[i], w(points[i])) << i;
  }
}

TEST(WindingNumber, RejectsEmptyMeshAndBadBeta) {
  EXPECT_THROW(WindingNumber(TriangleMesh{}), GeometryError);
  EXPECT_THROW(WindingNumber(make_box({0, 0, 0}, {1, 1, 1}), 1.0), GeometryError);
}

}  // namespace
}  // namespace sinew::voxelizer
