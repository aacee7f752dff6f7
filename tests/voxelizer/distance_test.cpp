// Exact point-mesh distance (CGAL AABB tree) against brute force and closed forms.
#include "sinew/voxelizer/distance.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "sinew/common/error.hpp"
#include "test_shapes.hpp"

namespace sinew::voxelizer {
namespace {

using testing::make_icosphere;
using testing::make_torus;

TEST(ClosestPointOnTriangle, EachVoronoiRegion) {
  const Vec3d a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  auto expect_at = [&](const Vec3d& p, const Vec3d& want) {
    const Vec3d got = closest_point_on_triangle(p, a, b, c);
    EXPECT_NEAR(norm(got - want), 0, 1e-15) << p.x << ' ' << p.y << ' ' << p.z;
  };
  expect_at({0.2, 0.3, 5}, {0.2, 0.3, 0});  // face
  expect_at({-1, -1, 1}, a);                // vertex regions
  expect_at({2, -0.5, -1}, b);
  expect_at({-0.5, 3, 0}, c);
  expect_at({0.5, -2, 1}, {0.5, 0, 0});  // edge ab
  expect_at({-3, 0.4, 0}, {0, 0.4, 0});  // edge ca
  expect_at({1, 1, 2}, {0.5, 0.5, 0});   // edge bc
}

// Brute force over all triangles agrees with the tree to 1e-12 relative, and the reported
// triangle is one of the nearest.
TEST(DistanceQuery, AgreesWithBruteForce) {
  TriangleMesh torus = make_torus(1.0, 0.3, 64, 32);
  for (Vec3d& v : torus.vertices) v = v + Vec3d{0.05 * std::sin(7 * v.y), 0, 0.03 * v.x * v.y};
  const DistanceQuery q(torus);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int i = 0; i < 2000; ++i) {
    const Vec3d p = i % 4 == 0 ? torus.vertices[i % torus.vertices.size()] +
                                     0.01 * Vec3d{u(rng), u(rng), u(rng)}
                               : Vec3d{u(rng), u(rng), u(rng)};
    double best = std::numeric_limits<double>::infinity();
    for (const auto& t : torus.triangles) {
      const Vec3d c = closest_point_on_triangle(p, torus.vertices[t[0]], torus.vertices[t[1]],
                                                torus.vertices[t[2]]);
      best = std::min(best, norm(p - c));
    }
    const DistanceQuery::Hit hit = q.closest(p);
    ASSERT_NEAR(hit.distance, best, 1e-12 * std::max(best, 1e-3)) << i;
    ASSERT_NEAR(q.distance(p), best, 1e-12 * std::max(best, 1e-3)) << i;
    ASSERT_NEAR(norm(hit.point - p), hit.distance, 1e-15);
    const auto& t = torus.triangles[hit.triangle];
    const Vec3d on = closest_point_on_triangle(p, torus.vertices[t[0]], torus.vertices[t[1]],
                                               torus.vertices[t[2]]);
    ASSERT_NEAR(norm(on - p), best, 1e-12 * std::max(best, 1e-3)) << i;
  }
}

TEST(DistanceQuery, SphereDistanceIsRadialWithinTessellationError) {
  const double R = 0.1;
  const TriangleMesh sphere = make_icosphere(R, 5);  // sag of the flat faces below 5e-4 R
  const DistanceQuery q(sphere);
  std::vector<Vec3d> points;
  for (double r : {0.0, 0.02, 0.05, 0.09, 0.11, 0.2, 1.0})
    points.push_back({r * 0.6, r * 0.0, r * 0.8});
  std::vector<double> d;
  q.evaluate(points, d);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double exact = std::abs(norm(points[i]) - R);
    EXPECT_NEAR(d[i], exact, 5e-4 * R) << i;
    EXPECT_EQ(d[i], q.distance(points[i]));
  }
}

TEST(DistanceQuery, CollinearTrianglesCountAsSegments) {
  TriangleMesh m = testing::make_box({0, 0, 0}, {1, 1, 1});
  m.vertices.push_back({5, 0, 0});
  m.vertices.push_back({6, 0, 0});
  m.vertices.push_back({7, 0, 0});
  m.triangles.push_back({8, 10, 9});  // a collinear sliver from x = 5 to 7
  const DistanceQuery q(m);
  const DistanceQuery::Hit hit = q.closest({6.5, 1, 0});
  EXPECT_DOUBLE_EQ(hit.distance, 1.0);
  EXPECT_EQ(hit.triangle, 12);
  EXPECT_DOUBLE_EQ(q.distance({8, 0, 0}), 1.0);
  EXPECT_DOUBLE_EQ(q.distance({0.5, 0.5, 2}), 1.0);  // the box still counts
  EXPECT_THROW(DistanceQuery(TriangleMesh{}), GeometryError);
}

}  // namespace
}  // namespace sinew::voxelizer
