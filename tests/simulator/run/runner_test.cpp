// Whole runs through run_scene (what sinew-simulate does): a run cut in two and resumed from its
// checkpoint writes bit-identical results to an uninterrupted one; an unstable run stops with a
// clear error and leaves valid frames; --explain prints the plan and writes nothing.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/checkpoint.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::simulator {
namespace {

using testing::read_file;
using testing::TempDir;
using testing::write_file;

// Every dataset of a results file as raw bytes, by path.
void collect(hid_t loc, const std::string& prefix,
             std::map<std::string, std::vector<unsigned char>>& out) {
  H5G_info_t info;
  H5Gget_info(loc, &info);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[256];
    H5Lget_name_by_idx(loc, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    const std::string path = prefix + "/" + name;
    H5O_info_t oinfo;
    H5Oget_info_by_name(loc, name, &oinfo, H5P_DEFAULT);
    if (oinfo.type == H5O_TYPE_GROUP) {
      const hid_t g = H5Gopen2(loc, name, H5P_DEFAULT);
      collect(g, path, out);
      H5Gclose(g);
    } else if (oinfo.type == H5O_TYPE_DATASET) {
      const hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
      const hid_t type = H5Dget_type(ds);
      const hid_t space = H5Dget_space(ds);
      const auto n =
          static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)) * H5Tget_size(type);
      std::vector<unsigned char> bytes(n);
      if (n > 0) H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data());
      out[path] = std::move(bytes);
      H5Sclose(space);
      H5Tclose(type);
      H5Dclose(ds);
    }
  }
}

std::map<std::string, std::vector<unsigned char>> datasets(const std::string& file) {
  std::map<std::string, std::vector<unsigned char>> out;
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0) << file;
  if (f < 0) return out;
  collect(f, "", out);
  H5Fclose(f);
  return out;
}

// A 4 × 4 × 4 block of 1 cm voxels with a muscle along x and a visual surface on top.
std::string write_model(const TempDir& dir) {
  const auto path = dir / "block.h5";
  formats::write_model(testing::small_box(true, true), path);
  return path;
}

const char* kMuscleScene = R"(
model: block.h5
effects: [elasticity, hourglass, damping, muscles, loads]
duration: 0.3
damping: 10
precision: double
muscles:
  flexor: {ramp: 0.1, hold: 0.1, release: 0.05}
boundary_conditions:
  - {type: fixed, set: x_min}
  - {type: force, set: x_max, value: [0, 0, -0.02], curve: [[0, 0], [0.2, 1]]}
output:
  interval: 0.02
  fields: [stress, J, energy_density, surfaces]
  probe_interval: 0.01
probes:
  - {name: tip, type: displacement, point: [0.04, 0.02, 0.04]}
  - {name: wall, type: reaction, set: x_min}
)";

// Writes the block model and kMuscleScene into dir; returns the scene's path.
std::string write_muscle_scene(const TempDir& dir) {
  write_model(dir);
  write_file(dir / "scene.yaml", kMuscleScene);
  return dir / "scene.yaml";
}

using testing::options_for;

