#include "sinew/sweep/sweep_file.hpp"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::sweep {

namespace fs = std::filesystem;

namespace {

constexpr int kFormatVersion = 1;

// The values of one run before the scene is made: (path, value) in the order of the columns.
using Values = std::vector<RunValue>;

// An empty value (~) removes the key from the run's scene: its default applies.
RunValue run_value(const std::string& path, const YamlNode& value) {
  return {path, value, value.defined() ? value.emit() : "~"};
}

// Which parameter an error of a run's scene is about: the varied path that is the scene key or
// one of its parents ("muscles.a.peak" for "muscles.a.peak" or "muscles.a"'s children), else the
// varied path under the key (a whole section replaced), else none.
const RunValue* value_of_key(const Values& values, const std::string& key) {
  const auto under = [](const std::string& path, const std::string& parent) {
    return path == parent ||
           (path.size() > parent.size() && path.compare(0, parent.size(), parent) == 0 &&
            (path[parent.size()] == '.' || path[parent.size()] == '['));
  };
  for (const auto& v : values)
    if (under(key, v.path)) return &v;
  for (const auto& v : values)
    if (!key.empty() && under(v.path, key)) return &v;
  return nullptr;
}

PlannedRun plan_run(const YamlNode& scene_doc, const std::string& scene_path,
                    const std::string& sweep_file, std::int64_t index, int width, Values values) {
  PlannedRun run;
  run.index = index;
  run.name = fmt::format("run_{:0{}}", index, width);
  run.values = std::move(values);
  std::vector<YamlReplacement> replacements;
  for (const auto& v : run.values) replacements.push_back({v.path, v.value});
  const auto text = scene_doc.replaced(replacements);
  const auto directory = fs::path(scene_path).parent_path().string();
  simulator::Scene scene;
  try {
    scene = simulator::parse_scene_text(text, scene_path, directory);
  } catch (const ConfigError& e) {
    // The base scene reads on its own (checked first), so the run's values are the cause: the
    // one at the key, else the run's first.
    const RunValue* v = value_of_key(run.values, e.field());
    if (!v && run.values.empty()) throw;
    if (!v) v = &run.values.front();
    // The problem without its line in the generated scene: the sweep file's line is the one to see.
    std::string problem = e.problem();
    if (const auto at = problem.rfind(" (line "); at != std::string::npos && problem.back() == ')')
      problem.erase(at);
    throw v->value.error(fmt::format("{}: the scene's {}: {}", run.describe(),
                                     e.field().empty() ? "text" : e.field(), problem));
  }
  if (!fs::exists(scene.model_path)) {
    const RunValue* v = value_of_key(run.values, "model");
    const auto problem = fmt::format("the model file '{}' does not exist", scene.model_path);
    if (v) throw v->value.error(fmt::format("{}: {}", run.describe(), problem));
    throw ConfigError(scene_path, "model", problem);
  }
  // The run's scene lives in its own folder: its model path becomes absolute.
  run.model_path = fs::absolute(scene.model_path).lexically_normal().string();
  const auto with_model = parse_yaml(text, sweep_file + ": " + run.name);
  const auto model_node = parse_yaml(fmt::format("'{}'", run.model_path), sweep_file);
  run.scene_text = with_model.replaced({{"model", model_node}});
  return run;
}

}  // namespace

std::string PlannedRun::values_text() const {
  std::string v;
  for (const auto& x : values) v += (v.empty() ? "" : ", ") + x.path + " = " + x.text;
  return v;
}

std::string PlannedRun::describe() const {
  const auto v = values_text();
  return v.empty() ? fmt::format("run {}", index) : fmt::format("run {} ({})", index, v);
}

Sweep parse_sweep(const std::string& path, const ParseOptions& options) {
  return parse_sweep_text(read_text_file(path, "sweep file"), path,
                          fs::path(path).parent_path().string(), options);
}

