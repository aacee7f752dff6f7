// voxelizer_bench [--target N] [--subdivisions S] [--threads T]
// Builds a layered model of at least 500,000 elements from generated meshes of at least 100,000
// triangles (an ellipsoidal "head": skin, skull, two muscles with harmonic fibres, rigid and
// sliding nodes, the skin bound as the visual surface) and prints time and peak memory per stage,
// plus the cost of single winding-number and distance queries. docs/performance.md records it.
#include <omp.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <random>

#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/primitives.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"
#include "sinew/voxelizer/winding_number.hpp"

using namespace sinew;
using namespace sinew::voxelizer;

int main(int argc, char** argv) {
  CLI::App app{"voxelizer benchmark"};
  std::int64_t target = 550000;
  int subdivisions = 7;
  int threads = 0;
  app.add_option("--target", target, "target element count");
  app.add_option("--subdivisions", subdivisions,
                 "icosphere level of the skin (7: 327,680 triangles)");
  app.add_option("--threads", threads, "OpenMP threads (default: all)");
  CLI11_PARSE(app, argc, argv);

  const std::string yaml = R"(
units: mm
resolution: {target_elements: )" +
                           std::to_string(target) + R"(}
outer: {ellipsoid: {radii: [60, 50, 70]}, subdivisions: )" +
                           std::to_string(subdivisions) + R"(}
inner: {ellipsoid: {radii: [50, 40, 60]}, subdivisions: )" +
                           std::to_string(subdivisions - 1) + R"(}
materials: {preset: warburton2013}
layers:
  - {material: stratum_corneum, thickness: 0.02}
  - {material: dermis, thickness: 1.8}
  - {material: hypodermis}
muscles:
  - name: left
    mesh: {cylinder: {centre: [-20, -40, 0], radius: 3, half_length: 20}, subdivisions: 3}
    material: muscle
    fibres: {type: harmonic, origin: {box: {min: [-30, -50, -21], max: [-10, -30, -17]}},
             insertion: {box: {min: [-30, -50, 17], max: [-10, -30, 21]}}}
  - name: right
    mesh: {cylinder: {centre: [20, -40, 0], radius: 3, half_length: 20}, subdivisions: 3}
    material: muscle
    fibres: {type: constant, direction: [0, 0, 1]}
boundary:
  - {type: rigid, inside: true}
  - {type: sliding, within: 1.5}
)";
  const Spec spec = parse_spec(yaml, "bench.yaml");
  VoxelizeOptions opt;
  opt.threads = threads;
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = voxelize(spec, opt);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::int64_t triangles = 0;
  for (const auto& m : r.summary.meshes) triangles += m.diagnostics.triangles;
  std::printf(
      "voxelizer_bench: %lld elements, %lld nodes, %lld triangles in all meshes, %d threads\n",
      static_cast<long long>(r.summary.elements), static_cast<long long>(r.summary.nodes),
      static_cast<long long>(triangles), r.summary.threads);
  std::printf("%s", summary_text(r.summary).c_str());
  std::printf("wall %.3f s, peak RSS %.1f MiB\n", wall, peak_rss_bytes() / (1024.0 * 1024.0));

  // Single-query costs on the skin mesh, near the surface (where the voxelizer queries most).
  const auto skin = make_ellipsoid({0, 0, 0}, {0.06, 0.05, 0.07}, subdivisions);
  const WindingNumber wn(skin);
  const DistanceQuery dq(skin);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3d> pts;
  for (int i = 0; i < 20000; ++i) {
    const auto& v = skin.vertices[static_cast<std::size_t>(i) % skin.vertices.size()];
    pts.push_back(v + 0.002 * Vec3d{u(rng), u(rng), u(rng)});
  }
  double sink = 0;
  auto t1 = std::chrono::steady_clock::now();
  for (const auto& p : pts) sink += wn(p);
  auto t2 = std::chrono::steady_clock::now();
  for (const auto& p : pts) sink += dq.closest(p).distance;
  auto t3 = std::chrono::steady_clock::now();
  std::printf(
      "per query near the skin (%zu triangles): winding number %.2f us, closest point %.2f us "
      "(%g)\n",
      skin.triangles.size(), 1e6 * std::chrono::duration<double>(t2 - t1).count() / pts.size(),
      1e6 * std::chrono::duration<double>(t3 - t2).count() / pts.size(), sink > 0 ? 1.0 : 0.0);
  return 0;
}
