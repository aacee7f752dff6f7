// sinew::sweep: the sweep file's checks (every bad file fails before any run, naming the file and
// the key), the runs it plans, and running them: figures against a closed form, the same table
// bit for bit with runs at once, resuming, and failed runs recorded without stopping the sweep.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/runner.hpp"
#include "sinew/sweep/run_sweep.hpp"
#include "sinew/sweep/sweep_file.hpp"

namespace fs = std::filesystem;
using namespace sinew;

namespace {

// A 10 mm cube of 4 × 4 × 4 voxels (μ = 60 kPa, ν = 0.45, ρ = 1000 kg/m³: m = 1 g) on a fixed
// base under gravity, heavily damped so it settles within the 0.1 s run; its base then carries
// its weight, m g (the reaction probe).
constexpr double kMass = 1000.0 * 0.01 * 0.01 * 0.01;
constexpr const char* kScene = R"(title: cube under gravity
model: cube.h5
effects: [elasticity, hourglass, damping, gravity]
duration: 0.1
damping: 400
gravity: [0, 0, -9.81]
boundary_conditions:
  - {type: fixed, set: z_min}
output:
  interval: 0.05
probes:
  - {name: base, type: reaction, set: z_min}
  - {name: top, type: displacement, point: [0.005, 0.005, 0.01]}
)";

class SweepTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // One folder per test (parametrised names hold a '/').
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = fs::temp_directory_path() / ("sinew_sweep_test_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    formats::BoxSpec spec;
    spec.dims = {4, 4, 4};
    spec.voxel_size = 2.5e-3;
    spec.materials = {formats::make_neo_hookean_material_from_shear("tissue", 60e3, 0.45, 1000)};
    formats::write_model(formats::make_box_model(spec), (dir_ / "cube.h5").string());
    write("cube.yaml", kScene);
  }
  void TearDown() override { fs::remove_all(dir_); }

  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  sweep::Sweep parse(const std::string& text, bool yes = false) {
    write("sweep.yaml", text);
    sweep::ParseOptions o;
    o.yes = yes;
    return sweep::parse_sweep((dir_ / "sweep.yaml").string(), o);
  }
  // The ConfigError message of a bad sweep file ("" when it parses).
  std::string error_of(const std::string& text, bool yes = false) {
    try {
      parse(text, yes);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  }
  sweep::SweepOptions options(const std::string& out, int concurrent = 1) {
    sweep::SweepOptions o;
    o.output_dir = (dir_ / out).string();
    o.settings.device = "cpu";
    o.settings.concurrent = concurrent;
    o.quiet = true;
    return o;
  }
  std::string read(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

  fs::path dir_;
};

const char* kHeader = "version: 1\nscene: cube.yaml\n";

// A row's figures without the last, wall_time_s (the one figure that is not reproducible).
std::vector<std::optional<double>> reproducible(const sweep::Row& row) {
  return {row.figures.begin(), row.figures.end() - 1};
}

}  // namespace

