// Inward offset surfaces: a sphere's offset is the concentric sphere of radius R - d.
#include "sinew/voxelizer/offset.hpp"

#include <gtest/gtest.h>
#include <omp.h>
#include <tbb/global_control.h>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/winding_number.hpp"
#include "test_shapes.hpp"

namespace sinew::voxelizer {
namespace {

using testing::kPi;
using testing::make_icosphere;

// 6 and 15 voxels deep (OpenVDB's band distances are least exact deep down).
TEST(InwardOffset, SphereGivesConcentricSphereWithinAVoxel) {
  const double R = 0.05, h = 0.002;
  const Vec3d centre{0.3, -0.2, 0.1};
  const TriangleMesh skin = make_icosphere(R, 4, centre);  // faces sag < 4e-5 m
  for (const double d : {0.012, 0.03}) {
    SCOPED_TRACE(d);
    TriangleMesh inner = inward_offset_surface(skin, d, h);
    ASSERT_FALSE(inner.triangles.empty());
    double worst = 0;
    for (const Vec3d& v : inner.vertices)
      worst = std::max(worst, std::abs(norm(v - centre) - (R - d)));
    EXPECT_LT(worst, h);
    std::printf("offset sphere R %g by %g: max |r - (R - d)| = %.3g voxel\n", R, d, worst / h);
    const MeshDiagnostics diag = clean_mesh(inner, 0.0);
    EXPECT_TRUE(diag.closed);
    EXPECT_EQ(diag.components, 1);
    EXPECT_EQ(diag.inconsistently_oriented_edges, 0);
    const double exact = 4.0 / 3 * kPi * std::pow(R - d, 3);
    EXPECT_NEAR(diag.enclosed_volume, exact, 0.03 * exact);  // outward: positive
  }
}

// A skin with a hole (a cap cut off): the winding number still knows the inside, so the offset
// exists and follows the sphere away from the hole.
TEST(InwardOffset, SkinWithAHoleStillHasAnInside) {
  const double R = 0.05, d = 0.01, h = 0.002;
  TriangleMesh skin = make_icosphere(R, 4);
  std::erase_if(skin.triangles, [&](const auto& t) {
    return skin.vertices[t[0]].z > 0.9 * R || skin.vertices[t[1]].z > 0.9 * R ||
           skin.vertices[t[2]].z > 0.9 * R;
  });
  ASSERT_GT(describe_mesh(skin).boundary_edges, 0);
  const TriangleMesh inner = inward_offset_surface(skin, d, h);
  ASSERT_FALSE(inner.triangles.empty());
  int below = 0;
  for (const Vec3d& v : inner.vertices) {
    if (v.z > 0.3 * R) continue;
    ++below;
    EXPECT_NEAR(norm(v), R - d, h);
  }
  EXPECT_GT(below, 100);
}

// OpenVDB runs on TBB, the exact distances and winding numbers on OpenMP: one thread of each
// and the default give the same mesh, bit for bit.
TEST(InwardOffset, IsIndependentOfThreadCount) {
  const TriangleMesh skin = make_icosphere(0.05, 4, {0.01, 0.02, -0.03});
  const TriangleMesh many = inward_offset_surface(skin, 0.01, 0.003);
  TriangleMesh one;
  {
    const tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
    const int saved = omp_get_max_threads();
    omp_set_num_threads(1);
    one = inward_offset_surface(skin, 0.01, 0.003);
    omp_set_num_threads(saved);
  }
  ASSERT_EQ(one.vertices.size(), many.vertices.size());
  ASSERT_EQ(one.triangles, many.triangles);
  for (std::size_t i = 0; i < one.vertices.size(); ++i) {
    ASSERT_EQ(one.vertices[i].x, many.vertices[i].x) << i;
    ASSERT_EQ(one.vertices[i].y, many.vertices[i].y) << i;
    ASSERT_EQ(one.vertices[i].z, many.vertices[i].z) << i;
  }
}

TEST(InwardOffset, RejectsBadArguments) {
  const TriangleMesh skin = make_icosphere(0.05, 2);
  EXPECT_THROW(inward_offset_surface(skin, 0.0, 0.001), GeometryError);
  EXPECT_THROW(inward_offset_surface(skin, 0.01, -1.0), GeometryError);
  EXPECT_THROW(inward_offset_surface(skin, std::nan(""), 0.001), GeometryError);
  EXPECT_THROW(inward_offset_surface(TriangleMesh{}, 0.01, 0.001), GeometryError);
  // Deeper than the radius: nothing is left.
  EXPECT_THROW(inward_offset_surface(skin, 0.06, 0.005), GeometryError);
}

}  // namespace
}  // namespace sinew::voxelizer
