// CPU backend throughput: element-steps per second on a 100,000-element block (50 × 50 × 40 voxels
// of 1 mm, μ = 1 kPa, ν = 0.49), float and double, with and without muscles (the upper half of
// the block) and sliding (the bottom face over a wavy skull-like surface, 7,200 triangles). Prints
// one table; docs/performance.md records it. Usage: simulator_cpu_bench [--steps N] [--threads T]
// [--scene FILE ... [--precision float|double] [--out DIR]] (scene_timing.hpp: real scenes through
// the runner instead of the block).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <omp.h>

#include "scene_timing.hpp"
#include "sinew/formats/box_model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sliding_height_field.hpp"

using namespace sinew;
using namespace sinew::simulator;

namespace {

// A skull-like sliding surface under the block: the height field
// z = −0.5 mm + 0.3 mm · sin(2πx/20 mm) sin(2πy/20 mm) on a 1 mm grid over [−30, 30]² mm.
bench::HeightField wavy_surface() {
  return bench::make_height_field("skull", -30e-3, -30e-3, 1e-3, 60, 60, [](double x, double y) {
    return -0.5e-3 + 0.3e-3 * std::sin(2 * M_PI * x / 20e-3) * std::sin(2 * M_PI * y / 20e-3);
  });
}

formats::Model make_block(bool muscles, bool sliding) {
  const int nx = 50, ny = 50, nz = 40;
  const double h = 1e-3;
  formats::BoxSpec spec;
  spec.dims = {nx, ny, nz};
  spec.voxel_size = h;
  spec.origin = {-0.5 * nx * h, -0.5 * ny * h, 0.0};
  spec.materials = {formats::make_neo_hookean_material_from_shear("tissue", 1000, 0.49, 1000)};
  if (muscles) {
    formats::BoxMuscleSpec m;
    m.element_min = {0, 0, nz / 2};
    m.element_max = {nx, ny, nz};
    m.fibre = {1, 0.3, 0};
    m.reference_stress = 5e3;
    spec.muscles = {m};
  }
  spec.created = "2026-01-01T00:00:00Z";
  formats::Model model = formats::make_box_model(spec);
  if (sliding) bench::bind_bottom_to_height_field(model, wavy_surface(), 3);
  return model;
}

}  // namespace

int run(int argc, char** argv) {
  int steps = 40, threads = 0;
  bench::SceneTimingOptions scenes;
  for (int i = 1; i < argc; ++i) {
    if (bench::parse_scene_option(i, argc, argv, scenes)) continue;
    if (i + 1 < argc && !std::strcmp(argv[i], "--steps")) {
      steps = std::atoi(argv[++i]);
    } else if (i + 1 < argc && !std::strcmp(argv[i], "--threads")) {
      threads = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: simulator_cpu_bench [--steps N] [--threads T] [--scene FILE ... "
                   "[--precision float|double] [--out DIR]]\n");
      return 2;
    }
  }
  if (!scenes.scenes.empty()) {  // the real scenes through the runner instead of the block
    scenes.threads = threads;
    return bench::run_scene_timing(scenes);
  }
  std::printf(
      "simulator_cpu_bench: 50 x 50 x 40 block, %d OpenMP threads, median of 5 runs of %d steps "
      "after 3 warm-up steps, energies every 10 steps\n",
      threads > 0 ? threads : omp_get_max_threads(), steps);
  std::printf("%-9s %-8s %-8s %9s %9s %9s %12s %16s\n", "precision", "muscles", "sliding",
              "elements", "nodes", "sliding n", "ms/step", "element-steps/s");
  for (int variant = 0; variant < 4; ++variant) {
    const bool muscles = variant & 1, sliding = variant & 2;
    const formats::Model model = make_block(muscles, sliding);
    for (auto precision : {Precision::float32, Precision::float64}) {
      Setup s;
      s.precision = precision;
      s.threads = threads;
      s.effects.damping = true;
      s.damping_alpha = 50;
      s.effects.muscles = muscles;
      s.effects.sliding = sliding;
      s.effects.loads = true;
      if (muscles) s.activation = {Curve::ramp(0.01, 1.0)};
      // Pull the top face sideways so the block deforms and the sliding nodes move; slowly enough
      // (5 mm over 1 s) that a timed run stays far from inverting the top layer (a 20 ms ramp
      // inverted it after ~180 steps: reported, as designed, by the engine).
      PrescribedDisplacement top;
      for (std::size_t n = 0; n < model.node_count(); ++n)
        if (model.node_lattice[n][2] == 40) top.nodes.push_back(formats::Index(n));
      top.components = {true, false, false};
      top.value = {5e-3, 0, 0};
      top.curve = Curve::ramp(1.0, 1.0);
      s.prescribed.push_back(top);
      auto b = make_cpu_backend(model, s);
      b->step(3);
      // Median of kRepeats timed runs of `steps` steps each, every one from the state after the
      // warm-up: run on from the previous one, the 5 × 200 steps sheared the top layer until an
      // element inverted and the engine stopped the bench (issue 34).
      const State warm = b->state();
      constexpr int kRepeats = 5;
      std::vector<double> walls;
      for (int r = 0; r < kRepeats; ++r) {
        b->restore(warm);
        const auto t0 = std::chrono::steady_clock::now();
        b->step(steps);
        walls.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      std::sort(walls.begin(), walls.end());
      const double wall = walls[kRepeats / 2];
      const double per_step = wall / steps;
      std::printf("%-9s %-8s %-8s %9zu %9zu %9zu %12.3f %16.4g\n",
                  precision == Precision::float32 ? "float" : "double", muscles ? "yes" : "no",
                  sliding ? "yes" : "no", model.element_count(), model.node_count(),
                  model.sliding.size(), per_step * 1e3, double(model.element_count()) / per_step);
      std::fflush(stdout);
    }
  }
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "simulator_cpu_bench: %s\n", e.what());
    return 1;
  }
}
