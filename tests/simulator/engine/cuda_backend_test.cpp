// CUDA backend against the CPU backend, reproducibility, restart and instability detection.
// Every case skips with "no CUDA device" when no GPU is present (CI).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "engine_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/benchmark_models.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"

namespace sinew::simulator::testing {
namespace {
using SimSetup = sinew::simulator::Setup;

#define SKIP_WITHOUT_GPU() \
  if (!cuda_device_available()) GTEST_SKIP() << "no CUDA device"

// A small forehead-like model: 2 muscles, fibres, sliding bottom nodes over a curved skull,
// rigid y_max edge, activation ramped over the run.
struct Scene {
  formats::Model model;
  SimSetup setup;
};

Scene muscle_sliding_scene(Precision p) {
  Scene s;
  s.model = make_forehead_model(24, 12, 4, 0.5e-3);
  SimSetup& st = s.setup;
  st.precision = p;
  st.effects.muscles = true;
  st.effects.sliding = true;
  st.effects.damping = true;
  st.effects.gravity = true;
  st.damping_alpha = 200;
  st.activation = {Curve::ramp(2e-3, 0.05), Curve::ramp(3e-3, 0.025)};
  for (const auto& ns : s.model.node_sets)
    if (ns.name == "y_max") st.rigid_nodes = ns.ids;
  st.duration = 1;
  return s;
}

std::vector<Index> node_set_ids(const formats::Model& m, const std::string& name) {
  for (const auto& ns : m.node_sets)
    if (ns.name == name) return ns.ids;
  ADD_FAILURE() << "no node set " << name;
  return {};
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}
double max_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

TEST(CudaBackend, AgreesWithCpuOnAMuscleAndSlidingModelAfterManySteps) {
  SKIP_WITHOUT_GPU();
  for (Precision p : {Precision::float32, Precision::float64}) {
    const Scene s = muscle_sliding_scene(p);
    auto cpu = make_cpu_backend(s.model, s.setup);
    auto gpu = make_cuda_backend(s.model, s.setup);
    ASSERT_EQ(cpu->dt(), gpu->dt());
    const std::int64_t steps = 2000;
    cpu->step(steps);
    gpu->step(steps);
    const auto uc = cpu->displacements(), ug = gpu->displacements();
    const double scale = max_abs(uc), diff = max_diff(uc, ug);
    ASSERT_GT(scale, 1e-7) << "the scene must move";
    const double measure = diff / scale;
    std::printf(
        "[ measured ] %s, %lld steps: max|u_gpu - u_cpu| / max|u_cpu| = %.3g (max|u| = %.3g m)\n",
        p == Precision::float32 ? "float" : "double", static_cast<long long>(steps), measure,
        scale);
    EXPECT_LT(measure, p == Precision::float32 ? 1e-3 : 1e-9);
    const Energies ec = cpu->energies(), eg = gpu->energies();
    EXPECT_NEAR(eg.strain, ec.strain,
                (p == Precision::float32 ? 1e-3 : 1e-9) * std::abs(ec.strain));
    EXPECT_NEAR(eg.external_work, ec.external_work,
                (p == Precision::float32 ? 1e-3 : 1e-9) * std::abs(ec.external_work) + 1e-30);
    const auto fc = cpu->element_fields(), fg = gpu->element_fields();
    EXPECT_LT(max_diff(fc.jacobian, fg.jacobian), p == Precision::float32 ? 1e-3 : 1e-12);
  }
}

TEST(CudaBackend, GatherAssemblyIsBitReproducibleFromRunToRun) {
  SKIP_WITHOUT_GPU();
  const Scene s = muscle_sliding_scene(Precision::float32);
  std::vector<double> first;
  for (int run = 0; run < 3; ++run) {
    auto gpu = make_cuda_backend(s.model, s.setup);
    gpu->step(777);
    const auto u = gpu->displacements();
    if (run == 0)
      first = u;
    else
      EXPECT_EQ(0, std::memcmp(first.data(), u.data(), u.size() * sizeof(double))) << "run " << run;
  }
  // Atomic assembly: same physics to float precision (its last bits may change between runs).
  CudaOptions atomic;
  atomic.assembly = ForceAssembly::atomic;
  auto a = make_cuda_backend(s.model, s.setup, atomic);
  a->step(777);
  const auto ua = a->displacements();
  const double measure = max_diff(first, ua) / max_abs(first);
  std::printf("[ measured ] atomic vs gather, 777 float steps: max|du| / max|u| = %.3g\n", measure);
  EXPECT_LT(measure, 1e-3);
}

// A model with sliding, muscles and gravity (float and double), a skin block whose loads run in
// the node program, and a sparse lattice (the soft body under gravity).
std::vector<std::pair<std::string, Scene>> assembly_scenes() {
  std::vector<std::pair<std::string, Scene>> scenes;
  scenes.emplace_back("muscles + sliding, float", muscle_sliding_scene(Precision::float32));
  scenes.emplace_back("muscles + sliding, double", muscle_sliding_scene(Precision::float64));
  {
    Scene s;
    s.model = make_skin_block_model(30, 20, 9, 0.25e-3);
    s.setup.effects.damping = true;
    s.setup.effects.loads = true;
    s.setup.damping_alpha = 100;
    s.setup.duration = 1;
    s.setup.rigid_nodes = node_set_ids(s.model, "x_min");
    PrescribedDisplacement p;
    p.nodes = node_set_ids(s.model, "x_max");
    p.components = {true, false, false};
    p.value = {-0.1 * 30 * 0.25e-3, 0, 0};
    p.curve = Curve::ramp(2e-3, 1.0);
    s.setup.prescribed.push_back(p);
    scenes.emplace_back("skin block, prescribed, float", std::move(s));
  }
  {
    Scene s;
    s.model = make_soft_body_model(0.6, 2e-3);
    s.setup.effects.damping = true;
    s.setup.effects.gravity = true;
    s.setup.damping_alpha = 20;
    s.setup.duration = 10;
    s.setup.rigid_nodes = node_set_ids(s.model, "feet");
    scenes.emplace_back("soft body, gravity, float", std::move(s));
  }
  return scenes;
}

// Scene s run `steps` steps on the CUDA backend with options a and with options b.
struct BackendPair {
  std::unique_ptr<Backend> a, b;
};
BackendPair run_both(const Scene& s, const CudaOptions& a, const CudaOptions& b, int steps) {
  BackendPair r{make_cuda_backend(s.model, s.setup, a), make_cuda_backend(s.model, s.setup, b)};
  r.a->step(steps);
  r.b->step(steps);
  return r;
}

// Tiled assembly sums the same element entries in the same order as gather (lattice_tiles.hpp): on
// the assembly scenes it gives gather's results; the figure printed says whether they are
// bit-identical.
TEST(CudaBackend, TiledAssemblyGivesGathersResults) {
  SKIP_WITHOUT_GPU();
  for (const auto& [name, s] : assembly_scenes()) {
    CudaOptions gather, tiled;
    gather.assembly = ForceAssembly::gather;
    tiled.assembly = ForceAssembly::tiled;
    const auto [a, b] = run_both(s, gather, tiled, 700);
    const auto ua = a->displacements(), ub = b->displacements();
    ASSERT_GT(max_abs(ua), 1e-9) << name << ": the scene must move";
    const double measure = max_diff(ua, ub) / max_abs(ua);
    const bool same_bits = std::memcmp(ua.data(), ub.data(), ua.size() * sizeof(double)) == 0;
    std::printf("[ measured ] tiled vs gather, %s, 700 steps: max|du| / max|u| = %.3g (%s)\n",
                name.c_str(), measure, same_bits ? "bit-identical" : "not bit-identical");
    EXPECT_LT(measure, s.setup.precision == Precision::float32 ? 1e-5 : 1e-12) << name;
    const Energies ea = a->energies(), eb = b->energies();
    EXPECT_NEAR(eb.external_work, ea.external_work, 1e-5 * std::abs(ea.external_work) + 1e-30)
        << name;
    EXPECT_NEAR(eb.kinetic, ea.kinetic, 1e-4 * std::abs(ea.kinetic) + 1e-30) << name;
  }
}

// Programmatic dependent launches (the default on sm_90 and later) change when a kernel's blocks
// start, not what they compute: the same bits as plain launches on the assembly scenes, gathered
// and tiled (the sliding scene reads its warm starts and lists before the wait, and forks list
// refreshes beside the step).
TEST(CudaBackend, ProgrammaticLaunchesGiveThePlainLaunchesResults) {
  SKIP_WITHOUT_GPU();
  for (const auto& [name, s] : assembly_scenes())
    for (ForceAssembly assembly : {ForceAssembly::gather, ForceAssembly::tiled}) {
      CudaOptions plain, programmatic;
      plain.assembly = programmatic.assembly = assembly;
      plain.programmatic_launch = false;
      programmatic.programmatic_launch = true;
      const auto [a, b] = run_both(s, plain, programmatic, 700);
      const auto ua = a->displacements(), ub = b->displacements();
      ASSERT_GT(max_abs(ua), 1e-9) << name << ": the scene must move";
      const char* how = assembly == ForceAssembly::gather ? "gather" : "tiled";
      EXPECT_EQ(0, std::memcmp(ua.data(), ub.data(), ua.size() * sizeof(double)))
          << name << ", " << how;
      EXPECT_EQ(a->state().sliding_triangle, b->state().sliding_triangle) << name << ", " << how;
      EXPECT_EQ(a->energies().external_work, b->energies().external_work) << name << ", " << how;
    }
}

// The sliding candidate lists are exact for any skin and refresh interval: a skin so small that
// nodes leave their lists every step (misses, batch replays, the refresh interval halved; from 2
// steps on, down to inline refreshes), the default, 0.35 cells (longer lists, read before the wait
// of a programmatic launch), refreshes every step, and a skin so large that lists overflow (full
// searches) give the same bits, with gather and with tiled assembly (lists refreshed beside the
// step, the constraint kernel after it).
TEST(CudaBackend, SlidingListsGiveTheSameResultsForAnySkin) {
  SKIP_WITHOUT_GPU();
  const Scene s = muscle_sliding_scene(Precision::float32);
  const int every = CudaOptions{}.sliding_refresh_interval;
  const std::pair<double, int> cases[] = {{CudaOptions{}.sliding_skin, every},
                                          {0.35, every},
                                          {CudaOptions{}.sliding_skin, 1},
                                          {1e-6, every},
                                          {1e-6, 2},
                                          {3.0, every}};
  for (ForceAssembly assembly : {ForceAssembly::gather, ForceAssembly::tiled}) {
    std::vector<double> first;
    std::vector<std::int32_t> first_triangles;
    for (const auto& [skin, refresh] : cases) {
      CudaOptions o;
      o.assembly = assembly;
      o.sliding_skin = skin;
      o.sliding_refresh_interval = refresh;
      auto gpu = make_cuda_backend(s.model, s.setup, o);
      gpu->step(600);
      const auto u = gpu->displacements();
      const auto tri = gpu->state().sliding_triangle;
      if (first.empty()) {
        first = u;
        first_triangles = tri;
        continue;
      }
      const char* name = assembly == ForceAssembly::gather ? "gather" : "tiled";
      EXPECT_EQ(0, std::memcmp(first.data(), u.data(), u.size() * sizeof(double)))
          << name << ", skin " << skin << ", refresh every " << refresh;
      EXPECT_EQ(first_triangles, tri) << name << ", skin " << skin << ", refresh every " << refresh;
    }
  }
}

TEST(CudaBackend, RestoredRunContinuesBitIdentically) {
  SKIP_WITHOUT_GPU();
  const Scene s = muscle_sliding_scene(Precision::float32);
  auto a = make_cuda_backend(s.model, s.setup);
  a->step(300);
  const State mid = a->state();
  a->step(401);
  auto b = make_cuda_backend(s.model, s.setup);
  b->restore(mid);
  b->step(401);
  EXPECT_EQ(a->step_index(), b->step_index());
  const auto ua = a->displacements(), ub = b->displacements();
  EXPECT_EQ(0, std::memcmp(ua.data(), ub.data(), ua.size() * sizeof(double)));
  EXPECT_EQ(a->state().sliding_triangle, b->state().sliding_triangle);
}

// A damaged checkpoint's state is refused before anything reaches the device, as on the CPU
// (BackendCore::check_state; EngineTest.RestoreRefusesADamagedState): a sliding triangle id past
// its surface, which the first sliding kernel would read past the corner array.
TEST(CudaBackend, RestoreRefusesADamagedState) {
  SKIP_WITHOUT_GPU();
  const Scene s = muscle_sliding_scene(Precision::float32);
  auto a = make_cuda_backend(s.model, s.setup);
  a->step(10);
  const State good = a->state();
  ASSERT_FALSE(good.sliding_triangle.empty());
  State bad = good;
  bad.sliding_triangle.back() = 1 << 20;
  auto b = make_cuda_backend(s.model, s.setup);
  try {
    b->restore(bad);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "state.sliding_triangle") << e.what();
  }
  bad = good;
  bad.u[1] = std::nan("");
  EXPECT_THROW(b->restore(bad), ConfigError);
  b->restore(good);
  b->step(5);
  EXPECT_EQ(b->step_index(), 15);
}

// Calls of any length (the runner stops at every frame and probe row) run as batch graphs, short
// graphs or single launches: all give the bits of one long call, in both precisions, with sliding
// (lists refreshed ahead in graphs, inline in single launches).
TEST(CudaBackend, CallsOfAnyLengthGiveTheBitsOfOneLongCall) {
  SKIP_WITHOUT_GPU();
  for (Precision p : {Precision::float32, Precision::float64}) {
    const Scene s = muscle_sliding_scene(p);
    auto whole = make_cuda_backend(s.model, s.setup);
    auto cut = make_cuda_backend(s.model, s.setup);
    const std::vector<std::int64_t> calls = {1, 2, 73, 74, 29, 31, 7, 96, 200, 1, 13, 59, 3, 411};
    std::int64_t total = 0;
    for (auto n : calls) {
      cut->step(n);
      total += n;
    }
    whole->step(total);
    ASSERT_EQ(cut->step_index(), whole->step_index());
    const auto a = whole->displacements(), b = cut->displacements();
    EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(double)))
        << (p == Precision::float32 ? "float" : "double");
    EXPECT_EQ(whole->state().sliding_triangle, cut->state().sliding_triangle);
    EXPECT_EQ(whole->energies().external_work, cut->energies().external_work);
  }
}