TEST_F(SweepTest, BadSweepFilesNameTheFileAndKeyBeforeAnyRun) {
  const std::string h = kHeader;
  struct Case {
    std::string text, key, problem;
  };
  const Case cases[] = {
      {h + "grid: {dampin: [10, 20]}\n", "grid.dampin", "unknown key 'dampin'"},
      {h + "grid: {damping: []}\n", "grid.damping", "empty list of values"},
      {h + "grid: {}\n", "grid", "empty grid"},
      {h + "list: []\n", "list", "empty list"},
      {h + "grid: {damping: [ten]}\n", "grid.damping", "expected a number, got 'ten'"},
      {h + "grid: {damping: [-1]}\n", "grid.damping[0]",
       "run 0 (damping = -1): the scene's damping: must be > 0, got -1 (line 3)"},
      {h + "grid: {damping: 10}\n", "grid.damping", "expected a list of values"},
      {h + "grid:\n  probes[5].point: [[0, 0, 0]]\n", "grid.probes[5].point",
       "index 5 out of range"},
      {h + "grid: {output.nothing.x: [1]}\n", "grid.output.nothing.x", "no key 'nothing'"},
      {h + "list:\n  - {model: missing.h5}\n", "list[0].model", "does not exist"},
      {h + "grid: {damping: [1]}\nfigures:\n  - {name: f, probe: base, value: uq}\n",
       "figures[0].value", "unknown probe value 'uq'"},
      {h + "grid: {damping: [1]}\nfigures:\n  - {name: f, summary: steps}\n", "figures[0].summary",
       "unknown summary number"},
      {h + "grid: {damping: [1]}\nfigure: []\n", "figure", "unknown key 'figure'"},
      {h + "grid: {damping: [1]}\nrun: {concurrent: 0}\n", "run.concurrent", "must be in"},
      {"scene: cube.yaml\ngrid: {damping: [1]}\n", "", "missing key 'version'"},
      {"version: 1\nscene: nowhere.yaml\ngrid: {damping: [1]}\n", "scene", "does not exist"},
      {h, "", "nothing to sweep"},
  };
  for (const auto& c : cases) {
    const auto message = error_of(c.text);
    SCOPED_TRACE(c.text);
    EXPECT_NE(message.find("sweep.yaml"), std::string::npos) << message;
    EXPECT_NE(message.find(c.key), std::string::npos) << message;
    EXPECT_NE(message.find(c.problem), std::string::npos) << message;
  }
  // A million runs need --yes; refused at once, before any scene is made.
  std::string values;
  for (int i = 0; i < 1000; ++i) values += (i ? ", " : "") + std::to_string(i);
  const auto million = h + "grid:\n  damping: [" + values + "]\n  mass_scaling: [" + values + "]\n";
  const auto m = error_of(million);
  EXPECT_NE(m.find("1000000 runs: more than 1000 runs need --yes"), std::string::npos) << m;
  EXPECT_NE(m.find("sweep.yaml: grid"), std::string::npos) << m;
}

TEST_F(SweepTest, PlansTheProductOfListAndGridWithTheValuesInEachScene) {
  const auto sw =
      parse(std::string(kHeader) +
            "list:\n  - {duration: 0.05}\n  - {duration: 0.1, damping: 300}\n"
            "grid:\n  gravity: [[0, 0, -1], [0, 0, -2]]\n  output.interval: [0.01, 0.02, 0.05]\n");
  ASSERT_EQ(sw.runs.size(), 12u);
  EXPECT_EQ(sw.parameters,
            (std::vector<std::string>{"duration", "damping", "gravity", "output.interval"}));
  // The last grid key varies fastest, the list outermost.
  EXPECT_EQ(sw.runs[0].describe(),
            "run 0 (duration = 0.05, gravity = [0, 0, -1], output.interval = 0.01)");
  EXPECT_EQ(sw.runs[11].describe(),
            "run 11 (duration = 0.1, damping = 300, gravity = [0, 0, -2], output.interval = 0.05)");
  EXPECT_EQ(sw.runs[7].name, "run_0007");
  const auto& text = sw.runs[11].scene_text;
  EXPECT_NE(text.find("damping: 300"), std::string::npos) << text;
  EXPECT_NE(text.find("interval: 0.05"), std::string::npos) << text;
  EXPECT_NE(text.find("model: " + fs::absolute(dir_ / "cube.h5").lexically_normal().string()),
            std::string::npos)
      << text;
}

// The physics of a sweep on every backend: CPU always, CUDA when built with it (skipped without a
// device).
class SweepBackendTest : public SweepTest, public ::testing::WithParamInterface<std::string> {};

