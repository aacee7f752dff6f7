// Throughput of the voxelizer's geometry queries: generalized winding number (hierarchical, at
// beta 2 and 4) and exact distance (CGAL AABB tree), on the Armadillo (100k triangles; skipped
// when ../shared/data/meshes is absent) and a synthetic bumpy torus of 115,200 triangles.
// Queries: 50k points (--points) uniform in the bounding box ("box"), and as many within 1% of the
// box diagonal of the surface ("near"). Prints one table; times are medians of 3 runs.
//
//   build/<dir>/bench/voxelizer_geometry_bench [--points N]
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/winding_number.hpp"

using namespace sinew;
using namespace sinew::voxelizer;

namespace {

double seconds_of(const std::function<void()>& f, int repeats = 3) {
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto a = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

TriangleMesh bumpy_torus(int nu, int nv) {
  const double pi = 3.14159265358979323846, R = 1.0, r = 0.35;
  TriangleMesh m;
  for (int i = 0; i < nu; ++i) {
    const double u = 2 * pi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double w = 2 * pi * j / nv;
      const double rr = r * (1 + 0.15 * std::sin(7 * u) * std::cos(5 * w));
      m.vertices.push_back({(R + rr * std::cos(w)) * std::cos(u),
                            (R + rr * std::cos(w)) * std::sin(u), rr * std::sin(w)});
    }
  }
  auto id = [&](int i, int j) { return std::int32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  m.source = "bumpy torus (synthetic)";
  return m;
}

void run(const std::string& name, TriangleMesh mesh, std::size_t n_points) {
  clean_mesh(mesh, 0.0);
  const BoundingBox b = bounding_box(mesh);
  const Vec3d e = b.hi - b.lo;
  const double diag = norm(e);
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0, 1), s(-1, 1);
  std::vector<Vec3d> box(n_points), near(n_points);
  for (auto& p : box) p = {b.lo.x + u(rng) * e.x, b.lo.y + u(rng) * e.y, b.lo.z + u(rng) * e.z};
  for (std::size_t i = 0; i < n_points; ++i) {
    const auto& t = mesh.triangles[(i * 2654435761u) % mesh.triangles.size()];
    const double a = u(rng), c = u(rng) * (1 - a);
    const Vec3d on = mesh.vertices[t[0]] + a * (mesh.vertices[t[1]] - mesh.vertices[t[0]]) +
                     c * (mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    near[i] = on + 0.01 * diag * Vec3d{s(rng), s(rng), s(rng)};
  }
  std::vector<double> out;
  const int threads = omp_get_max_threads();
  auto row = [&](const char* what, const char* set, double build, const std::function<void()>& f,
                 std::size_t n) {
    omp_set_num_threads(1);
    const double t1 = seconds_of(f);
    omp_set_num_threads(threads);
    const double tn = seconds_of(f);
    std::printf("| %-26s | %9lld | %-24s | %-4s | %8.3f | %10.3g | %10.3g |\n", name.c_str(),
                (long long)mesh.triangles.size(), what, set, build, n / t1, n / tn);
  };
  for (double beta : {2.0, 4.0}) {
    double build = 0;
    std::unique_ptr<WindingNumber> w;
    build = seconds_of([&] { w = std::make_unique<WindingNumber>(mesh, beta); }, 1);
    const std::string what = "winding number, beta " + std::to_string(int(beta));
    row(
        what.c_str(), "box", build, [&] { w->evaluate(box, out); }, box.size());
    row(
        what.c_str(), "near", build, [&] { w->evaluate(near, out); }, near.size());
  }
  std::unique_ptr<DistanceQuery> d;
  const double build = seconds_of([&] { d = std::make_unique<DistanceQuery>(mesh); }, 1);
  row(
      "distance (CGAL AABB)", "box", build, [&] { d->evaluate(box, out); }, box.size());
  row(
      "distance (CGAL AABB)", "near", build, [&] { d->evaluate(near, out); }, near.size());
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t n = 50000;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--points") == 0) n = std::strtoull(argv[i + 1], nullptr, 10);
  try {
    std::printf("voxelizer geometry queries: %zu points per set, %d threads (OpenMP)\n\n", n,
                omp_get_max_threads());
    std::printf("| %-26s | %9s | %-24s | %-4s | %8s | %10s | %10s |\n", "mesh", "triangles",
                "query", "set", "build s", "q/s 1 thr", "q/s all");
    std::printf("|%s|%s|%s|%s|%s|%s|%s|\n", std::string(28, '-').c_str(),
                std::string(11, '-').c_str(), std::string(26, '-').c_str(),
                std::string(6, '-').c_str(), std::string(10, '-').c_str(),
                std::string(12, '-').c_str(), std::string(12, '-').c_str());
    const std::filesystem::path armadillo =
        std::filesystem::path(SINEW_SHARED_MESH_DIR) / "armadillo_100k.obj";
    if (std::filesystem::exists(armadillo))
      run("Armadillo (Stanford)", load_mesh(armadillo), n);
    else
      std::printf("(Armadillo skipped: %s absent)\n", armadillo.string().c_str());
    run("bumpy torus (synthetic)", bumpy_torus(360, 160), n);
  } catch (const sinew::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