TEST(CudaBackend, InstabilityIsDetectedWithTheStateAtTheLastGoodStep) {
  SKIP_WITHOUT_GPU();
  const auto model = block(8, 8, 8, 1e-3, neo_hookean(1000, 0.49, 1000));
  SimSetup s;
  s.precision = Precision::float32;
  s.duration = 1;
  const Plan probe = make_plan(model, s);
  s.time_step.policy = TimeStepPolicy::forced;
  s.time_step.user_dt = 1.3 * probe.dt_critical;
  s.initial_velocities.push_back({nodes_at(model, 2, 8), {0, 0, 0.05}});
  auto gpu = make_cuda_backend(model, s);
  std::string message;
  try {
    gpu->step(20000);
  } catch (const InstabilityError& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty()) << "no instability detected";
  std::printf("[ measured ] %s\n", message.c_str());
  EXPECT_NE(message.find("at step"), std::string::npos);
  for (double v : gpu->displacements()) ASSERT_TRUE(std::isfinite(v)) << "state not at a good step";
  // Calls of 73 steps (single launches between the aligned graphs) stop at the same step with the
  // same message.
  auto cut = make_cuda_backend(model, s);
  std::string cut_message;
  try {
    for (int k = 0; k < 20000 / 73 + 1; ++k) cut->step(73);
  } catch (const InstabilityError& e) {
    cut_message = e.what();
  }
  EXPECT_EQ(cut_message, message);
  EXPECT_EQ(cut->step_index(), gpu->step_index());
}

