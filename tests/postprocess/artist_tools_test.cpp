// sinew-export's files opened by the tools artists use: Blender 3.4 headless (blender_check.py)
// and the Khronos glTF validator (gltf_validate.mjs, npm gltf-validator). Each test skips, saying
// so, when its tool is not installed: scripts/install-deps installs both.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "export_test_support.hpp"
#include "sinew/postprocess/results_reader.hpp"

namespace {

using namespace sinew::postprocess;
using namespace sinew::postprocess::testing;

// Runs a shell command with its output into `log`; returns its exit status.
int run(const std::string& command, const fs::path& log) {
  const std::string cmd = command + " > '" + log.string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool on_path(const std::string& program) {
  return std::system(("command -v " + program + " > /dev/null 2>&1").c_str()) == 0;
}

// The vertex of a results file's surface that moves most between frames 0 and 1, and its positions
// in Blender's world coordinates: sinew's +Y up turned to Blender's +Z up, (x, y, z) → (x, −z, y),
// as both the glTF importer and the OBJ importer (forward −Z, up Y) do.
nlohmann::json blender_positions(const std::string& results) {
  const auto a = read_surface(results);
  std::size_t best = 0;
  float most = -1;
  for (std::size_t i = 0; i < a.vertex_count(); ++i) {
    const float d = std::abs(a.frames[1][3 * i + 1] - a.frames[0][3 * i + 1]);
    if (d > most) most = d, best = i;
  }
  nlohmann::json out = nlohmann::json::array();
  for (const auto& x : a.frames) out.push_back({x[3 * best], -x[3 * best + 2], x[3 * best + 1]});
  return out;
}

// Exports `results` with `options`, writes what Blender must show, runs blender_check.py.
void check_in_blender(const fs::path& dir, const std::string& results, const std::string& options,
                      const nlohmann::json& expect) {
  const auto glb = dir / "skin.glb", pc2 = dir / "skin.pc2", rest = dir / "rest.obj";
  ASSERT_EQ(run(std::string(SINEW_EXPORT_EXE) + " " + results + " " + options + " --glb " +
                    glb.string() + " --pc2 " + pc2.string() + " --rest-obj " + rest.string(),
                dir / "export.log"),
            0)
      << text_of(dir / "export.log");
  auto e = expect;
  e["positions"] = blender_positions(results);
  std::ofstream(dir / "expect.json") << e.dump();
  const int rc =
      run("blender -b --factory-startup --python-exit-code 1 -P '" + std::string(SINEW_SOURCE_DIR) +
              "/tests/postprocess/blender_check.py' -- " + glb.string() + " " + rest.string() +
              " " + pc2.string() + " " + (dir / "expect.json").string(),
          dir / "blender.log");
  EXPECT_EQ(rc, 0) << options << "\n" << text_of(dir / "blender.log");
}

TEST(ArtistTools, BlenderShowsResultsFrameKAtItsFrame) {
  if (!on_path("blender")) GTEST_SKIP() << "blender not installed (apt-get install blender)";
  const auto dir = temp_dir("blender");
  const auto results = (dir / "results.h5").string();
  // 6 frames 10 ms apart (100 Hz): the default is 24 fps, results frame k at Blender frame k.
  write_results(results, stretching_sphere(6));
  nlohmann::json one_per_frame = {{"fps", 24}, {"range", {0, 5}}};
  for (int k = 0; k < 6; ++k) {
    one_per_frame["gltf"].push_back({k, k});
    one_per_frame["pc2"].push_back({k, k});
  }
  check_in_blender(dir, results, "", one_per_frame);
  // Slow motion 10× at 30 fps: results frame k at frame 3k (held until 3k + 2); the PC2 stays one
  // sample per frame. Frame 3k − 1 must still show k − 1 and 3k already k: no key a rounding error
  // late.
  nlohmann::json slow = {{"fps", 30}, {"range", {0, 15}}, {"color", true}};
  for (int k = 0; k < 6; ++k) {
    slow["gltf"].push_back({3 * k, k});
    if (k > 0) slow["gltf"].push_back({3 * k - 1, k - 1});
    slow["pc2"].push_back({k, k});
  }
  // Frame times up to a step (here 50 µs) after their output times, as the simulator writes a frame
  // at the first step at or after it: unsnapped keys (scene time × 10) would land 0.015 frames
  // after frame 3k, past Blender's 0.01-frame tolerance, and frame 3k would show results frame
  // k − 1.
  auto late = stretching_sphere(6);
  for (std::size_t k = 1; k < late.times.size(); ++k) late.times[k] += 5e-5;
  const auto late_results = (dir / "late.h5").string();
  write_results(late_results, late);
  check_in_blender(dir, late_results, "--time-scale 10 --fps 30 --color displacement", slow);
}

// Every kind of .glb sinew-export writes, through the Khronos validator: no errors, no warnings.
TEST(ArtistTools, GltfValidatorAcceptsEveryExport) {
  const fs::path validator = fs::path(SINEW_SOURCE_DIR) / ".cache" / "gltf-validator";
  if (!on_path("node") || !fs::exists(validator / "node_modules" / "gltf-validator")) {
    GTEST_SKIP() << "node or the npm gltf-validator not installed (scripts/install-deps)";
  }
  const auto dir = temp_dir("validator");
  const auto results = (dir / "results.h5").string();
  write_results(results, stretching_sphere(5));
  const std::vector<std::string> variants = {"",
                                             "--linear",
                                             "--up z",
                                             "--color displacement",
                                             "--time-scale 10 --fps 30",
                                             "--surface volume"};
  for (std::size_t v = 0; v < variants.size(); ++v) {
    const auto glb = dir / ("variant_" + std::to_string(v) + ".glb");
    ASSERT_EQ(run(std::string(SINEW_EXPORT_EXE) + " " + results + " " + variants[v] + " --glb " +
                      glb.string(),
                  dir / "export.log"),
              0)
        << variants[v] << ": " << text_of(dir / "export.log");
    const int rc = run("node '" + std::string(SINEW_SOURCE_DIR) +
                           "/tests/postprocess/gltf_validate.mjs' " + glb.string(),
                       dir / "validator.log");
    EXPECT_EQ(rc, 0) << variants[v] << ":\n" << text_of(dir / "validator.log");
  }
}

}  // namespace