Sweep parse_sweep_text(const std::string& text, const std::string& file,
                       const std::string& directory, const ParseOptions& options) {
  const YamlNode root = parse_yaml(text, file);
  root.expect_map();
  root.allow_keys({"version", "title", "scene", "grid", "list", "figures", "run"});
  Sweep sweep;
  sweep.file = file;
  const auto version = root.require("version");
  if (version.integer() != kFormatVersion) {
    throw version.error(fmt::format("unsupported sweep file version {} (this sinew reads {})",
                                    version.integer(), kFormatVersion));
  }
  if (root.has("title")) sweep.title = root.child("title").text();
  const auto scene_key = root.require("scene");
  sweep.scene_path = (fs::path(directory) / scene_key.text()).lexically_normal().string();
  if (!fs::exists(sweep.scene_path)) {
    throw scene_key.error(
        fmt::format("the base scene '{}' does not exist (relative to the sweep "
                    "file's folder)",
                    sweep.scene_path));
  }

  // The runs: each list item (or one empty item without a list) with each grid point.
  std::vector<Values> items;
  if (root.has("list")) {
    const auto list = root.child("list");
    list.expect_sequence();
    if (list.size() == 0) throw list.error("empty list: give at least one run");
    for (const auto& item : list.items()) {
      item.expect_map();
      Values values;
      for (const auto& key : item.keys()) values.push_back(run_value(key, item.child(key)));
      if (values.empty()) throw item.error("empty run: give at least one key path and value");
      items.push_back(std::move(values));
    }
  } else {
    items.emplace_back();
  }
  std::vector<std::pair<std::string, std::vector<YamlNode>>> grid;
  if (root.has("grid")) {
    const auto g = root.child("grid");
    g.expect_map();
    if (g.size() == 0) throw g.error("empty grid: give at least one key path with its values");
    for (const auto& key : g.keys()) {
      const auto values = g.child(key);
      if (!values.is_sequence())
        throw values.error("expected a list of values (a single value: [value])");
      if (values.size() == 0) throw values.error("empty list of values: give at least one value");
      for (const auto& [other, unused] : grid)
        if (other == key) throw values.error("given twice");
      grid.emplace_back(key, values.items());
    }
  }
  if (!root.has("list") && !root.has("grid"))
    throw root.error("nothing to sweep: give a grid, a list, or both (docs/sweep-format.md)");

  // Count first (without building anything), so a huge grid is refused at once.
  std::int64_t count = std::int64_t(items.size());
  const std::int64_t cap = std::int64_t(1) << 40;
  for (const auto& [key, values] : grid) count = std::min(cap, count * std::int64_t(values.size()));
  if (count > kMaxRunsWithoutYes && !options.yes) {
    throw ConfigError(file, root.has("grid") ? "grid" : "list",
                      fmt::format("{}{} runs: more than {} runs need --yes (check the grid for a "
                                  "list longer than meant)",
                                  count >= cap ? "over " : "", count, kMaxRunsWithoutYes));
  }

  // Columns: list keys in order of first appearance, then the grid's keys.
  for (const auto& values : items)
    for (const auto& v : values)
      if (std::find(sweep.parameters.begin(), sweep.parameters.end(), v.path) ==
          sweep.parameters.end())
        sweep.parameters.push_back(v.path);
  for (const auto& [key, values] : grid) {
    if (std::find(sweep.parameters.begin(), sweep.parameters.end(), key) != sweep.parameters.end())
      throw root.child("grid").child(key).error("this key path is also in the list");
    sweep.parameters.push_back(key);
  }

  if (root.has("figures")) {
    const auto figs = root.child("figures");
    figs.expect_sequence();
    for (const auto& f : figs.items()) {
      sweep.figures.push_back(parse_figure(f));
      const auto& name = sweep.figures.back().name;
      const bool clash = std::count_if(sweep.figures.begin(), sweep.figures.end(),
                                       [&](const Figure& g) { return g.name == name; }) > 1 ||
                         std::find(sweep.parameters.begin(), sweep.parameters.end(), name) !=
                             sweep.parameters.end() ||
                         name == "run" || name == "status" || name == "message";
      if (clash) throw f.child("name").error(fmt::format("column name '{}' is taken", name));
    }
  }

  if (root.has("run")) {
    const auto r = root.child("run");
    r.expect_map();
    r.allow_keys({"device", "precision", "threads", "concurrent", "force"});
    if (r.has("device")) {
      sweep.settings.device = r.child("device").text();
      if (sweep.settings.device != "cpu" && sweep.settings.device != "cuda" &&
          sweep.settings.device != "auto")
        throw r.child("device").error("expected cpu, cuda or auto");
    }
    if (r.has("precision")) {
      sweep.settings.precision = r.child("precision").text();
      if (*sweep.settings.precision != "float" && *sweep.settings.precision != "double")
        throw r.child("precision").error("expected float or double");
    }
    if (r.has("threads")) {
      const auto t = r.child("threads").integer();
      if (t < 0 || t > 4096) throw r.child("threads").error("must be in [0, 4096]");
      sweep.settings.threads = int(t);
    }
    if (r.has("concurrent")) {
      const auto c = r.child("concurrent").integer();
      if (c < 1 || c > 1024) throw r.child("concurrent").error("must be in [1, 1024]");
      sweep.settings.concurrent = int(c);
    }
    if (r.has("force")) sweep.settings.force = r.child("force").boolean();
  }

  // Plan every run: substitute, parse as a scene, check the model exists. The base scene first,
  // so that its own problems are named as its own.
  const auto scene_text = read_text_file(sweep.scene_path, "base scene");
  simulator::parse_scene_text(scene_text, sweep.scene_path,
                              fs::path(sweep.scene_path).parent_path().string());
  const YamlNode scene_doc = parse_yaml(scene_text, sweep.scene_path);
  const int width =
      std::max<int>(4, int(std::to_string(std::max<std::int64_t>(count - 1, 0)).size()));
  std::vector<std::size_t> at(grid.size(), 0);
  std::int64_t index = 0;
  for (const auto& item : items) {
    std::fill(at.begin(), at.end(), 0);
    while (true) {
      Values values = item;
      for (std::size_t k = 0; k < grid.size(); ++k)
        values.push_back(run_value(grid[k].first, grid[k].second[at[k]]));
      sweep.runs.push_back(
          plan_run(scene_doc, sweep.scene_path, file, index++, width, std::move(values)));
      // Next grid point, the last key fastest.
      std::size_t k = grid.size();
      while (k > 0 && ++at[k - 1] == grid[k - 1].second.size()) at[--k] = 0;
      if (k == 0) break;
    }
  }
  return sweep;
}

}  // namespace sinew::sweep
