// A target the muscles cannot reach (issue 29; docs/fit.md, "A target the muscles cannot
// reach"): on the box of box_skin.hpp, two key shapes of its skin at 30 and 60 ms, sculpted from
// a run of the left muscle (activation 0.1 over 20 ms, held): the skin as that run moved it, and
// the right half of it pushed 2 mm further, into the block. The muscles lie along x in the top
// layers: contracting, they pull the skin along x and thicken the tissue, never push it in.
// sinew-fit's report must say so: the right half's markers about 2 mm from their targets, the
// left half's close to theirs, the worst markers in the summary all on the right; the left
// muscle recovered, the right one left near 0, every activation inside its bounds and every
// forward run completed (an inverted element stops a run, and the fit with it). A second case
// gives the targets as a marker CSV on the scene's probes and checks the same residual table.
// Bad target input leaves nothing under the output's name.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "box_skin.hpp"
#include "sinew/common/error.hpp"
#include "sinew/fit/fit_run.hpp"
#include "sinew/fit/response.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::fit {
namespace {
namespace fs = std::filesystem;

constexpr double kPush = 0.002;  // m, into the block, right half
constexpr double kHalf = 0.006;  // m, the y of the muscles' border

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
void write(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

std::string scene_text(const std::string& muscles, const std::string& extra) {
  return "title: unreachable target\nmodel: box_skin.h5\n"
         "effects: [elasticity, hourglass, damping, muscles]\nduration: 0.06\ndamping: 50\n"
         "muscles: " +
         muscles +
         "\nboundary_conditions:\n  - {type: fixed, set: x_min}\n"
         "  - {type: fixed, set: z_min}\n" +
         extra;
}

// CSV rows as name → cells.
std::map<std::string, std::vector<std::string>> table(const fs::path& p) {
  std::map<std::string, std::vector<std::string>> rows;
  std::istringstream in(read(p));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
    rows[cells.front()] = cells;
  }
  return rows;
}

class UnreachableTarget : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("sinew-fit-unreachable-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    model_ = testing::box_with_skin();
    formats::write_model(model_, (dir_ / "box_skin.h5").string());
    // The truth: the left muscle alone, its skin every 30 ms and four probes on the skin's
    // lattice points (two each side) every 30 ms.
    write(dir_ / "truth.yaml",
          scene_text("{left: [[0, 0], [0.02, 0.1]]}",
                     "output: {interval: 0.03, fields: [surfaces], probe_interval: 0.03}\n" +
                         probes_yaml()));
    simulator::RunOptions ro;
    ro.scene_path = (dir_ / "truth.yaml").string();
    ro.output_dir = (dir_ / "truth").string();
    ro.device = "cpu";
    ro.quiet = true;
    ro.print = [](const std::string&) {};
    ASSERT_EQ(simulator::run_scene(ro).summary.status, "completed");
    const auto skin = postprocess::read_surface((dir_ / "truth/results.h5").string(), "skin");
    ASSERT_EQ(skin.frame_count(), 3u);
    std::string manifest = "time,mesh\n";
    for (std::size_t f = 1; f < 3; ++f) {
      std::vector<formats::Point> v;
      for (std::size_t i = 0; i < skin.vertex_count(); ++i) {
        const bool right = model_.surfaces.front().vertices[i][1] > kHalf + 1e-9;
        v.push_back({skin.frames[f][3 * i], skin.frames[f][3 * i + 1],
                     skin.frames[f][3 * i + 2] - (right ? kPush : 0.0)});
      }
      const std::string name = "shape_" + std::to_string(f) + ".obj";
      write(dir_ / name, testing::skin_obj(model_.surfaces.front(), v));
      manifest += std::to_string(skin.times[f]) + "," + name + "\n";
    }
    write(dir_ / "targets.csv", manifest);
    write(dir_ / "base.yaml", scene_text("{}", probes_yaml()));
    // The same targets as a marker CSV on the probes (m, the scene's unit), the right ones
    // pushed 2 mm in.
    std::vector<ProbePath> paths;
    std::string csv = "time";
    for (const auto& [name, point] : kProbes) {
      paths.push_back(read_probe_path((dir_ / "truth" / ("probe_" + name + ".csv")).string()));
      csv += "," + name + ".x," + name + ".y," + name + ".z";
    }
    csv += "\n";
    for (std::size_t f = 1; f < paths.front().times.size(); ++f) {
      csv += std::to_string(paths.front().times[f]);
      for (std::size_t k = 0; k < kProbes.size(); ++k) {
        const auto& p = kProbes[k].second;
        const double push = p[1] > kHalf ? kPush : 0.0;
        csv += fmt::format(",{:.9g},{:.9g},{:.9g}", p[0] + paths[k].u[f][0],
                           p[1] + paths[k].u[f][1], p[2] + paths[k].u[f][2] - push);
      }
      csv += "\n";
    }
    write(dir_ / "markers.csv", csv);
  }
  static void TearDownTestSuite() {
    // SINEW_FIT_KEEP=DIR: a copy of the model, scenes, targets and fits there (to run sinew-fit
    // by hand: sinew-fit DIR/base.yaml --targets DIR/targets.csv -o fit).
    if (const char* keep = std::getenv("SINEW_FIT_KEEP"); keep && *keep)
      fs::copy(dir_, keep, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // Four displacement probes on lattice points of the top face (m): two over each muscle.
  static inline const std::vector<std::pair<std::string, formats::Point>> kProbes = {
      {"left_mid", {0.010, 0.002, 0.006}},
      {"left_end", {0.018, 0.004, 0.006}},
      {"right_mid", {0.010, 0.010, 0.006}},
      {"right_end", {0.018, 0.008, 0.006}}};
  static std::string probes_yaml() {
    std::string s = "probes:\n";
    for (const auto& [name, p] : kProbes)
      s += fmt::format("  - {{name: {}, type: displacement, point: [{}, {}, {}]}}\n", name, p[0],
                       p[1], p[2]);
    return s;
  }
  static FitOptions options(const std::string& out) {
    FitOptions o;
    o.scene_path = (dir_ / "base.yaml").string();
    o.targets_path = (dir_ / "targets.csv").string();
    o.output_dir = (dir_ / out).string();
    o.target_markers = 60;
    o.threads = 2;
    return o;
  }
  static fs::path dir_;
  static formats::Model model_;
};
fs::path UnreachableTarget::dir_;
formats::Model UnreachableTarget::model_;

TEST_F(UnreachableTarget, ReportSaysWhereAndHowFarWithActivationsInBounds) {
  const auto o = options("fit");
  const FitResult r = run_fit(o);
  const fs::path out = dir_ / "fit";
  ASSERT_TRUE(fs::exists(out / "marker_residual.csv"));
  // Every forward run completed (no element inverted); activations within [0, 1].
  EXPECT_EQ(r.forward_runs, o.corrections + 1);
  ASSERT_EQ(r.muscles, (std::vector<std::string>{"left", "right"}));
  for (const auto& curve : r.activations)
    for (const double a : curve) {
      EXPECT_GE(a, 0.0);
      EXPECT_LE(a, 1.0);
    }
  // The left muscle recovered at the held knot (0.1), the right one hardly used.
  EXPECT_NEAR(r.activations[0].back(), 0.1, 0.03);
  EXPECT_LT(r.activations[1].back(), 0.05);

  // Per marker: right half ≈ 2 mm (the push), left half well under it.
  const auto rows = table(out / "marker_residual.csv");
  ASSERT_EQ(rows.size(), 60u);
  double left_max = 0, right_min = 1e9, right_max = 0;
  int left = 0, right = 0;
  for (const auto& [name, cells] : rows) {
    const double y_mm = std::stod(cells[3]);
    const double rms = std::stod(cells[5]);
    // The vertex's own y (its marker's node may sit on the border row).
    const int vertex = std::stoi(cells[1]);
    const double vy = model_.surfaces.front().vertices[static_cast<std::size_t>(vertex)][1];
    (void)y_mm;
    if (vy > kHalf + 1e-9) {
      right_min = std::min(right_min, rms);
      right_max = std::max(right_max, rms);
      ++right;
    } else {
      left_max = std::max(left_max, rms);
      ++left;
    }
  }
  std::printf(
      "unreachable target: %d left markers RMS ≤ %.3f mm, %d right markers RMS %.3f–%.3f "
      "mm; marker RMS %.3f mm (max %.3f mm); activations at 60 ms: left %.3f, right %.3f\n",
      left, left_max, right, right_min, right_max, r.rms_mm, r.max_mm, r.activations[0].back(),
      r.activations[1].back());
  EXPECT_GT(left, 10);
  EXPECT_GT(right, 10);
  EXPECT_LT(left_max, 0.3);
  EXPECT_GT(right_min, 1.6);
  EXPECT_LT(right_max, 2.4);

  // The summary names the worst frame and the worst markers: all on the right half.
  const auto j = nlohmann::json::parse(read(out / "fit_summary.json"));
  ASSERT_TRUE(j.contains("worst_frame"));
  EXPECT_GT(j["worst_frame"]["rms_mm"].get<double>(), 1.0);
  ASSERT_EQ(j["worst_markers"].size(), 10u);
  for (const auto& w : j["worst_markers"]) {
    const int vertex = w["vertex"].get<int>();
    EXPECT_GT(model_.surfaces.front().vertices[static_cast<std::size_t>(vertex)][1], kHalf);
    EXPECT_GT(w["rms_mm"].get<double>(), 1.6);
  }
  EXPECT_EQ(j["targets"]["markers"].get<int>(), 60);
}

TEST_F(UnreachableTarget, MarkerCsvReportSaysTheSame) {
  auto o = options("fit_markers");
  o.targets_path.clear();
  o.markers_path = (dir_ / "markers.csv").string();
  const FitResult r = run_fit(o);
  EXPECT_EQ(r.forward_runs, o.corrections + 1);
  const auto rows = table(dir_ / "fit_markers" / "marker_residual.csv");
  ASSERT_EQ(rows.size(), 4u);
  for (const auto& [name, cells] : rows) {
    const double rms = std::stod(cells[5]);
    std::printf("marker CSV: %s at (%s, %s, %s) mm: RMS %.3f mm, max %s mm\n", name.c_str(),
                cells[2].c_str(), cells[3].c_str(), cells[4].c_str(), rms, cells[6].c_str());
    EXPECT_TRUE(cells[1].empty());  // no surface vertex
    if (name.rfind("right", 0) == 0) {
      EXPECT_GT(rms, 1.6);
      EXPECT_LT(rms, 2.4);
    } else {
      EXPECT_LT(rms, 0.3);
    }
  }
  const auto j = nlohmann::json::parse(read(dir_ / "fit_markers" / "fit_summary.json"));
  EXPECT_EQ(j["worst_markers"][0]["marker"].get<std::string>().rfind("right", 0), 0u);
  EXPECT_EQ(j["worst_markers"][1]["marker"].get<std::string>().rfind("right", 0), 0u);
  for (const auto& curve : r.activations)
    for (const double a : curve) {
      EXPECT_GE(a, 0.0);
      EXPECT_LE(a, 1.0);
    }
}

TEST_F(UnreachableTarget, MarkersAndTargetsExcludeEachOther) {
  auto both = options("bad_fit");
  both.markers_path = (dir_ / "markers.csv").string();
  auto neither = options("bad_fit");
  neither.targets_path.clear();
  for (const auto& [o, message] :
       {std::pair{both,
                  "--targets: give either markers (a CSV or a run's folder) or --targets, "
                  "not both"},
        std::pair{neither,
                  "markers: nothing to fit: give markers (a CSV or a run's folder) or "
                  "--targets"}}) {
    try {
      run_fit(o);
      ADD_FAILURE() << "no error";
    } catch (const ConfigError& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
    EXPECT_FALSE(fs::exists(dir_ / "bad_fit"));
  }
}

TEST_F(UnreachableTarget, BadTargetsLeaveNothingWritten) {
  // A mesh with a vertex more (another topology), a NaN coordinate, times not increasing.
  const std::string good = read(dir_ / "shape_1.obj");
  std::string more = good;
  more.insert(more.find("\nv ") + 1, "v 0 0 0.006\n");  // a vertex added (before the others)
  write(dir_ / "more.obj", more);
  std::string nan = good;
  const auto at = nan.find("\nv ", nan.find("\nv ") + 1) + 3;
  nan.replace(at, nan.find(' ', at) - at, "nan");
  write(dir_ / "nan.obj", nan);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"time,mesh\n0.03,more.obj\n", "more.obj: v: 274 vertices, the surface has 273"},
      {"time,mesh\n0.03,nan.obj\n", "nan.obj: line 3: vertex 2 x: not a finite number: 'nan'"},
      {"time,mesh\n0.03,shape_1.obj\n0.02,shape_2.obj\n",
       "bad.csv: line 3: time 0.02 does not come after the previous target's 0.03 (line 2)"}};
  for (const auto& [manifest, message] : cases) {
    write(dir_ / "bad.csv", manifest);
    auto o = options("bad_fit");
    o.targets_path = (dir_ / "bad.csv").string();
    try {
      run_fit(o);
      ADD_FAILURE() << "no error for " << manifest;
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir_ / "bad_fit"));
    for (const auto& entry : fs::directory_iterator(dir_))
      EXPECT_EQ(entry.path().filename().string().rfind("bad_fit.tmp", 0), std::string::npos);
  }
}

}  // namespace
}  // namespace sinew::fit
