// sinew-sweep: runs every run of a sweep file (docs/sweep-format.md) and writes one results
// folder per run and one table (CSV and JSON) of the runs' values and figures.
//
//   sinew-sweep SWEEP [-o RESULTS] [--device cpu|cuda|auto] [--precision float|double]
//               [--threads N] [--concurrent K] [--yes] [--force] [--plan] [--quiet]
//   mpirun -n R sinew-sweep SWEEP ...     (built with MPI: rank 0 hands out, R − 1 ranks run)
//
// Exit status: 0 every run completed, 1 bad input or I/O error (before any run), 2 bad command
// line, 3 some runs failed or became unstable (each recorded in the table with its message),
// 130 interrupted (rerun the same command to go on).
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/threads.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/simulator/run/runner.hpp"
#include "sinew/sweep/run_sweep.hpp"
#include "sinew/sweep/sweep_file.hpp"
#if defined(SINEW_WITH_MPI)
#include "sinew/sweep/sweep_mpi.hpp"
#endif

namespace {

int exit_status(const sinew::sweep::SweepReport& report, const std::string& output) {
  using namespace sinew;
  if (report.interrupted) {
    tool::report_error("sinew-sweep", fmt::format("interrupted; the same command goes on "
                                                  "(finished runs in {} are kept)",
                                                  output));
    return tool::kExitInterrupted;
  }
  log::info("sweep done: {} runs ({} ran now, {} finished before), {} failed -> {}/sweep_table.csv",
            report.rows.size(), report.ran, report.skipped, report.failed, output);
  std::int64_t not_completed = 0;
  for (const auto& r : report.rows) not_completed += r.status != "completed";
  return not_completed > 0 ? tool::kExitUnstable : tool::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace sinew;
  threads::prefer_passive_wait(argv);
  CLI::App app{
      "sinew-sweep: runs a sweep file (docs/sweep-format.md): a base scene with values varied "
      "over a grid or a list; one results folder per run and one table of values and figures"};
  std::string sweep_path, output, device, precision;
  int threads = -1, concurrent = 0;
  bool yes = false, force = false, plan_only = false, quiet = false;
  app.add_option("sweep", sweep_path, "Sweep file (YAML)")->required()->check(CLI::ExistingFile);
  app.add_option("-o,--output", output,
                 "Results folder (default: <sweep name>_results in the current directory)");
  app.add_option("--device", device,
                 "Backend of every run: cpu, cuda or auto (default: the "
                 "sweep file's run.device, else auto)")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  app.add_option("--precision", precision, "Override the scenes' precision: float or double")
      ->check(CLI::IsMember({"float", "double"}));
  app.add_option("--threads", threads,
                 "OpenMP threads per run (default: the cores shared among the runs at once)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--concurrent", concurrent,
                 "Runs at once in this process (per MPI rank); on one GPU each has its own "
                 "streams (default: the sweep file's run.concurrent, else 1)")
      ->check(CLI::Range(1, 1024));
  app.add_flag("--yes", yes, "Allow sweeps of more than 1000 runs");
  app.add_flag("--force", force, "Let runs go past the step, frame and probe-row limits");
  app.add_flag("--plan", plan_only, "Check the sweep file, list the runs and exit");
  app.add_flag("-q,--quiet", quiet, "Warnings and errors only (no progress lines)");
  app.set_version_flag("--version", std::string(sinew::kVersion));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  log::set_level(quiet ? log::Level::warn : log::Level::info);

#if defined(SINEW_WITH_MPI)
  std::unique_ptr<sweep::MpiSession> mpi;
  if (sweep::launched_by_mpi() && !plan_only)
    mpi = std::make_unique<sweep::MpiSession>(&argc, &argv);
  // Only rank 0 speaks, except for errors.
  if (mpi && mpi->rank() != 0 && !quiet) log::set_level(log::Level::warn);
#endif
  simulator::install_interrupt_handlers();
  return tool::run("sinew-sweep", [&] {
    sweep::ParseOptions po;
    po.yes = yes;
#if defined(SINEW_WITH_MPI)
    // Every rank reads the sweep file; a bad one is reported once, by rank 0.
    const auto level = log::level();
    if (mpi && mpi->rank() != 0) log::set_level(log::Level::off);
#endif
    const auto sw = sweep::parse_sweep(sweep_path, po);
#if defined(SINEW_WITH_MPI)
    log::set_level(level);
#endif
    sweep::SweepOptions so;
    so.settings = sw.settings;
    if (!device.empty()) so.settings.device = device;
    if (!precision.empty()) so.settings.precision = precision;
    if (threads >= 0) so.settings.threads = threads;
    if (concurrent > 0) so.settings.concurrent = concurrent;
    so.settings.force = so.settings.force || force;
    so.quiet = quiet;
    so.output_dir =
        !output.empty() ? output : std::filesystem::path(sweep_path).stem().string() + "_results";
    if (plan_only) {
      std::string text = fmt::format("{}: {} runs of {}{}\n", sweep_path, sw.runs.size(),
                                     sw.scene_path, sw.title.empty() ? "" : " (" + sw.title + ")");
      for (const auto& r : sw.runs)
        text += fmt::format("  {}  {}{}\n", r.name, r.values_text(),
                            sweep::run_is_finished(so, r) ? " [finished]" : "");
      std::fputs(text.c_str(), stdout);
      return tool::kExitOk;
    }
#if defined(SINEW_WITH_MPI)
    if (mpi && mpi->size() > 1) {
      sweep::SweepReport report;
      try {
        report = sweep::run_sweep_mpi(sw, so, *mpi);
      } catch (const std::exception& e) {
        // A rank that stops alone would leave the others waiting for it.
        tool::report_error("sinew-sweep", fmt::format("rank {}: {}", mpi->rank(), e.what()));
        mpi->abort(tool::kExitError);
      }
      if (mpi->rank() != 0) return report.interrupted ? tool::kExitInterrupted : tool::kExitOk;
      return exit_status(report, so.output_dir);
    }
#endif
    return exit_status(sweep::run_sweep(sw, so), so.output_dir);
  });
}