TEST_P(SweepBackendTest, GravityGridGivesTheWeightOnTheBaseAndTheSameTableWithRunsAtOnce) {
  const std::string device = GetParam();
  if (device == "cuda" && !simulator::cuda_device_available()) GTEST_SKIP() << "no CUDA device";
  // Several runs at once: on the GPU each engine on its own streams.
  const int at_once = device == "cuda" ? 3 : 2;
  const auto options = [&](const std::string& out, int concurrent) {
    auto o = SweepTest::options(out, concurrent);
    o.settings.device = device;
    return o;
  };
  const auto sw = parse(std::string(kHeader) +
                        "grid:\n  gravity: [[0, 0, -9.81], [0, 0, -3.7], [0, 0, -1.62]]\n"
                        "figures:\n  - {name: base_fz, probe: base, value: fz}\n"
                        "  - {name: top_uz_max, probe: top, value: uz, stat: max_abs}\n"
                        "  - {name: ke_end, energy: kinetic}\n");
  const auto one = sweep::run_sweep(sw, options("one", 1));
  ASSERT_EQ(one.rows.size(), 3u);
  EXPECT_EQ(one.ran, 3);
  EXPECT_EQ(one.failed, 0);
  const double g[] = {9.81, 3.7, 1.62};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(one.rows[i].status, "completed") << one.rows[i].message;
    ASSERT_TRUE(one.rows[i].figures[0]);
    // Settled: the base carries the weight m g (the damped run is within 1e-6 of rest).
    EXPECT_NEAR(*one.rows[i].figures[0], kMass * g[i], 1e-6 * kMass * g[i]) << i;
    EXPECT_GT(*one.rows[i].figures[1], 0.0);
  }
  // Runs at once in threads: the same figures, bit for bit (wall time aside).
  const auto two = sweep::run_sweep(sw, options("two", at_once));
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(two.rows[i].status, "completed") << two.rows[i].message;
    for (std::size_t f = 0; f + 1 < one.rows[i].figures.size(); ++f)
      EXPECT_EQ(one.rows[i].figures[f], two.rows[i].figures[f]) << i << " " << f;
  }
  const auto csv = read(dir_ / "one" / "sweep_table.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "run,status,message,gravity,base_fz,top_uz_max,ke_end,steps_done,wall_time_s");
  EXPECT_TRUE(fs::exists(dir_ / "one" / "sweep_table.json"));
  EXPECT_TRUE(fs::exists(dir_ / "one" / "run_0002" / "results.h5"));
}

INSTANTIATE_TEST_SUITE_P(Backends, SweepBackendTest, ::testing::Values("cpu", "cuda"),
                         [](const auto& info) { return info.param; });

TEST_F(SweepTest, RerunSkipsFinishedRunsAndRedoesTheOthers) {
  const auto text = std::string(kHeader) + "grid:\n  damping: [300, 400, 500]\n";
  const auto sw = parse(text);
  const auto first = sweep::run_sweep(sw, options("out"));
  EXPECT_EQ(first.ran, 3);
  const auto again = sweep::run_sweep(sw, options("out"));
  EXPECT_EQ(again.ran, 0);
  EXPECT_EQ(again.skipped, 3);
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_EQ(again.rows[i].figures, first.rows[i].figures);  // read back: wall time too
  // A run cut off (its summary says running) is redone; so is a run whose value changed.
  { std::ofstream(dir_ / "out" / "run_0001" / "run_summary.json") << R"({"status": "running"})"; }
  const auto changed = parse(std::string(kHeader) + "grid:\n  damping: [300, 400, 450]\n");
  const auto third = sweep::run_sweep(changed, options("out"));
  EXPECT_EQ(third.ran, 2);
  EXPECT_EQ(third.skipped, 1);
  EXPECT_EQ(third.rows[0].figures, first.rows[0].figures);              // skipped
  EXPECT_EQ(reproducible(third.rows[1]), reproducible(first.rows[1]));  // redone
  EXPECT_EQ(third.rows[2].values[0], "450");
}