TEST(Runner, ResumedRunIsBitIdenticalToAnUninterruptedOne) {
  TempDir dir("restart");
  const std::string scene = write_muscle_scene(dir);

  auto full = options_for(scene, dir / "full");
  full.threads = 2;
  const auto a = run_scene(full);
  ASSERT_EQ(a.summary.status, "completed");
  ASSERT_GT(a.summary.steps_done, 60);

  // Cut at a step that is neither a frame nor a probe step, then resume on another thread count.
  auto first = options_for(scene, dir / "cut");
  first.threads = 2;
  first.stop_at_step = 37;
  const auto b = run_scene(first);
  EXPECT_EQ(b.summary.status, "interrupted");
  EXPECT_EQ(b.summary.steps_done, 37);
  ASSERT_TRUE(std::filesystem::exists(dir / "cut/checkpoint.h5"));

  auto second = options_for(scene, dir / "cut");
  second.threads = 1;
  second.restart = dir / "cut/checkpoint.h5";
  const auto c = run_scene(second);
  EXPECT_EQ(c.summary.status, "completed");
  EXPECT_EQ(c.summary.restart_step, 37);
  EXPECT_EQ(c.summary.steps_this_run, a.summary.steps_done - 37);
  EXPECT_EQ(c.summary.steps_done, a.summary.steps_done);
  EXPECT_EQ(c.summary.frames, a.summary.frames);
  EXPECT_EQ(c.summary.energies.size(), a.summary.energies.size());

  const auto da = datasets(dir / "full/results.h5");
  const auto dc = datasets(dir / "cut/results.h5");
  ASSERT_EQ(da.size(), dc.size());
  for (const auto& [name, bytes] : da) {
    ASSERT_TRUE(dc.count(name)) << name;
    EXPECT_TRUE(bytes == dc.at(name))
        << name << " differs between the uninterrupted and the resumed run";
  }
  EXPECT_GT(da.at("/frames/displacement").size(), 0u);
  EXPECT_EQ(read_file(dir / "full/probe_tip.csv"), read_file(dir / "cut/probe_tip.csv"));
  EXPECT_EQ(read_file(dir / "full/probe_wall.csv"), read_file(dir / "cut/probe_wall.csv"));
  EXPECT_EQ(read_file(dir / "full/results.xdmf"), read_file(dir / "cut/results.xdmf"));
  // The run did something: the tip moved.
  EXPECT_NE(read_file(dir / "full/probe_tip.csv").find("\n0.29"), std::string::npos);
}

// The same on the CUDA backend (its default assembly, gather or tiled, is deterministic), where a device is.
TEST(Runner, ResumedCudaRunIsBitIdentical) {
  if (!cuda_device_available()) GTEST_SKIP() << "no CUDA device";
  TempDir dir("restart_cuda");
  const std::string scene = write_muscle_scene(dir);
  auto full = options_for(scene, dir / "full");
  full.device = "cuda";
  const auto a = run_scene(full);
  ASSERT_EQ(a.summary.status, "completed");
  auto first = options_for(scene, dir / "cut");
  first.device = "cuda";
  first.stop_at_step = 41;
  run_scene(first);
  auto second = options_for(scene, dir / "cut");
  second.device = "cuda";
  second.restart = dir / "cut/checkpoint.h5";
  const auto c = run_scene(second);
  ASSERT_EQ(c.summary.status, "completed");
  const auto da = datasets(dir / "full/results.h5");
  const auto dc = datasets(dir / "cut/results.h5");
  ASSERT_EQ(da.size(), dc.size());
  for (const auto& [name, bytes] : da) {
    ASSERT_TRUE(dc.count(name)) << name;
    EXPECT_TRUE(bytes == dc.at(name)) << name << " differs";
  }
  EXPECT_EQ(read_file(dir / "full/probe_wall.csv"), read_file(dir / "cut/probe_wall.csv"));
}

// A run that takes its model from a ModelCache (sinew-sweep) is the run sinew-simulate makes: the
// same files bit for bit, and its checkpoint's digest is the one an uncached run computes, so each
// resumes the other's checkpoint.
TEST(Runner, ARunThroughTheModelCacheIsTheSameRun) {
  TempDir dir("model_cache_run");
  const std::string scene = write_muscle_scene(dir);
  const auto plain = run_scene(options_for(scene, dir / "plain"));
  ASSERT_EQ(plain.summary.status, "completed");

  ModelCache models;
  auto first = options_for(scene, dir / "cached");
  first.models = &models;
  first.stop_at_step = 37;
  EXPECT_EQ(run_scene(first).summary.status, "interrupted");
  auto second = options_for(scene, dir / "cached");  // no cache: the digest from the file
  second.restart = dir / "cached/checkpoint.h5";
  const auto resumed = run_scene(second);
  EXPECT_EQ(resumed.summary.status, "completed");
  EXPECT_EQ(resumed.summary.restart_step, 37);

  auto whole = options_for(scene, dir / "whole");
  whole.models = &models;
  EXPECT_EQ(run_scene(whole).summary.steps_done, plain.summary.steps_done);
  for (const char* out : {"cached", "whole"}) {
    const auto got = datasets(dir / (std::string(out) + "/results.h5"));
    const auto want = datasets(dir / "plain/results.h5");
    ASSERT_EQ(got.size(), want.size()) << out;
    for (const auto& [name, bytes] : want)
      EXPECT_TRUE(got.count(name) && bytes == got.at(name)) << out << ": " << name;
    EXPECT_EQ(read_file(dir / (std::string(out) + "/probe_wall.csv")),
              read_file(dir / "plain/probe_wall.csv"))
        << out;
  }
}