// The blow-up test runs where each step's row flags it (steps ≡ 0 mod the energy interval), so
// graphs start at any step ≡ 0 mod 3: with intervals that are not multiples of 3 (7, 10) and one
// that is (3), long calls and calls of 73 steps (single launches and short graphs) stop at the
// step the CPU stops at, with one message.
TEST(CudaBackend, BlowUpTestsFollowTheEnergyIntervalAsOnTheCpu) {
  SKIP_WITHOUT_GPU();
  const auto model = block(8, 8, 8, 1e-3, neo_hookean(1000, 0.49, 1000));
  for (int interval : {7, 10, 3}) {
    SCOPED_TRACE(interval);
    SimSetup s;
    s.precision = Precision::float64;
    s.duration = 1;
    s.energy_interval = interval;
    const Plan probe = make_plan(model, s);
    s.time_step.policy = TimeStepPolicy::forced;
    s.time_step.user_dt = 1.3 * probe.dt_critical;
    s.initial_velocities.push_back({nodes_at(model, 2, 8), {0, 0, 0.05}});
    auto stop = [](Backend& b, std::int64_t call) {
      try {
        for (int k = 0; k < 20000 / call + 1; ++k) b.step(call);
      } catch (const InstabilityError& e) {
        return std::string(e.what());
      }
      return std::string();
    };
    auto cpu = make_cpu_backend(model, s);
    ASSERT_FALSE(stop(*cpu, 20000).empty()) << "no instability on the CPU";
    std::string first;
    for (std::int64_t call : {std::int64_t(20000), std::int64_t(73)}) {
      auto gpu = make_cuda_backend(model, s);
      const std::string message = stop(*gpu, call);
      ASSERT_FALSE(message.empty()) << "calls of " << call;
      if (first.empty()) first = message;
      EXPECT_EQ(message, first) << "calls of " << call;
      EXPECT_EQ(gpu->step_index(), cpu->step_index()) << "calls of " << call << ": " << message;
    }
  }
}

