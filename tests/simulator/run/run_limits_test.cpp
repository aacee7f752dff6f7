// Scene values that would overflow or stall a run (issue 20): a step count past int64, a billion
// steps, a frame or probe row every femtosecond. Each is refused before anything is written, with
// the scene key in the message, or runs in bounded time; --force (RunOptions::force) overrides
// the sane limits; the plan prints the frame count and the output size.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/run/run_limits.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::simulator {
namespace {

using testing::options_for;
using testing::read_file;
using testing::TempDir;
using testing::write_file;

// The 4 × 4 × 4 block (Δt ≈ 1.6 ms) and a scene with `extra` lines appended.
std::string write_scene(const TempDir& dir, const std::string& extra) {
  formats::write_model(testing::small_box(), dir / "block.h5");
  write_file(dir / "scene.yaml", "model: block.h5\neffects: [elasticity]\n" + extra);
  return dir / "scene.yaml";
}

// Runs and returns the ConfigError's field (FAILs when there is none); nothing may be written.
std::string refused_key(const RunOptions& o, const std::string& expect_in_message) {
  try {
    run_scene(o);
    ADD_FAILURE() << "the run was not refused";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), o.scene_path);
    EXPECT_NE(std::string(e.what()).find(expect_in_message), std::string::npos) << e.what();
    EXPECT_FALSE(std::filesystem::exists(o.output_dir)) << e.what();
    return e.field();
  }
  return "";
}

TEST(RunLimits, StepCountsPastInt64AreRefusedNamingTheKey) {
  TempDir dir("limits_overflow");
  auto o = options_for(write_scene(dir, "duration: 2e14\n"), dir / "out");
  EXPECT_EQ(refused_key(o, "more than a run can count"), "duration");
  o.force = true;  // not overridable: the count does not exist
  EXPECT_EQ(refused_key(o, "more than a run can count"), "duration");

  TempDir dir2("limits_scaling");
  o = options_for(write_scene(dir2, "duration: 0.5\ntime_scaling: 1e30\n"), dir2 / "out");
  EXPECT_EQ(refused_key(o, "time_scaling 1e+30"), "time_scaling");
}

TEST(RunLimits, ABillionStepsNeedsForce) {
  TempDir dir("limits_steps");
  auto o = options_for(write_scene(dir, "duration: 1e7\n"), dir / "out");
  EXPECT_EQ(refused_key(o, "--force"), "duration");
}

TEST(RunLimits, TooManyFramesOrProbeRowsNeedForce) {
  OutputCounts c;
  ResolvedScene scene;
  scene.setup.duration = 1;
  scene.output_interval = 1e-12;
  c.steps = 1e6;
  c.frames = 1e6 + 1;
  c.frame_bytes = 1000;
  try {
    check_output_limits(c, scene, "s.yaml", false);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "output.interval");
    EXPECT_NE(std::string(e.what()).find("1e+06 frames"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_output_limits(c, scene, "s.yaml", true));

  c.frames = 2;
  c.steps = 5e8;
  c.probes = 1;
  c.probe_rows = c.steps + 1;  // no probe_interval: a row every step
  try {
    check_output_limits(c, scene, "s.yaml", false);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "output.probe_interval");
    EXPECT_NE(std::string(e.what()).find("rows per probe"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_output_limits(c, scene, "s.yaml", true));
}

// An interval far below Δt gives one frame or row per step, in bounded time (it hung at
// probe_interval 1e-15 and slowed every step 150× at output.interval 1e-12).
TEST(RunLimits, IntervalsBelowTheStepGiveOneEventPerStepQuickly) {
  TempDir dir("limits_tiny");
  const auto scene =
      write_scene(dir,
                  "duration: 0.05\noutput: {interval: 1e-12, probe_interval: 1e-15}\nprobes:\n"
                  "  - {name: p, type: displacement, node: 0}\n");
  auto o = options_for(scene, dir / "out");
  std::string plan;
  o.explain = true;
  o.print = [&](const std::string& s) { plan += s; };
  const auto r = run_scene(o);
  ASSERT_EQ(r.summary.status, "completed");
  const auto steps = r.summary.steps_done;
  EXPECT_EQ(r.summary.frames, steps + 1);
  const auto csv = read_file(dir / "out/probe_p.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), steps + 2);  // header + a row per step
  EXPECT_NE(plan.find(std::to_string(steps + 1) + " frames of"), std::string::npos) << plan;
  EXPECT_NE(plan.find("rows per probe; about"), std::string::npos) << plan;
}

}  // namespace
}  // namespace sinew::simulator