TEST(Runner, RestartRefusesAnotherScene) {
  TempDir dir("restart_digest");
  const std::string scene = write_muscle_scene(dir);
  auto first = options_for(scene, dir / "out");
  first.stop_at_step = 5;
  run_scene(first);
  write_file(dir / "scene.yaml", std::string(kMuscleScene) + "title: changed\n");
  auto second = options_for(scene, dir / "out");
  second.restart = dir / "out/checkpoint.h5";
  EXPECT_THROW(run_scene(second), ConfigError);
  write_file(dir / "scene.yaml", kMuscleScene);
  second.precision = Precision::float32;
  EXPECT_THROW(run_scene(second), ConfigError);
}

// The checkpoint of `scene` run into `out` and interrupted at step 30.
std::string checkpoint_at_step_30(const std::string& scene, const std::string& out) {
  auto first = options_for(scene, out);
  first.stop_at_step = 30;
  EXPECT_EQ(run_scene(first).summary.status, "interrupted");
  return out + "/checkpoint.h5";
}

// A checkpoint damaged on disk (one bit of /u) is refused by name before anything is restored or
// written; it restarted with exit 0 and a last frame off by 2.4e-5 m (issue 33).
TEST(Runner, RestartRefusesACheckpointWithAFlippedBit) {
  TempDir dir("restart_flip");
  const std::string scene = write_muscle_scene(dir);
  const std::string ckpt = checkpoint_at_step_30(scene, dir / "out");
  {
    const hid_t f = H5Fopen(ckpt.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t ds = H5Dopen2(f, "/u", H5P_DEFAULT);
    const hid_t space = H5Dget_space(ds);
    std::vector<double> u(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    ASSERT_GE(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, u.data()), 0);
    std::uint64_t bits;
    std::memcpy(&bits, &u[u.size() - 1], sizeof bits);
    bits ^= std::uint64_t{1} << 40;
    std::memcpy(&u[u.size() - 1], &bits, sizeof bits);
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, u.data()), 0);
    H5Sclose(space);
    H5Dclose(ds);
    H5Fclose(f);
  }
  const auto results_before = read_file(dir / "out/results.h5");
  auto second = options_for(scene, dir / "out");
  second.restart = ckpt;
  try {
    run_scene(second);
    FAIL() << "a damaged checkpoint was restarted";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.file(), ckpt);
    EXPECT_EQ(e.field(), "/u");
  }
  EXPECT_EQ(read_file(dir / "out/results.h5"), results_before);
}