// The same with muscles and sliding (the accuracy study's forehead at 0.9 h/c once ended in an
// illegal memory access instead): a diverging run with sliding nodes must stop with the
// instability message, whatever the precision, and keep the last good state.
TEST(CudaBackend, UnstableSlidingRunStopsCleanly) {
  SKIP_WITHOUT_GPU();
  for (const Precision p : {Precision::float32, Precision::float64}) {
    Scene sc = muscle_sliding_scene(p);
    const Plan probe = make_plan(sc.model, sc.setup);
    sc.setup.time_step.policy = TimeStepPolicy::forced;
    sc.setup.time_step.user_dt = 1.5 * probe.dt_critical;
    auto gpu = make_cuda_backend(sc.model, sc.setup);
    std::string message;
    try {
      gpu->step(200000);
    } catch (const InstabilityError& e) {
      message = e.what();
    }
    ASSERT_FALSE(message.empty()) << "no instability detected";
    std::printf("[ measured ] %s\n", message.c_str());
    for (double v : gpu->displacements()) ASSERT_TRUE(std::isfinite(v));
  }
}

TEST(CudaBackend, InternalForcesAndReactionsMatchTheCpu) {
  SKIP_WITHOUT_GPU();
  const Scene s = muscle_sliding_scene(Precision::float64);
  auto cpu = make_cpu_backend(s.model, s.setup);
  auto gpu = make_cuda_backend(s.model, s.setup);
  cpu->step(150);
  gpu->step(150);
  const auto fc = cpu->internal_forces(), fg = gpu->internal_forces();
  EXPECT_LT(max_diff(fc, fg) / max_abs(fc), 1e-9);
  const auto rc = cpu->reaction(s.setup.rigid_nodes), rg = gpu->reaction(s.setup.rigid_nodes);
  for (int d = 0; d < 3; ++d)
    EXPECT_NEAR(rg[std::size_t(d)], rc[std::size_t(d)],
                1e-9 * (std::abs(rc[std::size_t(d)]) + 1e-12));
}

