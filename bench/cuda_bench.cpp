// CUDA backend benchmark on the three Table-2-sized models (Warburton & Maddock 2013, GTX 680):
// ms per step (CUDA events around graph launches, warm-up, median), element-steps per second,
// achieved bandwidth against a measured device-to-device copy, stage shares from variants that
// leave one stage out, float/double, gather/atomic/tiled assembly, and the CPU backend on the same machine. Usage:
// cuda_bench [--quick] [--only NAME] [--profile] [--launches N] [--sliding-skin S]
// [--sliding-refresh N]. quick: fewer launches, for checking the program; only: the models whose
// name contains NAME; profile: float, default assembly only, 3 launches after the warm-up, nothing
// else, each launch's time printed (for ncu, and for how the step time moves through the scene);
// launches: N timed launches; sliding-skin, sliding-refresh: those CudaOptions in every run.
// --scene FILE ... [--precision float|double] [--out DIR]: the real scenes through the runner beside
// the step alone on their model (scene_timing.hpp), instead of the models above.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "scene_timing.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/benchmark_models.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"

using namespace sinew;
using namespace sinew::simulator;

namespace {

struct Case {
  std::string name;
  double paper_ms;  // GTX 680, Table 2
  formats::Model model;
  Setup setup;
};

const std::vector<Index>* node_set(const formats::Model& m, const std::string& name) {
  for (const auto& s : m.node_sets)
    if (s.name == name) return &s.ids;
  return nullptr;
}

// What every case shares: damping, a run length, and the node set held rigid.
Case damped_case(std::string name, double paper_ms, formats::Model model, double damping_alpha,
                 double duration, const std::string& rigid_set) {
  Case c{std::move(name), paper_ms, std::move(model), {}};
  Setup& s = c.setup;
  s.effects.damping = true;
  s.damping_alpha = damping_alpha;
  s.duration = duration;
  s.rigid_nodes = *node_set(c.model, rigid_set);
  return c;
}

Case skin_block() {
  Case c = damped_case("skin block", 1.48, make_skin_block_model(), 100, 1, "x_min");
  Setup& s = c.setup;
  s.effects.loads = true;
  PrescribedDisplacement p;
  p.nodes = *node_set(c.model, "x_max");
  p.components = {true, false, false};
  p.value = {-0.1 * 120 * 0.25e-3, 0, 0};
  p.curve = Curve::ramp(0.05, 1.0);
  s.prescribed.push_back(p);
  return c;
}

Case forehead() {
  Case c = damped_case("face-scale forehead", 6.83, make_forehead_model(), 100, 1, "y_max");
  Setup& s = c.setup;
  s.effects.muscles = true;
  s.effects.sliding = true;
  s.activation = {Curve::ramp(0.05, 0.05), Curve::ramp(0.05, 0.05)};
  return c;
}

Case soft_body() {
  Case c = damped_case("15k multi-material body", 0.14, make_soft_body_model(), 20, 10, "feet");
  c.setup.effects.gravity = true;
  return c;
}

const ForceAssembly kDefault = CudaOptions{}.assembly;

const char* assembly_name(ForceAssembly a) {
  return a == ForceAssembly::gather   ? "gather"
         : a == ForceAssembly::atomic ? "atomic"
         : a == ForceAssembly::tiled  ? "tiled"
                                      : "automatic";
}

double median(std::vector<float> v) {
  std::sort(v.begin(), v.end());
  return double(v[v.size() / 2]);
}

struct Timing {
  double ms_per_step = 0, bytes_per_step = 0, dt = 0;
};

// The options of every run (--sliding-skin, --sliding-refresh); with_option changes one more.
CudaOptions base_options;
bool print_each_launch = false;

Timing time_gpu(const Case& c, const Setup& s, ForceAssembly assembly, int launches,
                CudaOptions o = base_options) try {
  o.assembly = assembly;
  auto b = make_cuda_backend(c.model, s, o);
  auto* t = dynamic_cast<CudaTiming*>(b.get());
  t->timed_graph_launches(3);  // warm-up
  const auto ms = t->timed_graph_launches(launches);
  if (print_each_launch) {
    std::printf("  ms/step of each launch:");
    for (float m : ms) std::printf(" %.4f", double(m) / t->graph_steps());
    std::printf("\n");
  }
  return {median(ms) / t->graph_steps(), t->bytes_per_step(), b->dt()};
} catch (const std::exception& e) {
  std::printf("  (failed: %s)\n", e.what());
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // each figure visible as soon as measured
  bool quick = false, profile = false;
  int launches = 0;
  std::string only;
  auto number = [&](int& k, double low) {
    char* end = nullptr;
    const double v = k + 1 < argc ? std::strtod(argv[++k], &end) : 0;
    return end && *end == '\0' && v >= low ? v : -1.0;
  };
  sinew::bench::SceneTimingOptions scenes;
  scenes.device = "cuda";
  for (int k = 1; k < argc; ++k) {
    bool ok = true;
    try {
      if (sinew::bench::parse_scene_option(k, argc, argv, scenes)) continue;
    } catch (const std::invalid_argument& e) {
      std::printf("cuda_bench: %s\n", e.what());
      return 2;
    }
    if (std::strcmp(argv[k], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[k], "--profile") == 0) {
      profile = true;
    } else if (std::strcmp(argv[k], "--only") == 0 && k + 1 < argc) {
      only = argv[++k];
    } else if (std::strcmp(argv[k], "--launches") == 0) {
      launches = int(number(k, 1));
      ok = launches >= 1;
    } else if (std::strcmp(argv[k], "--sliding-skin") == 0) {
      base_options.sliding_skin = number(k, 1e-9);
      ok = base_options.sliding_skin > 0;
    } else if (std::strcmp(argv[k], "--sliding-refresh") == 0) {
      base_options.sliding_refresh_interval = int(number(k, 1));
      ok = base_options.sliding_refresh_interval >= 1;
    } else {
      ok = false;
    }
    if (!ok) {
      std::printf(
          "usage: cuda_bench [--quick] [--only NAME] [--profile] [--launches N] "
          "[--sliding-skin CELLS] [--sliding-refresh STEPS] | [--scene FILE ... "
          "[--precision float|double] [--out DIR]]\n");
      return 2;
    }
  }
  if (launches == 0) launches = profile ? 3 : quick ? 5 : 20;
  print_each_launch = profile;
  if (!cuda_device_available()) {
    std::printf("no CUDA device: nothing to measure\n");
    return 0;
  }
  std::printf("device: %s\n", cuda_device_name().c_str());
  if (!scenes.scenes.empty()) return sinew::bench::run_scene_timing(scenes);
  const double copy_bw = measure_copy_bandwidth(std::size_t(1) << 30);
  std::printf("device-to-device copy (1 GiB, read + write): %.0f GB/s\n", copy_bw / 1e9);
  std::printf(
      "timing: median of %d CUDA-graph launches (120 steps each) after 3 warm-up launches\n\n",
      launches);

  std::vector<Case> cases;
  for (auto make : {forehead, skin_block, soft_body}) {
    Case c = make();
    if (c.name.find(only) != std::string::npos) cases.push_back(std::move(c));
  }

  std::vector<std::string> summary;
  for (const auto& c : cases) {
    const double e = double(c.model.element_count()), n = double(c.model.node_count());
    std::printf("== %s: %zu elements, %zu nodes, %zu sliding nodes\n", c.name.c_str(),
                c.model.element_count(), c.model.node_count(),
                c.setup.effects.sliding ? c.model.sliding.size() : std::size_t(0));
    // What the default (automatic) assembly resolves to on this model: the base of the shares.
    ForceAssembly chosen = kDefault;
    try {
      auto b = make_cuda_backend(c.model, c.setup, base_options);
      chosen = dynamic_cast<CudaTiming*>(b.get())->assembly();
    } catch (const std::exception& ex) {
      std::printf("  (failed: %s)\n", ex.what());
    }
    std::printf("  default assembly (%s) here: %s\n", assembly_name(kDefault),
                assembly_name(chosen));
    Timing base{};
    for (Precision p : {Precision::float32, Precision::float64})
      for (ForceAssembly a : {ForceAssembly::gather, ForceAssembly::atomic, ForceAssembly::tiled}) {
        if (profile && (p != Precision::float32 || a != chosen)) continue;
        Setup s = c.setup;
        s.precision = p;
        const Timing t = time_gpu(c, s, a, launches);
        if (p == Precision::float32 && a == chosen) base = t;
        const double bw = t.bytes_per_step / (t.ms_per_step * 1e-3);
        std::printf(
            "  %-6s %-6s %9.4f ms/step  %7.2f G element-steps/s  %6.0f GB/s (%4.1f%% of copy)\n",
            p == Precision::float32 ? "float" : "double", assembly_name(a), t.ms_per_step,
            e / (t.ms_per_step * 1e-3) / 1e9, bw / 1e9, 100 * bw / copy_bw);
      }
    if (profile) continue;
    // Stage shares: leave one stage out (float, default assembly).
    struct Variant {
      const char* stage;
      std::function<void(Setup&)> off;
    };
    std::vector<Variant> variants = {
        {"hourglass", [](Setup& s) { s.effects.hourglass = false; }},
    };
    if (c.setup.effects.muscles)
      variants.push_back({"muscles", [](Setup& s) { s.effects.muscles = false; }});
    if (c.setup.effects.sliding)
      variants.push_back({"sliding", [](Setup& s) { s.effects.sliding = false; }});
    if (c.setup.effects.gravity)
      variants.push_back({"gravity", [](Setup& s) { s.effects.gravity = false; }});
    if (c.setup.effects.loads)
      variants.push_back({"loads", [](Setup& s) { s.effects.loads = false; }});
    // Float ms per step with one CUDA option changed (label: what was changed).
    auto with_option = [&](const std::string& label, ForceAssembly a,
                           const std::function<void(CudaOptions&)>& set) {
      CudaOptions o = base_options;
      set(o);
      Setup s = c.setup;
      s.precision = Precision::float32;
      const Timing t = time_gpu(c, s, a, launches, o);
      std::printf("  %-66s %9.4f ms/step\n", label.c_str(), t.ms_per_step);
    };
    with_option("plain launches (no programmatic dependent launch)", kDefault,
                [](CudaOptions& o) { o.programmatic_launch = false; });
    if (c.setup.effects.sliding) {
      const CudaOptions defaults;
      char label[96];
      for (double skin : {0.02, 0.05, 0.1, 0.25, 0.35}) {
        if (skin == defaults.sliding_skin) continue;  // that is `base`
        std::snprintf(label, sizeof label, "sliding skin %g cells (default %g)", skin,
                      defaults.sliding_skin);
        with_option(label, kDefault, [&](CudaOptions& o) { o.sliding_skin = skin; });
      }
      for (int every : {1, 2, 4, 8, 16}) {
        if (every == defaults.sliding_refresh_interval) continue;
        std::snprintf(label, sizeof label, "sliding lists refreshed every %d steps (default %d)",
                      every, defaults.sliding_refresh_interval);
        with_option(label, kDefault, [&](CudaOptions& o) { o.sliding_refresh_interval = every; });
      }
    }
    for (int tps : {1, 2, 4, 6})  // tiled: the default, 3 tiles per SM, is `base` when tiled
      with_option("tiled, " + std::to_string(tps) + " tiles per SM (default 3)",
                  ForceAssembly::tiled, [&](CudaOptions& o) { o.tiles_per_sm = tps; });
    for (const auto& v : variants) {
      Setup s = c.setup;
      s.precision = Precision::float32;
      v.off(s);
      const Timing t = time_gpu(c, s, kDefault, launches);
      std::printf("  without %-58s %9.4f ms/step  share %5.1f%%\n", v.stage, t.ms_per_step,
                  100 * (base.ms_per_step - t.ms_per_step) / base.ms_per_step);
    }
    // Per-stage device time (float, default assembly): events between the stages of single steps.
    try {
      Setup s = c.setup;
      s.precision = Precision::float32;
      auto b = make_cuda_backend(c.model, s, base_options);
      auto* t = dynamic_cast<CudaTiming*>(b.get());
      const auto stages = t->stage_times(quick ? 5 : 30);
      double sum = 0;
      for (const auto& st : stages) sum += st.second;
      for (const auto& st : stages)
        std::printf("  stage %-56s %9.4f ms  %5.1f%% of the stages' sum\n", st.first.c_str(),
                    st.second, 100 * st.second / sum);
    } catch (const std::exception& ex) {
      std::printf("  stage timing failed: %s\n", ex.what());
    }
    // CPU backend, a few steps.
    try {
      Setup s = c.setup;
      s.precision = Precision::float32;
      auto cpu = make_cpu_backend(c.model, s);
      cpu->step(1);
      const int steps = e > 2e5 ? 3 : 20;
      const auto t0 = std::chrono::steady_clock::now();
      cpu->step(steps);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
          steps;
      std::printf(
          "  CPU backend (float, all cores): %.3f ms/step, %.1f M element-steps/s; GPU speed-up "
          "%.0fx\n",
          ms, e / (ms * 1e-3) / 1e6, ms / base.ms_per_step);
    } catch (const std::exception& ex) {
      std::printf("  CPU backend failed: %s\n", ex.what());
    }
    char line[512];
    std::snprintf(line, sizeof line,
                  "| %s | %.0f | %.0f | %.3g | %.2f | %.4f (%s) | %.0fx | %.2f |", c.name.c_str(),
                  n, e, base.dt * 1e3, c.paper_ms, base.ms_per_step, assembly_name(chosen),
                  c.paper_ms / base.ms_per_step, base.dt / (base.ms_per_step * 1e-3));
    summary.push_back(line);
    std::printf("\n");
  }
  std::printf(
      "| model | nodes | elements | dt (ms) | paper ms/step (GTX 680) | ours ms/step (float, "
      "%s) | ratio | simulated s per wall s |\n",
      assembly_name(kDefault));
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const auto& l : summary) std::printf("%s\n", l.c_str());
  return 0;
}
