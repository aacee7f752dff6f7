// The geometry core on third-party meshes from ../shared/data/meshes (see its README for
// sources and licences: Stanford 3D Scanning Repository; Lee Perry-Smith, CC BY 3.0; MakerBot,
// CC BY-SA 3.0). Every test skips when the folder is absent.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/offset.hpp"
#include "sinew/voxelizer/winding_number.hpp"

namespace sinew::voxelizer {
namespace {

std::filesystem::path mesh_path(const std::string& name) {
  return std::filesystem::path(SINEW_SHARED_MESH_DIR) / name;
}

#define SKIP_IF_ABSENT(name)                     \
  if (!std::filesystem::exists(mesh_path(name))) \
  GTEST_SKIP() << "shared test mesh " << mesh_path(name) << " absent (../shared/data/meshes)"

// Regular grid of cell centres over a box, n[i] cells along axis i.
std::vector<Vec3d> grid_points(const BoundingBox& b, const std::array<int, 3>& n) {
  std::vector<Vec3d> p;
  p.reserve(std::size_t(n[0]) * n[1] * n[2]);
  const Vec3d e = b.hi - b.lo;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        p.push_back({b.lo.x + (i + 0.5) * e.x / n[0], b.lo.y + (j + 0.5) * e.y / n[1],
                     b.lo.z + (k + 0.5) * e.z / n[2]});
  return p;
}

// Crossing counts of axis-parallel rays with a mesh, for an inside reference that does not use
// the winding number: triangles binned by their projection, one bin per ray.
class RayCaster {
 public:
  RayCaster(const TriangleMesh& m, int axis) : m_(m), axis_(axis) {
    u_ = (axis + 1) % 3;
    v_ = (axis + 2) % 3;
    const BoundingBox b = bounding_box(m);
    lo_ = {b.lo[u_], b.lo[v_]};
    size_ = {(b.hi[u_] - b.lo[u_]) / kBins, (b.hi[v_] - b.lo[v_]) / kBins};
    bins_.resize(kBins * kBins);
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      double ulo = 1e300, uhi = -1e300, vlo = 1e300, vhi = -1e300;
      for (int k = 0; k < 3; ++k) {
        const Vec3d& x = m.vertices[m.triangles[t][k]];
        ulo = std::min(ulo, x[u_]);
        uhi = std::max(uhi, x[u_]);
        vlo = std::min(vlo, x[v_]);
        vhi = std::max(vhi, x[v_]);
      }
      for (int i = bin(ulo, 0); i <= bin(uhi, 0); ++i)
        for (int j = bin(vlo, 1); j <= bin(vhi, 1); ++j) bins_[i * kBins + j].push_back(int(t));
    }
  }
  // Crossings of the ray from p towards +axis (sign > 0) or -axis.
  int crossings(const Vec3d& p, int sign) const {
    int count = 0;
    for (int t : bins_[bin(p[u_], 0) * kBins + bin(p[v_], 1)]) {
      const auto& tri = m_.triangles[t];
      const Vec3d a = m_.vertices[tri[0]], b = m_.vertices[tri[1]], c = m_.vertices[tri[2]];
      // 2D barycentric coordinates of p's projection.
      const double d = (b[u_] - a[u_]) * (c[v_] - a[v_]) - (c[u_] - a[u_]) * (b[v_] - a[v_]);
      if (d == 0) continue;
      const double l1 = ((p[u_] - a[u_]) * (c[v_] - a[v_]) - (c[u_] - a[u_]) * (p[v_] - a[v_])) / d;
      const double l2 = ((b[u_] - a[u_]) * (p[v_] - a[v_]) - (p[u_] - a[u_]) * (b[v_] - a[v_])) / d;
      if (l1 < 0 || l2 < 0 || l1 + l2 > 1) continue;
      const double hit = a[axis_] + l1 * (b[axis_] - a[axis_]) + l2 * (c[axis_] - a[axis_]);
      if ((hit - p[axis_]) * sign > 0) ++count;
    }
    return count;
  }