// Probe rows ask for several node lists in turn; the engine keeps each uploaded (up to 8, then
// replaces one): every answer is the nodes' own displacements, before and after replacements.
TEST(CudaBackend, NodeListsAskedInTurnGiveThoseNodesDisplacements) {
  SKIP_WITHOUT_GPU();
  const Scene s = muscle_sliding_scene(Precision::float32);
  auto gpu = make_cuda_backend(s.model, s.setup);
  gpu->step(150);
  const auto all = gpu->displacements();
  ASSERT_GT(max_abs(all), 0.0);
  const auto n = Index(s.model.node_count());
  for (int round = 0; round < 3; ++round)
    for (Index k = 0; k < 11; ++k) {  // 11 lists: more than the engine keeps
      const std::vector<Index> nodes{k, Index((7 * k + 3) % n), Index(n - 1 - k)};
      const auto got = gpu->displacements(nodes);
      ASSERT_EQ(got.size(), 9u);
      for (std::size_t i = 0; i < nodes.size(); ++i)
        for (std::size_t d = 0; d < 3; ++d)
          EXPECT_EQ(got[3 * i + d], all[3 * std::size_t(nodes[i]) + d])
              << "round " << round << ", list " << k << ", node " << nodes[i];
    }
  // The reaction set's list between them, as a run's probe rows ask.
  const auto r0 = gpu->reaction(s.setup.rigid_nodes);
  gpu->displacements({0, 1});
  EXPECT_EQ(gpu->reaction(s.setup.rigid_nodes), r0);
}

