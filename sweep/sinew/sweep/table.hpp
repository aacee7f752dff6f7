#pragma once
// The sweep's table: one row per run with its status, its values and its figures, written as
// <results>/sweep_table.csv and <results>/sweep_table.json (atomically: a reader never sees half a
// table; docs/sweep-format.md, Results). Numbers are printed with 17 significant digits, so a
// table read back gives the runs' figures bit for bit.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/sweep/sweep_file.hpp"

namespace sinew::sweep {

struct Row {
  std::int64_t index = 0;
  std::string name;  // run_0007
  std::string status =
      "pending";        // pending | completed | unstable | failed | interrupted | running
  std::string message;  // why it stopped, when not completed
  std::vector<std::string> values;  // per Sweep::parameters: YAML text, "" when the run has none
  std::vector<std::optional<double>> figures;  // per table_figures()
};

// The figures of the table: the sweep's own, then steps_done and wall_time_s of every run.
std::vector<Figure> table_figures(const Sweep& sweep);

// The row of a planned run as it stands in `run_dir` (pending when there is no summary or
// run_dir is "").
Row collect_row(const Sweep& sweep, const PlannedRun& run, const std::string& run_dir);

// A row as JSON text and back (MPI ranks send rows to rank 0). Throws FormatError on bad text.
std::string row_to_json(const Row& row);
Row row_from_json(const std::string& text);

// Writes sweep_table.csv and sweep_table.json into `dir`. Throws IoError.
void write_table(const Sweep& sweep, const std::vector<Row>& rows, const std::string& dir);

}  // namespace sinew::sweep
