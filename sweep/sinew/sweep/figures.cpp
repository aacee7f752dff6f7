#include "sinew/sweep/figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/common/error.hpp"
#include "sinew/common/names.hpp"

namespace sinew::sweep {

namespace fs = std::filesystem;

namespace {

constexpr NameTable<Figure::Reduce, 3> kStatistics{{{"max", Figure::Reduce::max},
                                                    {"min", Figure::Reduce::min},
                                                    {"max_abs", Figure::Reduce::max_abs}}};
const std::vector<std::string> kEnergies{"kinetic", "strain", "elastic", "hourglass",
                                         "external_work"};
const std::vector<std::string> kProbeColumns{"ux", "uy", "uz", "fx", "fy", "fz"};

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

// A series of (time, value) pairs reduced as the figure asks. `interpolate`: linear between the
// two samples around the time (probe rows, dense); otherwise the first sample at or after it.
std::optional<double> reduce(const Figure& f, const std::vector<std::pair<double, double>>& s,
                             bool interpolate) {
  if (s.empty()) return std::nullopt;
  switch (f.reduce) {
    case Figure::Reduce::end:
      return s.back().second;
    case Figure::Reduce::max:
    case Figure::Reduce::min:
    case Figure::Reduce::max_abs: {
      double best = f.reduce == Figure::Reduce::max_abs ? std::abs(s[0].second) : s[0].second;
      for (const auto& [t, v] : s) {
        if (f.reduce == Figure::Reduce::max) best = std::max(best, v);
        if (f.reduce == Figure::Reduce::min) best = std::min(best, v);
        if (f.reduce == Figure::Reduce::max_abs) best = std::max(best, std::abs(v));
      }
      return best;
    }
    case Figure::Reduce::at_time: {
      // Times are printed with 17 digits and reach the asked time up to rounding.
      const double tol = 1e-12 * std::max(1.0, std::abs(f.time));
      const auto it = std::lower_bound(s.begin(), s.end(), f.time - tol,
                                       [](const auto& a, double t) { return a.first < t; });
      if (it == s.end()) return std::nullopt;  // past the last sample: the run stopped early
      if (it->first <= f.time + tol || !interpolate) return it->second;
      if (it == s.begin()) return std::nullopt;  // before the first sample
      const auto& [t0, v0] = *(it - 1);
      const auto& [t1, v1] = *it;
      return v0 + (v1 - v0) * (f.time - t0) / (t1 - t0);
    }
  }
  return std::nullopt;
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

std::optional<double> probe_figure(const Figure& f, const std::string& run_dir) {
  const auto path = (fs::path(run_dir) / ("probe_" + f.what + ".csv")).string();
  std::ifstream in(path);
  if (!in) return std::nullopt;  // a run that failed before writing its probes
  std::string line;
  if (!std::getline(in, line)) return std::nullopt;
  const auto header = split_csv_line(line);
  const auto col = std::find(header.begin(), header.end(), f.column);
  if (header.empty() || header[0] != "time" || col == header.end()) {
    throw FormatError(
        path, f.column,
        fmt::format("the probe file has no column '{}' (header: {})", f.column, line));
  }
  const auto c = std::size_t(col - header.begin());
  std::vector<std::pair<double, double>> series;
  for (std::int64_t row = 1; std::getline(in, line); ++row) {
    if (line.empty()) continue;
    const auto cells = split_csv_line(line);
    if (cells.size() != header.size()) {
      throw FormatError(
          path, "",
          fmt::format("row {} has {} cells, the header {}", row, cells.size(), header.size()));
    }
    series.emplace_back(std::strtod(cells[0].c_str(), nullptr),
                        std::strtod(cells[c].c_str(), nullptr));
  }
  return reduce(f, series, true);
}

nlohmann::json read_summary(const std::string& run_dir) {
  const auto path = (fs::path(run_dir) / "run_summary.json").string();
  std::ifstream in(path);
  if (!in) return nullptr;
  auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw FormatError(path, "", "not a run summary (not a JSON object)");
  return j;
}

}  // namespace

const std::vector<std::string>& summary_figure_keys() {
  static const std::vector<std::string> keys{"steps_done",    "steps_planned",    "dt_s",
                                             "dt_critical_s", "simulated_time_s", "wall_time_s",
                                             "setup_s",       "frames",           "time_per_step_s",
                                             "duration_s",    "mass_scaling",     "time_scaling"};
  return keys;
}

Figure parse_figure(const YamlNode& node) {
  node.expect_map();
  node.allow_keys({"name", "probe", "value", "energy", "summary", "at", "stat"});
  Figure f;
  f.name = node.require("name").text();
  const int sources = int(node.has("probe")) + int(node.has("energy")) + int(node.has("summary"));
  if (sources != 1) throw node.error("give exactly one of probe, energy or summary");
  if (node.has("at") && node.has("stat")) throw node.error("give at or stat, not both");
  if (node.has("summary")) {
    f.source = Figure::Source::summary;
    f.what = node.child("summary").text();
    const auto& keys = summary_figure_keys();
    if (std::find(keys.begin(), keys.end(), f.what) == keys.end()) {
      throw node.child("summary").error(
          fmt::format("unknown summary number '{}' (expected one of: {})", f.what, join(keys)));
    }
    if (node.has("at") || node.has("stat") || node.has("value"))
      throw node.error("a summary figure takes no at, stat or value");
    return f;
  }
  if (node.has("probe")) {
    f.source = Figure::Source::probe;
    f.what = node.child("probe").text();
    f.column = node.require("value").text();
    if (std::find(kProbeColumns.begin(), kProbeColumns.end(), f.column) == kProbeColumns.end()) {
      throw node.child("value").error(fmt::format("unknown probe value '{}' (expected one of: {})",
                                                  f.column, join(kProbeColumns)));
    }
  } else {
    f.source = Figure::Source::energy;
    f.what = node.child("energy").text();
    if (std::find(kEnergies.begin(), kEnergies.end(), f.what) == kEnergies.end()) {
      throw node.child("energy").error(
          fmt::format("unknown energy '{}' (expected one of: {})", f.what, join(kEnergies)));
    }
    if (node.has("value")) throw node.child("value").error("an energy figure takes no value");
  }
  if (node.has("stat")) {
    f.reduce = node.child("stat").choose(kStatistics, "statistic");
  } else if (node.has("at")) {
    const auto at = node.child("at");
    if (at.is_scalar() && at.text() == "end") {
      f.reduce = Figure::Reduce::end;
    } else {
      f.reduce = Figure::Reduce::at_time;
      f.time = at.non_negative();
    }
  }
  return f;
}

std::optional<double> collect_figure(const Figure& f, const std::string& run_dir) {
  if (f.source == Figure::Source::probe) return probe_figure(f, run_dir);
  const auto j = read_summary(run_dir);
  if (j.is_null()) return std::nullopt;
  if (f.source == Figure::Source::summary) {
    const auto it = j.find(f.what);
    if (it == j.end() || !it->is_number()) return std::nullopt;
    return it->get<double>();
  }
  std::vector<std::pair<double, double>> series;
  const auto energies = j.find("energies");
  if (energies != j.end() && energies->is_array()) {
    for (const auto& row : *energies) {
      const auto t = row.find("time_s");
      const auto v = row.find(f.what + "_J");
      if (t == row.end() || v == row.end() || !t->is_number() || !v->is_number()) continue;
      series.emplace_back(t->get<double>(), v->get<double>());
    }
  }
  return reduce(f, series, false);
}

}  // namespace sinew::sweep