// Engines in threads of one process (sinew-sweep --concurrent) share the device and wait only for
// their own streams: each gives the bits of an engine alone, frames and probe queries included.
TEST(CudaBackend, EnginesInThreadsGiveTheBitsOfOneAlone) {
  SKIP_WITHOUT_GPU();
  const Scene s = muscle_sliding_scene(Precision::float32);
  const std::vector<Index> probe{0, 5, 17};
  const auto run = [&](std::vector<double>& u, std::vector<double>& picked, double& strain,
                       std::array<double, 3>& reaction) {
    auto gpu = make_cuda_backend(s.model, s.setup);
    for (int k = 0; k < 6; ++k) {  // steps between "probe rows" and "frames", as the runner does
      gpu->step(97);
      picked = gpu->displacements(probe);
      reaction = gpu->reaction(s.setup.rigid_nodes);
      if (k % 2) strain = gpu->frame(false).energies.strain;
    }
    u = gpu->displacements();
  };
  std::vector<double> u0, p0;
  double e0 = 0;
  std::array<double, 3> r0{};
  run(u0, p0, e0, r0);
  constexpr int kThreads = 4;
  std::vector<std::vector<double>> u(kThreads), p(kThreads);
  std::vector<double> e(kThreads);
  std::vector<std::array<double, 3>> r(kThreads);
  std::vector<std::exception_ptr> errors(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      try {
        run(u[std::size_t(t)], p[std::size_t(t)], e[std::size_t(t)], r[std::size_t(t)]);
      } catch (...) {
        errors[std::size_t(t)] = std::current_exception();
      }
    });
  for (auto& th : threads) th.join();
  for (int t = 0; t < kThreads; ++t) {
    if (errors[std::size_t(t)]) std::rethrow_exception(errors[std::size_t(t)]);
    EXPECT_EQ(u[std::size_t(t)], u0) << "thread " << t;
    EXPECT_EQ(p[std::size_t(t)], p0) << "thread " << t;
    EXPECT_EQ(e[std::size_t(t)], e0) << "thread " << t;
    EXPECT_EQ(r[std::size_t(t)], r0) << "thread " << t;
  }
  ASSERT_GT(max_abs(u0), 0.0);
}

TEST(CudaBackend, BenchmarkModelsHaveTable2Sizes) {
  // Runs without a GPU: the generators are host code. Paper Table 2 counts within 5%.
  const auto skin = make_skin_block_model();
  EXPECT_EQ(skin.element_count(), 129600u);
  EXPECT_EQ(skin.node_count(), 146410u);
  const auto body = make_soft_body_model();
  EXPECT_NEAR(double(body.element_count()), 15107.0, 0.05 * 15107);
  EXPECT_NEAR(double(body.node_count()), 19698.0, 0.05 * 19698);
}

#if !defined(SINEW_CUDA_ENABLED)
TEST(CudaBackend, BuiltWithoutCudaSaysSo) {
  const auto model = block(2, 2, 2, 1e-3, neo_hookean(1000, 0.3));
  SimSetup s;
  s.duration = 1e-3;
  try {
    make_cuda_backend(model, s);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("built without CUDA"), std::string::npos);
  }
}
#endif

}  // namespace
}  // namespace sinew::simulator::testing
