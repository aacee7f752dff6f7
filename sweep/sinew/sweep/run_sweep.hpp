#pragma once
// Running a planned sweep (docs/sweep-format.md): each run in its own folder
// <results>/<run name>/ (its scene as scene.yaml, then what sinew-simulate writes), one table of
// all runs (table.hpp), a progress line per finished run (done, failed, ETA).
//
// Resuming: a run whose folder holds its scene.yaml unchanged and a run_summary.json with a
// terminal status (completed, unstable, failed) is finished and skipped; any other run (never
// started, cut off by a dead process, or whose values changed) is redone from the start; an
// interrupted run (SIGINT/SIGTERM, or mpirun ending the job when another rank died) goes on from
// its checkpoint. A run that fails (instability, a setting its model rejects, any error) is recorded with
// its message and the sweep goes on.
//
// Concurrency: `concurrent` runs at once in threads of this process, each with its own engine
// (on one GPU, each CUDA engine has its own streams, so small models share the GPU). The runner's
// libraries are safe for this: the logger is spdlog's thread-safe one; every HDF5 call goes
// through formats' one lock (hdf5_file.hpp), so any HDF5 build works, thread-safe or not, and the
// runs' HDF5 I/O does not overlap; the interrupt flag is atomic. Each model file is read once per
// process and shared by the runs that use it (simulator::ModelCache): the runs' set-ups do not
// queue behind one another's model reads.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sinew/simulator/engine/model_cache.hpp"
#include "sinew/sweep/sweep_file.hpp"
#include "sinew/sweep/table.hpp"

namespace sinew::sweep {

struct SweepOptions {
  std::string output_dir;  // the results folder (created when missing)
  RunSettings settings;    // the sweep file's, with the command line's overrides
  int cuda_device = 0;     // the GPU of this process (MPI: one per rank)
  bool quiet = false;      // no progress lines
  // Share of the machine's cores for this process's runs (MPI: several ranks on one machine);
  // threads per run default to cores / (ranks_on_machine × concurrent), at least 1.
  int ranks_on_machine = 1;
  // How the runs' threads wait for the GPU (simulator::set_cuda_blocking_wait): "auto" asleep when
  // more runs are at once than this process has cores (spinning waits would starve the threads
  // that launch), spinning otherwise; "block", "spin" (sweep_bench compares them).
  std::string gpu_wait = "auto";
};

// Sets how this process's threads wait for its GPU for `options` (gpu_wait): when its runs may
// use CUDA and a device is there; nothing otherwise.
void choose_gpu_wait(const SweepOptions& options);

// Terminal statuses: a run with one of these in its summary is finished.
bool is_finished_status(const std::string& status);

// The folder of a run.
std::string run_directory(const SweepOptions& options, const PlannedRun& run);
// True when the run's folder holds this run's scene and a summary with a terminal status.
bool run_is_finished(const SweepOptions& options, const PlannedRun& run);
// Runs one run (after clearing what an unfinished attempt left in its folder) and returns its
// row. Never throws for the run's own failures: they are its row's status and message. `models`,
// when given, is where the run reads its model file: once per process for all runs that share it.
Row execute_run(const Sweep& sweep, const PlannedRun& run, const SweepOptions& options,
                simulator::ModelCache* models = nullptr);

// Counts finished and failed runs and prints the progress line with the ETA.
class SweepProgress {
 public:
  SweepProgress(std::int64_t to_run, std::int64_t skipped, bool quiet);
  void finished(const Row& row);
  std::int64_t failed() const { return failed_; }

 private:
  std::int64_t to_run_, skipped_, done_ = 0, failed_ = 0;
  bool quiet_;
  double start_s_;
};

struct SweepReport {
  std::vector<Row> rows;  // one per planned run, in order
  std::int64_t ran = 0, skipped = 0, failed = 0;
  bool interrupted = false;  // SIGINT/SIGTERM stopped it; a rerun goes on
};

// The start of a sweep (here or on MPI rank 0): creates the results folder, fills report.rows with
// the finished runs' rows (counted as skipped) and pending rows for the others, writes the table,
// and returns the indices of the runs to run.
std::vector<std::size_t> start_sweep(const Sweep& sweep, const SweepOptions& options,
                                     SweepReport& report);

// Runs the sweep in this process: `concurrent` runs at once. Writes the table as runs finish
// (at most every few seconds) and at the end.
SweepReport run_sweep(const Sweep& sweep, const SweepOptions& options);

}  // namespace sinew::sweep