// A state whose digests are intact but whose step, time and Δt disagree with each other or with
// the run: a step of 1e15 "completed" at once with 1.24e10 s simulated (issue 33).
TEST(Runner, RestartRefusesAStepOrTimeThatDoesNotFitTheRun) {
  TempDir dir("restart_clock");
  const std::string scene = write_muscle_scene(dir);
  const std::string ckpt = checkpoint_at_step_30(scene, dir / "out");
  const auto written = read_checkpoint(ckpt);
  const auto refused = [&](std::int64_t step, double time, const char* field) {
    auto c = written;
    c.state.step = step;
    c.state.time = time;
    write_checkpoint(dir / "edited.h5", c);
    auto second = options_for(scene, dir / "out");
    second.restart = dir / "edited.h5";
    try {
      run_scene(second);
      ADD_FAILURE() << "restarted at step " << step << ", t = " << time;
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.file(), dir / "edited.h5");
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  const double dt = written.state.dt;
  refused(1'000'000'000'000'000, 1e15 * dt, "step");  // consistent, but past the plan
  refused(30, 31 * dt, "state.time");                 // one step's time off
  refused(29, 30 * dt, "state.time");                 // the step changed, not the time
  refused(30, -30 * dt, "state.time");
  // The unedited state still restarts.
  auto second = options_for(scene, dir / "out");
  second.restart = ckpt;
  EXPECT_EQ(run_scene(second).summary.status, "completed");
}

TEST(Runner, CheckpointEveryNStepsKeepsTheLatest) {
  TempDir dir("checkpoint_every");
  const std::string scene = write_muscle_scene(dir);
  auto o = options_for(scene, dir / "out");
  o.checkpoint_every = 20;
  o.stop_at_step = 50;
  run_scene(o);
  // The interruption at 50 writes the last checkpoint; at 20 and 40 the periodic ones came first.
  const hid_t f = H5Fopen((dir / "out/checkpoint.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::int64_t step = -1;
  const hid_t a = H5Aopen(f, "step", H5P_DEFAULT);
  H5Aread(a, H5T_NATIVE_INT64, &step);
  H5Aclose(a);
  H5Fclose(f);
  EXPECT_EQ(step, 50);
}

TEST(Runner, InstabilityStopsWithAClearErrorAndValidFrames) {
  TempDir dir("unstable");
  write_model(dir);
  write_file(dir / "probe.yaml",
             "model: block.h5\neffects: [elasticity, hourglass]\nduration: 1\n");
  auto plan_only = options_for(dir / "probe.yaml", "");
  plan_only.run = false;
  const double dt_crit = run_scene(plan_only).summary.dt_critical;
  ASSERT_GT(dt_crit, 0);

  // A free block kicked at 3 × the critical step must blow up.
  write_file(dir / "scene.yaml", fmt::format(R"(
model: block.h5
effects: [elasticity, hourglass]
duration: 1
time_step: {{mode: fixed, value: {}, force: true}}
node_sets:
  corner: {{nodes: [0]}}
initial_velocity:
  - {{set: corner, value: [0.5, -0.3, 0.2]}}
output: {{interval: {}}}
)",
                                             3 * dt_crit, 2 * dt_crit));
  auto o = options_for(dir / "scene.yaml", dir / "out");
  try {
    run_scene(o);
    FAIL() << "expected an InstabilityError";
  } catch (const InstabilityError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("step"), std::string::npos) << what;
  }
  const auto summary = nlohmann::json::parse(read_file(dir / "out/run_summary.json"));
  EXPECT_EQ(summary["status"], "unstable");
  EXPECT_FALSE(summary["message"].get<std::string>().empty());
  // The frames written before the blow-up are complete and finite.
  const hid_t f = H5Fopen((dir / "out/results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const auto d = datasets(dir / "out/results.h5");
  const auto& u = d.at("/frames/displacement");
  ASSERT_GE(u.size(), sizeof(double));
  std::vector<double> values(u.size() / sizeof(double));
  std::memcpy(values.data(), u.data(), u.size());
  for (double v : values) ASSERT_TRUE(std::isfinite(v));
  const auto frames = d.at("/frames/time").size() / sizeof(double);
  EXPECT_EQ(values.size(), frames * 125 * 3);
  H5Fclose(f);
  EXPECT_EQ(summary["frames"].get<std::size_t>(), frames);
}

TEST(Runner, ExplainPrintsThePlanAndWritesNothing) {
  TempDir dir("explain");
  const std::string scene = write_muscle_scene(dir);
  auto o = options_for(scene, dir / "out");
  std::string text;
  o.print = [&](const std::string& s) { text += s; };
  o.explain = true;
  o.run = false;
  const auto r = run_scene(o);
  EXPECT_FALSE(r.ran);
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  EXPECT_NE(text.find("Time step"), std::string::npos) << text;
  EXPECT_NE(text.find("probe 'tip'"), std::string::npos) << text;
  EXPECT_NE(text.find("muscle"), std::string::npos) << text;
}

// --device cuda runs on the CUDA backend where there is a device, and is refused clearly where
// there is none (or the build has no CUDA backend).
TEST(Runner, CudaDeviceRunsOrIsAClearError) {
  TempDir dir("cuda");
  const std::string scene = write_muscle_scene(dir);
  auto o = options_for(scene, dir / "out");
  o.device = "cuda";
  if (cuda_device_available()) {
    const auto r = run_scene(o);
    EXPECT_EQ(r.summary.status, "completed");
    EXPECT_EQ(r.summary.device.rfind("cuda", 0), 0u) << r.summary.device;
    return;
  }
  try {
    run_scene(o);
    FAIL();
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find("CUDA"), std::string::npos) << e.what();
    EXPECT_EQ(e.field(), "--device");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

TEST(Runner, TimeStepAboveTheEstimateIsRefusedUnlessForced) {
  TempDir dir("dt_refused");
  write_model(dir);
  write_file(dir / "scene.yaml",
             "model: block.h5\neffects: [elasticity]\nduration: 0.01\ntime_step: 1.0\n");
  try {
    run_scene(options_for(dir / "scene.yaml", dir / "out"));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), dir / "scene.yaml");
    EXPECT_EQ(e.field(), "time_step.value") << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

// With time scaling s the engine runs s × the duration, and every output speaks scene time.
TEST(Runner, TimeScalingKeepsOutputsInSceneTime) {
  TempDir dir("time_scaling");
  write_model(dir);
  write_file(dir / "scene.yaml",
             "model: block.h5\neffects: [elasticity, hourglass, loads]\nduration: 0.05\n"
             "time_scaling: 2\nboundary_conditions:\n  - {type: fixed, set: x_min}\n"
             "  - {type: force, set: x_max, value: [0, 0, -0.01], curve: {ramp: 0.05}}\n"
             "output: {interval: 0.01}\n");
  const auto r = run_scene(options_for(dir / "scene.yaml", dir / "out"));
  ASSERT_EQ(r.summary.status, "completed");
  EXPECT_EQ(r.summary.steps_done, static_cast<std::int64_t>(std::ceil(0.1 / r.summary.dt - 1e-9)));
  EXPECT_GE(r.summary.simulated_time, 0.05);
  EXPECT_LT(r.summary.simulated_time, 0.05 + r.summary.dt);
  EXPECT_EQ(r.summary.frames, 6);  // 0, 0.01, ..., 0.05
  const auto d = datasets(dir / "out/results.h5");
  std::vector<double> t(d.at("/frames/time").size() / sizeof(double));
  std::memcpy(t.data(), d.at("/frames/time").data(), t.size() * sizeof(double));
  ASSERT_EQ(t.size(), 6u);
  for (std::size_t k = 1; k + 1 < t.size(); ++k) {
    EXPECT_GE(t[k], 0.01 * double(k) - 1e-12);
    EXPECT_LT(t[k], 0.01 * double(k) + r.summary.dt / 2);  // scene time = simulated / 2
  }
  EXPECT_EQ(r.summary.energies.back().time, t.back());
}

// The largest hourglass share of a run's frames as runner.hpp defines it, written out here: the
// hourglass energy over the elastic energy, the latter at least 10% of the run's largest.
double worst_hourglass_share(const std::vector<Energies>& energies) {
  double peak = 0, worst = 0;
  for (const auto& e : energies) peak = std::max(peak, e.elastic);
  for (const auto& e : energies)
    if (peak > 0) worst = std::max(worst, e.hourglass / std::max(e.elastic, 0.1 * peak));
  return worst;
}

// The rule on made-up frames: the onset of a load (both energies tiny, their ratio large) is not
// judged; a frame whose strain energy is negative (a contracting muscle) is; frames without a
// finite elastic energy (a summary written before it was reported) are skipped.
TEST(Runner, HourglassRuleJudgesTheElasticEnergyAboveAFloor) {
  const auto frame = [](double strain, double elastic, double hourglass) {
    Energies e;
    e.strain = strain;
    e.elastic = elastic;
    e.hourglass = hourglass;
    return e;
  };
  // Onset: 50% of an elastic energy that is 0.1% of the run's largest; then 8% at most.
  std::vector<Energies> run{frame(0, 0, 0), frame(-0.002, 0.001, 0.0005), frame(-2, 1, 0.08),
                            frame(-1.5, 0.8, 0.06), frame(0.3, 0.3, 0.02)};
  EXPECT_EQ(first_hourglass_dominated(run), run.size());
  EXPECT_LT(worst_hourglass_share(run), kHourglassWarningShare);
  // 12% of the elastic energy while the strain energy is negative: found, and not before.
  run.push_back(frame(-0.5, 0.5, 0.06));
  EXPECT_EQ(first_hourglass_dominated(run), run.size() - 1);
  // Past the onset the floor (10% of the largest, 0.1 J) counts: 0.011 J is 11% of it.
  run.insert(run.begin() + 2, frame(-0.02, 0.01, 0.011));
  EXPECT_EQ(first_hourglass_dominated(run), 2u);
  // A frame without an elastic energy is skipped, whatever its strain energy says.
  std::vector<Energies> old{frame(1, std::nan(""), 0.5), frame(1, 1, 0.01)};
  EXPECT_EQ(first_hourglass_dominated(old), old.size());
}

// Compression to 30% of height with the default `shear` hourglass modulus folds the one-point
// elements into hourglass patterns that keep every centre J > 0 (docs/stability.md, limit 2): the
// run must say so (hourglass energy over 10% of the elastic energy, here the strain energy), while
// a mild compression must not warn.
TEST(Runner, HourglassDominatedRunIsFlagged) {
  for (const double squash : {0.1, 0.75}) {
    TempDir dir("hourglass_warning");
    write_model(dir);
    write_file(dir / "scene.yaml",
               fmt::format("model: block.h5\neffects: [elasticity, hourglass, damping, loads]\n"
                           "duration: 0.6\ndamping: 40\ntime_step: {{mode: auto, safety_factor: "
                           "0.2}}\nnode_sets:\n  lid: {{plane: {{point: [0, 0, 0.04], normal: "
                           "[0, 0, 1]}}}}\nboundary_conditions:\n  - {{type: fixed, set: z_min}}\n"
                           "  - {{type: displacement, set: lid, components: [z], value: [0, 0, "
                           "{}], curve: {{ramp: 0.5}}}}\noutput: {{interval: 0.02}}\n",
                           -0.04 * squash));
    const auto r = run_scene(options_for(dir / "scene.yaml", dir / "out"));
    ASSERT_EQ(r.summary.status, "completed") << squash;
    bool warned = false;
    for (const auto& w : r.summary.warnings)
      warned = warned || w.find("hourglass energy is") != std::string::npos;
    for (const auto& e : r.summary.energies) EXPECT_EQ(e.elastic, e.strain);  // no muscles
    const double worst = worst_hourglass_share(r.summary.energies);
    EXPECT_EQ(warned, worst > kHourglassWarningShare) << squash << ": worst share " << worst;
    EXPECT_EQ(warned, squash > 0.5) << squash << ": worst share " << worst;
    RecordProperty(fmt::format("worst_share_{}", squash), fmt::format("{:.3f}", worst));
  }
}

// A contracting muscle (the block's flexor along x, fixed at x_min) reports a negative strain
// energy: its active potential outweighs what the tissue stores. The hourglass check measures the
// hourglass energy against the stored (elastic) energy, so it is made in such a run too (it was
// skipped while the strain energy was negative, issue 34): with the hourglass stiffness raised to
// κ = 10, the fixed face's bilinear shear (an hourglass shape) holds 25% of it and the run warns at
// a frame whose strain energy is negative; with the default κ = 0.075 it is 2.4% and the run does
// not warn. The warning names the frame first_hourglass_dominated finds.
TEST(Runner, HourglassCheckIsMadeInAContractingMuscleRun) {
  for (const double kappa : {0.075, 10.0}) {
    TempDir dir("hourglass_muscle");
    write_model(dir);
    write_file(dir / "scene.yaml",
               fmt::format("model: block.h5\neffects: [elasticity, hourglass, damping, muscles]\n"
                           "duration: 0.2\ndamping: 20\nhourglass: {{kappa: {}}}\nmuscles:\n"
                           "  flexor: {{ramp: 0.05, peak: 1}}\nboundary_conditions:\n"
                           "  - {{type: fixed, set: x_min}}\noutput: {{interval: 0.02}}\n",
                           kappa));
    const auto r = run_scene(options_for(dir / "scene.yaml", dir / "out"));
    ASSERT_EQ(r.summary.status, "completed") << kappa;
    std::string warning;
    for (const auto& w : r.summary.warnings)
      if (w.find("hourglass energy is") != std::string::npos) warning = w;
    int contracting = 0;
    for (const auto& e : r.summary.energies) {
      EXPECT_GE(e.elastic, 0.0);
      if (e.strain < 0 && e.elastic > 0) ++contracting;
    }
    const double worst = worst_hourglass_share(r.summary.energies);
    const std::size_t k = first_hourglass_dominated(r.summary.energies);
    const Energies* first = k < r.summary.energies.size() ? &r.summary.energies[k] : nullptr;
    EXPECT_EQ(first != nullptr, worst > kHourglassWarningShare) << kappa << ": " << worst;
    EXPECT_GT(contracting, 3) << kappa;  // the old check (strain > 0) skipped these frames
    EXPECT_EQ(!warning.empty(), first != nullptr) << kappa << ": worst share " << worst;
    EXPECT_EQ(!warning.empty(), kappa > 1) << kappa << ": worst share " << worst;
    if (first) {
      EXPECT_LT(first->strain, 0.0) << warning;
      EXPECT_NE(warning.find(fmt::format("(step {})", first->step)), std::string::npos) << warning;
      EXPECT_NE(warning.find("of the elastic energy"), std::string::npos) << warning;
    }
    RecordProperty(fmt::format("worst_share_{}", kappa), fmt::format("{:.3f}", worst));
    std::printf(
        "[ measured ] contracting muscle, hourglass kappa %g: worst hourglass / elastic "
        "%.3f, %d of %zu frames with strain < 0 < elastic\n",
        kappa, worst, contracting, r.summary.energies.size());
  }
}

TEST(Runner, MissingModelNamesTheFile) {
  TempDir dir("nomodel");
  write_file(dir / "scene.yaml", "model: nowhere.h5\neffects: [elasticity]\nduration: 1\n");
  try {
    run_scene(options_for(dir / "scene.yaml", dir / "out"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nowhere.h5"), std::string::npos) << e.what();
  }
}

// The last row of a probe CSV as numbers: time, step, x, y, z.
std::vector<double> last_row(const std::string& path) {
  const auto text = read_file(path);
  const auto end = text.find_last_not_of('\n');
  const auto start = text.rfind('\n', end);
  std::vector<double> v(5);
  std::sscanf(text.c_str() + start + 1, "%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4]);
  return v;
}

// The shipped verification scene reproduces physics-notes §7 (uniaxial stretch 1.5, ν = 0.49):
// P11 = 1043.71 Pa and lateral stretch 0.820731, from the probes alone.
TEST(Runner, UniaxialVerificationSceneMatchesTheClosedForm) {
  TempDir dir("uniaxial");
  formats::BoxSpec
      spec;  // sinew-generate box --dims 4 4 4 --voxel-size 0.0025 --material tissue:2980:0.49:1000
  spec.dims = {4, 4, 4};
  spec.voxel_size = 0.0025;
  spec.materials = {formats::make_neo_hookean_material("tissue", 2980, 0.49, 1000)};
  spec.created = "2026-01-01T00:00:00Z";
  formats::write_model(formats::make_box_model(spec), dir / "uniaxial_block.h5");
  std::filesystem::copy_file(
      std::string(SINEW_SOURCE_DIR) + "/data/scenes/uniaxial_verification.yaml",
      dir / "scene.yaml");
  const auto r = run_scene(options_for(dir / "scene.yaml", dir / "out"));
  ASSERT_EQ(r.summary.status, "completed");
  const auto pull = last_row(dir / "out/probe_pull.csv");
  const auto corner = last_row(dir / "out/probe_corner.csv");
  const double area = 0.01 * 0.01;
  EXPECT_NEAR(pull[2] / area, 1043.71, 1e-3 * 1043.71);
  EXPECT_NEAR((0.01 + corner[3]) / 0.01, 0.820731, 1e-3 * 0.820731);
  EXPECT_NEAR((0.01 + corner[4]) / 0.01, 0.820731, 1e-3 * 0.820731);
  EXPECT_NEAR((0.01 + corner[2]) / 0.01, 1.5, 1e-12);
  // At rest: kinetic energy far below the strain energy.
  const auto& e = r.summary.energies.back();
  EXPECT_LT(e.kinetic, 1e-9 * e.strain);
}

// The shipped muscle scene runs: the free end shortens while the muscle is active.
TEST(Runner, MuscleBlockSceneContracts) {
  TempDir dir("muscle_scene");
  formats::BoxSpec spec;  // as in the scene file's header
  spec.dims = {12, 3, 3};
  spec.voxel_size = 0.002;
  spec.materials = {formats::make_neo_hookean_material("muscle", 500000, 0.49, 11000)};
  formats::BoxMuscleSpec m;
  m.name = "flexor";
  m.element_max = {12, 3, 3};
  m.fibre = {1, 0, 0};
  spec.muscles = {m};
  spec.created = "2026-01-01T00:00:00Z";
  formats::write_model(formats::make_box_model(spec), dir / "muscle_block.h5");
  std::filesystem::copy_file(std::string(SINEW_SOURCE_DIR) + "/data/scenes/muscle_block.yaml",
                             dir / "scene.yaml");
  const auto r = run_scene(options_for(dir / "scene.yaml", dir / "out"));
  ASSERT_EQ(r.summary.status, "completed");
  const auto text = read_file(dir / "out/probe_free_end.csv");
  double min_ux = 0;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    double t, step, ux;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf", &t, &step, &ux) == 3)
      min_ux = std::min(min_ux, ux);
  }
  EXPECT_LT(min_ux, -1e-3);  // shortened by more than a millimetre
}

// The engine a run is given, counting the runner's step() calls (everything else passed on).
class CountingBackend : public Backend {
 public:
  explicit CountingBackend(std::unique_ptr<Backend> inner, int* calls)
      : inner_(std::move(inner)), calls_(calls) {}
  std::string name() const override { return inner_->name(); }
  const Plan& plan() const override { return inner_->plan(); }
  void step(std::int64_t n) override {
    ++*calls_;
    inner_->step(n);
  }
  std::int64_t step_index() const override { return inner_->step_index(); }
  std::int64_t preferred_step_count() const override { return inner_->preferred_step_count(); }
  double time() const override { return inner_->time(); }
  double dt() const override { return inner_->dt(); }
  State state() const override { return inner_->state(); }
  void restore(const State& s) override { inner_->restore(s); }
  std::vector<double> displacements() const override { return inner_->displacements(); }
  std::vector<double> displacements(const std::vector<Index>& nodes) const override {
    return inner_->displacements(nodes);
  }
  std::vector<double> velocities() const override { return inner_->velocities(); }
  std::vector<double> internal_forces() override { return inner_->internal_forces(); }
  std::array<double, 3> reaction(const std::vector<Index>& nodes) override {
    return inner_->reaction(nodes);
  }
  Energies energies() override { return inner_->energies(); }
  ElementFields element_fields() override { return inner_->element_fields(); }
  void set_activation_override(std::size_t m, std::optional<double> a) override {
    inner_->set_activation_override(m, a);
  }
  std::optional<double> activation_override(std::size_t m) const override {
    return inner_->activation_override(m);
  }
  std::size_t force_slot_count() const override { return inner_->force_slot_count(); }
  void set_force_slot(std::size_t k, const std::vector<Index>& nodes,
                      const std::array<double, 3>& force) override {
    inner_->set_force_slot(k, nodes, force);
  }
  void clear_force_slot(std::size_t k) override { inner_->clear_force_slot(k); }
  Frame frame(bool with_fields) override { return inner_->frame(with_fields); }

 private:
  std::unique_ptr<Backend> inner_;
  int* calls_;
};

// A scene without probes steps in the engine's batches between frames: the default probe schedule
// (every step) applies only where there are probes, or a GPU would run one step per call.
TEST(Runner, AnUnprobedSceneStepsInBatches) {
  TempDir dir("batches");
  write_model(dir);
  std::string scene = kMuscleScene;
  scene = scene.substr(0, scene.find("  probe_interval:"));
  write_file(dir / "scene.yaml", scene);
  int calls = 0;
  auto o = options_for(dir / "scene.yaml", dir / "out");
  o.make_backend = [&](const formats::Model& model, const simulator::Setup& setup) {
    return std::unique_ptr<Backend>(
        std::make_unique<CountingBackend>(make_cpu_backend(model, setup), &calls));
  };
  const auto r = run_scene(o);
  ASSERT_EQ(r.summary.status, "completed");
  const std::int64_t steps = r.summary.steps_done;
  ASSERT_GT(steps, 200);
  // Each frame interval (0.02 s of 0.3: 15 frames after the first) takes its steps in batches of
  // up to 64: at most ceil(steps/64) + one per frame.
  EXPECT_LE(calls, steps / 64 + 1 + 16) << steps << " steps";
  EXPECT_FALSE(std::filesystem::exists(dir / "out/probe_tip.csv"));
}

}  // namespace
}  // namespace sinew::simulator
