#pragma once
// The sweep file (YAML, docs/sweep-format.md): a base scene, the values to vary (a grid, a list,
// or a list of grids), the figures to collect per run, and how to run them. parse_sweep reads it
// and plans every run before anything runs: each run's scene is the base scene with the run's
// values substituted at their key paths (YamlNode::replaced) and is parsed as a scene, so an
// unknown path, a value of the wrong type or out of range, or a missing model fails here with a
// ConfigError naming the sweep file and the key, e.g.
//   "study.yaml: grid.dampin: run 0 (dampin = 10): unknown key 'dampin' in the scene (...)".
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/common/yaml_reader.hpp"
#include "sinew/sweep/figures.hpp"

namespace sinew::sweep {

// The largest sweep planned without `yes` (sinew-sweep --yes): a typo in a grid (a list of 1000
// values where 10 were meant) should not start a week of runs.
inline constexpr std::int64_t kMaxRunsWithoutYes = 1000;

// One value of one run: the scene key path and the value as the sweep file gives it.
struct RunValue {
  std::string path;  // scene key path, e.g. "muscles.frontalis_l.peak"
  YamlNode value;    // in the sweep file (its key names it in messages)
  std::string text;  // the value as one line of YAML ("50", "[0, 0, -9.81]")
};

struct PlannedRun {
  std::int64_t index = 0;
  std::string name;  // "run_0007": its folder under the results folder
  std::vector<RunValue> values;
  std::string scene_text;           // the run's scene (model path absolute)
  std::string model_path;           // resolved
  std::string values_text() const;  // "damping = 50, mass_scaling = 4"
  std::string describe() const;     // "run 7 (damping = 50, mass_scaling = 4)"
};

// How to run: the sweep file's `run:` section, overridden by the command line.
struct RunSettings {
  std::string device = "auto";           // cpu | cuda | auto
  std::optional<std::string> precision;  // float | double (default: the scene's)
  int threads = 0;                       // OpenMP threads per run (0: the cores / concurrent)
  int concurrent = 1;                    // runs at once in this process (one GPU: its streams)
  bool force = false;                    // runs past the step/frame/row limits
};

struct Sweep {
  std::string file;  // the sweep file as given
  std::string title;
  std::string scene_path;               // the base scene, resolved against the sweep file's folder
  std::vector<std::string> parameters;  // the varied key paths, in column order
  std::vector<Figure> figures;
  RunSettings settings;
  std::vector<PlannedRun> runs;
};

struct ParseOptions {
  bool yes = false;  // allow more than kMaxRunsWithoutYes runs
};

// Reads, checks and plans a sweep file. Throws ConfigError (file, key, problem) or IoError.
Sweep parse_sweep(const std::string& path, const ParseOptions& options = {});
// The same from text; `directory` resolves the base scene's path.
Sweep parse_sweep_text(const std::string& text, const std::string& file,
                       const std::string& directory, const ParseOptions& options = {});

}  // namespace sinew::sweep
