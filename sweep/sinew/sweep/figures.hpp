#pragma once
// The figures a sweep collects from each finished run's folder (docs/sweep-format.md, figures):
// read back from the files the runner wrote (run_summary.json, probe_<name>.csv), so a run done
// by an earlier invocation, another thread or another MPI rank gives the same numbers, bit for
// bit (the runner prints 17 significant digits).
//
//   probe: a probe's column ("ux", "fz", ...) at a scene time t (linear interpolation between the
//          two rows around t; none past the last row), at the end (the last row), or a statistic
//          over all rows (max, min, max_abs);
//   energy: kinetic, strain, hourglass or external_work (J) at t (the first frame at or after t:
//          frames are sparse, so no interpolation), at the end, or a statistic over the frames;
//   summary: a number of run_summary.json (steps_done, dt_s, wall_time_s, ...).
// A figure that does not exist for a run (a run that stopped early, a failed run) is empty.
#include <optional>
#include <string>
#include <vector>

#include "sinew/common/yaml_reader.hpp"

namespace sinew::sweep {

struct Figure {
  enum class Source { probe, energy, summary } source = Source::probe;
  enum class Reduce { at_time, end, max, min, max_abs } reduce = Reduce::end;
  std::string name;    // the table column
  std::string what;    // probe name, energy name or summary key
  std::string column;  // probe: ux, uy, uz, fx, fy, fz
  double time = 0;     // s of scene time (Reduce::at_time)
};

// Parses one entry of the sweep file's `figures` list. Throws ConfigError at the entry's key.
Figure parse_figure(const YamlNode& node);

// The figure's value for the run whose outputs are in `run_dir`; none when it has none.
// Throws FormatError for a probe CSV or summary that is not what the runner writes.
std::optional<double> collect_figure(const Figure& figure, const std::string& run_dir);

// The summary keys a `summary:` figure may name (numbers of run_summary.json).
const std::vector<std::string>& summary_figure_keys();

}  // namespace sinew::sweep