 private:
  static constexpr int kBins = 64;
  int bin(double x, int which) const {
    const double s = which == 0 ? size_[0] : size_[1];
    const int i = int((x - (which == 0 ? lo_[0] : lo_[1])) / s);
    return std::clamp(i, 0, kBins - 1);
  }
  const TriangleMesh& m_;
  int axis_, u_, v_;
  std::array<double, 2> lo_, size_;
  std::vector<std::vector<int>> bins_;
};

TEST(RealMesh, ArmadilloIsClosedAndItsWindingVolumeMatches) {
  SKIP_IF_ABSENT("armadillo_100k.obj");
  TriangleMesh m = load_mesh(mesh_path("armadillo_100k.obj"));
  const MeshDiagnostics d = clean_mesh(m, 0.0);
  EXPECT_EQ(d.triangles, 99976);
  EXPECT_TRUE(d.closed);
  EXPECT_EQ(d.components, 1);
  EXPECT_EQ(d.boundary_edges, 0);
  EXPECT_EQ(d.non_manifold_edges, 0);
  EXPECT_EQ(d.inconsistently_oriented_edges, 0);
  EXPECT_GT(d.enclosed_volume, 0);
  // Volume from the fraction of grid cell centres with w >= 1/2.
  const BoundingBox b = bounding_box(m);
  const std::array<int, 3> n{60, 72, 55};
  const std::vector<Vec3d> points = grid_points(b, n);
  const WindingNumber w(m);
  std::vector<double> values;
  w.evaluate(points, values);
  std::int64_t inside = 0;
  for (double v : values) inside += v >= 0.5;
  const Vec3d e = b.hi - b.lo;
  const double volume = double(inside) / double(points.size()) * e.x * e.y * e.z;
  std::printf("armadillo: divergence volume %.6g, winding-grid volume %.6g (%+.3f%%, %dx%dx%d)\n",
              d.enclosed_volume, volume, 100 * (volume / d.enclosed_volume - 1), n[0], n[1], n[2]);
  EXPECT_NEAR(volume, d.enclosed_volume, 0.01 * d.enclosed_volume);
}

TEST(RealMesh, BunnyWithHolesHasAnInside) {
  SKIP_IF_ABSENT("stanford-bunny.obj");
  TriangleMesh m = load_mesh(mesh_path("stanford-bunny.obj"));
  const MeshDiagnostics d = clean_mesh(m, 0.0);
  EXPECT_EQ(d.boundary_edges, 223);
  EXPECT_FALSE(d.closed);
  EXPECT_EQ(d.non_manifold_edges, 0);
  EXPECT_EQ(d.components, 1);
  // Reference: grid points that five axis rays (+-x, +y, +-z; -y would leave through the holes
  // in the base) all call inside (odd crossings) or all call outside, and that lie farther than
  // 2 mm-equivalent (1.5% of the size) from the surface.
  const BoundingBox b = bounding_box(m);
  std::vector<Vec3d> points = grid_points(b, {30, 30, 30});
  for (Vec3d& p : points) p += Vec3d{1.234e-7, 2.345e-7, 3.456e-7};  // off grid-aligned edges
  const RayCaster rx(m, 0), ry(m, 1), rz(m, 2);
  const DistanceQuery dist(m);
  const WindingNumber w(m);
  const double margin = 0.015 * norm(b.hi - b.lo);
  std::int64_t in_ref = 0, in_ok = 0, out_ref = 0, out_ok = 0;
  for (const Vec3d& p : points) {
    const int votes[5] = {rx.crossings(p, 1) % 2, rx.crossings(p, -1) % 2, ry.crossings(p, 1) % 2,
                          rz.crossings(p, 1) % 2, rz.crossings(p, -1) % 2};
    const int odd = votes[0] + votes[1] + votes[2] + votes[3] + votes[4];
    if ((odd != 0 && odd != 5) || dist.distance(p) < margin) continue;
    if (odd == 5) {
      ++in_ref;
      in_ok += w.inside(p);
    } else {
      ++out_ref;
      out_ok += !w.inside(p);
    }
  }
  std::printf("bunny: %lld/%lld interior points inside, %lld/%lld exterior points outside\n",
              (long long)in_ok, (long long)in_ref, (long long)out_ok, (long long)out_ref);
  ASSERT_GT(in_ref, 1000);
  EXPECT_GT(double(in_ok) / double(in_ref), 0.99);
  EXPECT_GT(double(out_ok) / double(out_ref), 0.99);
}

TEST(RealMesh, MessySkullIsReportedAsItIs) {
  SKIP_IF_ABSENT("skull_a_makerbot_622390.stl");
  TriangleMesh m = load_mesh(mesh_path("skull_a_makerbot_622390.stl"));
  // As loaded (exactly equal positions joined): the README's counts.
  const MeshDiagnostics raw = describe_mesh(m);
  EXPECT_EQ(raw.triangles, 31355);
  EXPECT_EQ(raw.components, 3);
  EXPECT_EQ(raw.boundary_edges, 11);
  EXPECT_EQ(raw.non_manifold_edges, 25);
  EXPECT_FALSE(raw.closed);
  // Cleaning drops the 74 degenerate triangles; most non-manifold edges were theirs.
  const MeshDiagnostics d = clean_mesh(m, 0.0);
  EXPECT_EQ(d.degenerate_triangles_removed, 74);
  EXPECT_EQ(d.triangles, 31355 - 74);
  EXPECT_EQ(d.components, 3);
  EXPECT_EQ(d.boundary_edges, 11);
  EXPECT_EQ(d.non_manifold_edges, 7);
  std::printf(
      "skull_a: raw %lld inconsistently oriented edges; cleaned: %lld boundary, %lld "
      "non-manifold, %lld inconsistently oriented edges, volume %.4g\n",
      (long long)raw.inconsistently_oriented_edges, (long long)d.boundary_edges,
      (long long)d.non_manifold_edges, (long long)d.inconsistently_oriented_edges,
      d.enclosed_volume);
}

TEST(RealMesh, HeadScanInwardOffsetLiesAtTheThickness) {
  SKIP_IF_ABSENT("lee_perry_smith_head.obj");
  MeshTransform t;
  t.scale = 0.15 / 0.453;  // about 0.15 m ear to ear
  TriangleMesh skin = load_mesh(mesh_path("lee_perry_smith_head.obj"), t);
  ASSERT_TRUE(clean_mesh(skin, 0.0).closed);
  const double d = 0.006, h = 0.002;
  TriangleMesh inner = inward_offset_surface(skin, d, h);
  const DistanceQuery dist(skin);
  const WindingNumber w(skin);
  double worst = 0;
  for (const Vec3d& v : inner.vertices) {
    worst = std::max(worst, std::abs(dist.distance(v) - d));
    ASSERT_TRUE(w.inside(v));
  }
  std::printf("head offset: %zu triangles, max |dist - d| = %.3g voxel\n", inner.triangles.size(),
              worst / h);
  EXPECT_LT(worst, h);
  EXPECT_GT(clean_mesh(inner, 0.0).enclosed_volume, 0);
}

}  // namespace
}  // namespace sinew::voxelizer