TEST_F(SweepTest, UnstableAndFailingRunsAreRecordedAndTheSweepGoesOn) {
  const auto sw = parse(std::string(kHeader) +
                        "list:\n"
                        "  - {damping: 400}\n"
                        // A fixed step 20 times the critical one, forced: it blows up.
                        "  - {time_step: {mode: fixed, value: 0.002, force: true}}\n"
                        // A node set the model does not have: refused before the loop.
                        "  - {boundary_conditions: [{type: fixed, set: nowhere}]}\n"
                        "figures:\n  - {name: base_fz, probe: base, value: fz}\n");
  const auto r = sweep::run_sweep(sw, options("out"));
  ASSERT_EQ(r.rows.size(), 3u);
  EXPECT_EQ(r.rows[0].status, "completed");
  EXPECT_EQ(r.rows[1].status, "unstable");
  EXPECT_FALSE(r.rows[1].message.empty());
  EXPECT_EQ(r.rows[2].status, "failed");
  EXPECT_NE(r.rows[2].message.find("nowhere"), std::string::npos) << r.rows[2].message;
  EXPECT_FALSE(r.rows[2].figures[0]);  // no probe file
  EXPECT_EQ(r.failed, 2);
  // Both are finished: a rerun does not redo them.
  EXPECT_EQ(sweep::run_sweep(sw, options("out")).ran, 0);
  const auto csv = read(dir_ / "out" / "sweep_table.csv");
  EXPECT_NE(csv.find("run_0001,unstable,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("run_0002,failed,"), std::string::npos) << csv;
}

TEST_F(SweepTest, AnInterruptedRunGoesOnFromItsCheckpointToTheSameFigures) {
  const auto sw = parse(std::string(kHeader) +
                        "grid:\n  damping: [400]\n"
                        "figures:\n  - {name: base_fz, probe: base, value: fz}\n"
                        "  - {name: top_uz_max, probe: top, value: uz, stat: max_abs}\n");
  const auto clean = sweep::run_sweep(sw, options("clean"));
  // The same run stopped half-way with a checkpoint, as SIGTERM (or mpirun ending the job) does.
  const auto dir = dir_ / "out" / "run_0000";
  fs::create_directories(dir);
  std::ofstream(dir / "scene.yaml") << sw.runs[0].scene_text;
  simulator::RunOptions ro;
  ro.scene_path = (dir / "scene.yaml").string();
  ro.output_dir = dir.string();
  ro.device = "cpu";
  ro.quiet = true;
  ro.stop_at_step = 500;
  ASSERT_EQ(simulator::run_scene(ro).summary.status, "interrupted");
  const auto resumed = sweep::run_sweep(sw, options("out"));
  EXPECT_EQ(resumed.ran, 1);
  EXPECT_EQ(resumed.rows[0].status, "completed");
  EXPECT_NE(read(dir / "run_summary.json").find("\"restart_step\": 500"), std::string::npos);
  EXPECT_EQ(reproducible(resumed.rows[0]), reproducible(clean.rows[0]));
}

TEST_F(SweepTest, AnEmptyValueRemovesTheKeyAndTheBaseScenesOwnProblemsAreNamedAsItsOwn) {
  const auto sw = parse(std::string(kHeader) +
                        "list:\n  - {damping: ~, effects: [elasticity, hourglass, gravity]}\n");
  ASSERT_EQ(sw.runs.size(), 1u);
  EXPECT_EQ(sw.runs[0].scene_text.find("damping"), std::string::npos) << sw.runs[0].scene_text;
  EXPECT_EQ(sw.runs[0].describe(),
            "run 0 (damping = ~, effects = [elasticity, hourglass, gravity])");
  // A value that breaks another key of the scene is blamed on the run.
  const auto m = error_of(std::string(kHeader) + "list:\n  - {effects: [elasticity, gravity]}\n");
  EXPECT_NE(m.find("sweep.yaml: list[0].effects: run 0 (effects = [elasticity, gravity]): the "
                   "scene's damping: 'damping' is given but 'damping' is not in effects"),
            std::string::npos)
      << m;
  // A broken base scene is named as itself, before any run is planned.
  write("cube.yaml", std::string(kScene) + "dampin: 3\n");
  const auto b = error_of(std::string(kHeader) + "grid: {damping: [1]}\n");
  EXPECT_NE(b.find("cube.yaml: dampin: unknown key 'dampin'"), std::string::npos) << b;
}
