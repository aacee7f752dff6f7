// sinew-simulate: runs a scene file (docs/scene-format.md) and writes results
// (docs/results-format.md).
//
//   sinew-simulate SCENE [-o OUTDIR] [--explain [--run]] [--device cpu|cuda|auto]
//                  [--precision float|double] [--threads N] [--quiet] [--restart CKPT]
//                  [--checkpoint-every N] [--force] [--parts P (with --explain)]
//
// Exit status: 0 done (or plan printed), 1 bad input or I/O error, 2 bad command line,
// 3 the simulation became unstable (frames written so far stay valid), 130 interrupted (a
// checkpoint was written; resume with --restart).
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <filesystem>
#include <optional>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/threads.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/partition/partition.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace {

// Runs the scene and returns the exit status; errors other than instability escape to tool::run.
int simulate(const sinew::simulator::RunOptions& opt) {
  using namespace sinew;
  try {
    const auto result = simulator::run_scene(opt);
    if (!result.ran) return tool::kExitOk;
    const auto& s = result.summary;
    if (s.status == "interrupted") {
      tool::report_error("sinew-simulate", s.message);
      return tool::kExitInterrupted;
    }
    log::info("done: {} steps of {:.6g} s, {} frames, {:.3g} s wall ({:.3g} ms/step) -> {}",
              s.steps_done, s.dt, s.frames, s.wall_time_s, 1e3 * s.time_per_step_s,
              result.output_dir);
    return tool::kExitOk;
  } catch (const InstabilityError& e) {
    // The one error with its own status and a hint: the frames written so far are usable.
    tool::report_error("sinew-simulate",
                       fmt::format("unstable: {}\n(the frames written so far in {} are valid)",
                                   e.what(), opt.output_dir));
    return tool::kExitUnstable;
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace sinew;
  threads::prefer_passive_wait(argv);
  CLI::App app{"sinew-simulate: TLED simulation of a sinew model as a scene file describes it"};
  simulator::RunOptions opt;
  std::string precision, output;
  bool run_too = false, verbose = false;
  app.add_option("scene", opt.scene_path, "Scene file (YAML, docs/scene-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("-o,--output", output,
                 "Output directory (default: <scene name>_results in the current directory)");
  app.add_flag("--explain", opt.explain,
               "Print the plan (stages, element collections, memory, time step) and exit");
  app.add_flag("--run", run_too, "With --explain: run after printing the plan");
  int parts = 0;
  app.add_option("--parts", parts,
                 "With --explain: also print the partition into P slabs for P ranks or GPUs "
                 "(docs/multi-gpu.md)")
      ->check(CLI::PositiveNumber);
  app.add_option("--device", opt.device,
                 "Backend: cpu, cuda or auto (cuda when a CUDA device is available, else cpu)")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  app.add_option("--precision", precision, "Override the scene's precision: float or double")
      ->check(CLI::IsMember({"float", "double"}));
  app.add_option(
         "--threads", opt.threads,
         "OpenMP threads (default: every core, waiting passively; results do not depend on it)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("-q,--quiet", opt.quiet, "No progress bar, warnings and errors only");
  app.add_flag("-v,--verbose", verbose, "Debug messages");
  app.add_option("--restart", opt.restart,
                 "Resume from a checkpoint (written by --checkpoint-every or an interruption)")
      ->check(CLI::ExistingFile);
  app.add_option("--checkpoint-every", opt.checkpoint_every,
                 "Write <OUTDIR>/checkpoint.h5 every N steps")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--force", opt.force,
               "Run even past the sane limits on steps (1e9), frames (1e5) and probe rows per "
               "probe (1e8) that catch a duration or interval in the wrong unit");
  app.set_version_flag("--version", std::string(sinew::kVersion));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every command-line mistake exits 2.
    return app.exit(e) == 0 ? 0 : 2;
  }

  log::set_level(verbose ? log::Level::debug : opt.quiet ? log::Level::warn : log::Level::info);
  if (!precision.empty()) {
    opt.precision =
        precision == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
  }
  opt.run = !opt.explain || run_too;
  if (parts > 0) {
    if (!opt.explain) {
      tool::report_error("sinew-simulate",
                         "--parts needs --explain (runs on several parts use "
                         "sinew-simulate-parts under mpirun)");
      return 2;
    }
    opt.explain_more = [parts](const formats::Model& model, const simulator::Plan& plan) {
      const auto p = partition::make_partition(model, partition::work_of(model, plan), parts);
      return p.explain(plan.precision == simulator::Precision::float32 ? 4 : 8);
    };
  }
  opt.output_dir =
      !output.empty() ? output : std::filesystem::path(opt.scene_path).stem().string() + "_results";
  simulator::install_interrupt_handlers();
  return tool::run("sinew-simulate", [&] { return simulate(opt); });
}
