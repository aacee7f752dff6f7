// sinew-simulate-parts: runs a scene file on P parts under MPI (docs/multi-gpu.md), with the same
// results, bit for bit, as `sinew-simulate --device cpu`.
//
//   mpirun -n P sinew-simulate-parts SCENE [-o OUTDIR] [--precision float|double] [--threads N]
//                                    [--quiet] [--restart CKPT] [--checkpoint-every N] [--force]
//
// Every rank runs the runner (run_scene) on the partitioned engine, whose calls are collective;
// rank 0 writes the outputs, the other ranks write theirs into a temporary folder removed at the
// end (with --restart, a copy of rank 0's: the ranks must share a file system). Exit status as sinew-simulate's (no interruption checkpoints: a signal stops every rank).
// Any other error on one rank aborts all of them (MPI_Abort) rather than leave the others waiting.
#include <fmt/format.h>
#include <mpi.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/partition/partitioned_engine.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace {

// A fresh folder for a rank's discarded outputs; removed when it goes out of scope.
struct ScratchFolder {
  std::filesystem::path path;
  explicit ScratchFolder(int rank) {
    std::string tmpl =
        (std::filesystem::temp_directory_path() / fmt::format("sinew-rank{}-XXXXXX", rank))
            .string();
    if (!mkdtemp(tmpl.data()))
      throw sinew::IoError(tmpl, "", "cannot create a scratch folder for this rank's outputs");
    path = tmpl;
  }
  ~ScratchFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

int simulate(const sinew::simulator::RunOptions& opt, int rank) {
  using namespace sinew;
  try {
    const auto result = simulator::run_scene(opt);
    if (!result.ran) return tool::kExitOk;
    if (result.summary.status == "interrupted") {  // as sinew-simulate: resume with --restart
      if (rank == 0) tool::report_error("sinew-simulate-parts", result.summary.message);
      return tool::kExitInterrupted;
    }
    if (rank == 0)
      log::info("done: {} steps of {:.6g} s, {} frames, {:.3g} s wall ({:.3g} ms/step) -> {}",
                result.summary.steps_done, result.summary.dt, result.summary.frames,
                result.summary.wall_time_s, 1e3 * result.summary.time_per_step_s,
                result.output_dir);
    return tool::kExitOk;
  } catch (const InstabilityError& e) {
    // Thrown on every rank at the same step (the checks are collective).
    if (rank == 0)
      tool::report_error("sinew-simulate-parts",
                         fmt::format("unstable: {}\n(the frames written so far in {} are valid)",
                                     e.what(), opt.output_dir));
    return tool::kExitUnstable;
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace sinew;
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  CLI::App app{"sinew-simulate-parts: a sinew scene on P parts under mpirun (docs/multi-gpu.md)"};
  simulator::RunOptions opt;
  std::string precision, output;
  bool verbose = false;
  app.add_option("scene", opt.scene_path, "Scene file (YAML, docs/scene-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("-o,--output", output,
                 "Output directory (default: <scene name>_results in the current directory)");
  app.add_option("--precision", precision, "Override the scene's precision: float or double")
      ->check(CLI::IsMember({"float", "double"}));
  app.add_option("--threads", opt.threads, "OpenMP threads per rank (default: all)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("-q,--quiet", opt.quiet, "No progress bar, warnings and errors only");
  app.add_flag("-v,--verbose", verbose, "Debug messages");
  app.add_option("--restart", opt.restart, "Resume from a checkpoint (of any number of parts)")
      ->check(CLI::ExistingFile);
  app.add_option("--checkpoint-every", opt.checkpoint_every,
                 "Write <OUTDIR>/checkpoint.h5 every N steps")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--force", opt.force, "Run past the sane limits on steps, frames and probe rows");
  app.set_version_flag("--version", std::string(sinew::kVersion));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e) == 0 ? 0 : 2;
    MPI_Finalize();
    return rc;
  }

  // Rank 0 speaks; the others say only their errors (warnings are the same on every rank).
  log::set_level(rank != 0   ? log::Level::error
                 : verbose   ? log::Level::debug
                 : opt.quiet ? log::Level::warn
                             : log::Level::info);
  if (rank != 0) opt.quiet = true;
  if (!precision.empty())
    opt.precision =
        precision == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
  opt.device = "cpu";
  opt.make_backend = [](const formats::Model& model, const simulator::Setup& setup) {
    return partition::make_partitioned_cpu_backend(model, setup, MPI_COMM_WORLD);
  };
  const std::string output_dir =
      !output.empty() ? output : std::filesystem::path(opt.scene_path).stem().string() + "_results";
  const int rc = tool::run("sinew-simulate-parts", [&] {
    std::optional<ScratchFolder> scratch;
    if (rank == 0) {
      opt.output_dir = output_dir;
    } else {
      scratch.emplace(rank);
      opt.output_dir = scratch->path.string();
      // A resumed run appends to its outputs: these ranks resume on a copy of rank 0's (taken
      // before rank 0 touches them: the barrier below).
      const std::filesystem::path from = output_dir;
      if (!opt.restart.empty() && std::filesystem::is_directory(from))
        std::filesystem::copy(from, scratch->path,
                              std::filesystem::copy_options::recursive |
                                  std::filesystem::copy_options::overwrite_existing);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank == 0) log::info("{} parts (MPI ranks)", size);
    return simulate(opt, rank);
  });
  // An error on some ranks only would leave the others waiting in a collective call: end them all.
  if (rc != tool::kExitOk && rc != tool::kExitUnstable) MPI_Abort(MPI_COMM_WORLD, rc);
  MPI_Finalize();
  return rc;
}
