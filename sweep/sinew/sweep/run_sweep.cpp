#include "sinew/sweep/run_sweep.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/run_summary.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::sweep {

namespace fs = std::filesystem;

namespace {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string read_or_empty(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string summary_status(const fs::path& dir) {
  std::ifstream in(dir / "run_summary.json");
  if (!in) return "";
  const auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("status") || !j["status"].is_string())
    return "";
  return j["status"].get<std::string>();
}

std::string format_eta(double s) {
  if (!(s >= 0) || s > 1e7) return "?";
  const auto t = std::int64_t(s + 0.5);
  if (t >= 3600) return fmt::format("{}h{:02}m", t / 3600, t / 60 % 60);
  if (t >= 60) return fmt::format("{}m{:02}s", t / 60, t % 60);
  return fmt::format("{}s", t);
}

}  // namespace

bool is_finished_status(const std::string& status) {
  return status == "completed" || status == "unstable" || status == "failed";
}

std::string run_directory(const SweepOptions& options, const PlannedRun& run) {
  return (fs::path(options.output_dir) / run.name).string();
}

bool run_is_finished(const SweepOptions& options, const PlannedRun& run) {
  const fs::path dir = run_directory(options, run);
  return read_or_empty(dir / "scene.yaml") == run.scene_text &&
         is_finished_status(summary_status(dir));
}

Row execute_run(const Sweep& sweep, const PlannedRun& run, const SweepOptions& options,
                simulator::ModelCache* models) {
  const log::ScopedContext context(run.name);  // the runner's messages name the run
  const fs::path dir = run_directory(options, run);
  const auto scene_path = (dir / "scene.yaml").string();
  simulator::RunOptions ro;
  ro.scene_path = scene_path;
  ro.output_dir = dir.string();
  ro.device = options.settings.device;
  if (options.settings.precision)
    ro.precision = *options.settings.precision == "float" ? simulator::Precision::float32
                                                          : simulator::Precision::float64;
  const int concurrent = std::max(1, options.settings.concurrent);
  ro.threads =
      options.settings.threads > 0
          ? options.settings.threads
          : std::max(1, omp_get_num_procs() / (std::max(1, options.ranks_on_machine) * concurrent));
  ro.cuda_device = options.cuda_device;
  ro.quiet = true;
  ro.force = options.settings.force;
  ro.models = models;
  std::string failure;
  try {
    // An interrupted attempt of this very run (a SIGTERM, or mpirun ending the job when another
    // rank died) goes on from its checkpoint; the runner checks the checkpoint's digest.
    const auto checkpoint = dir / "checkpoint.h5";
    const bool resume = summary_status(dir) == "interrupted" && fs::exists(checkpoint) &&
                        read_or_empty(dir / "scene.yaml") == run.scene_text;
    bool done = false;
    if (resume) {
      ro.restart = checkpoint.string();
      try {
        simulator::run_scene(ro);
        done = true;
      } catch (const ConfigError& e) {
        if (e.file() != ro.restart) throw;
        log::warn("cannot resume ({}); running it again from the start", e.what());
        ro.restart.clear();
      }
    }
    if (!done) {
      // What an earlier attempt left (frames, a checkpoint) would mix with this one's.
      fs::remove_all(dir);
      fs::create_directories(dir);
      write_text_atomically(scene_path, run.scene_text);
      simulator::run_scene(ro);
    }
  } catch (const InstabilityError&) {
    // The runner wrote the summary: status unstable, its message, every frame so far.
  } catch (const std::exception& e) {
    failure = e.what();
  }
  // An error before the step loop leaves no terminal summary: the sweep writes one.
  if (!failure.empty() && !is_finished_status(summary_status(dir))) {
    simulator::RunSummary s;
    s.status = "failed";
    s.message = failure;
    s.scene_file = scene_path;
    s.model_file = run.model_path;
    try {
      fs::create_directories(dir);
      simulator::write_run_summary((dir / "run_summary.json").string(), s);
    } catch (const std::exception& e) {
      log::error("cannot record the failure ({}): {}", e.what(), failure);
    }
  }
  try {
    return collect_row(sweep, run, dir.string());
  } catch (const std::exception& e) {
    // A probe file or summary that does not read back: the run's row says so, the sweep goes on.
    Row row = collect_row(sweep, run, "");
    row.status = "failed";
    row.message = std::string("its results do not read back: ") + e.what();
    return row;
  }
}

SweepProgress::SweepProgress(std::int64_t to_run, std::int64_t skipped, bool quiet)
    : to_run_(to_run), skipped_(skipped), quiet_(quiet), start_s_(now_s()) {
  if (!quiet_ && skipped_ > 0)
    log::info("sweep: {} runs finished before, skipped; {} to run", skipped_, to_run_);
}

void SweepProgress::finished(const Row& row) {
  ++done_;
  if (row.status != "completed") ++failed_;
  if (quiet_) return;
  const double elapsed = now_s() - start_s_;
  const double eta = done_ > 0 ? elapsed / double(done_) * double(to_run_ - done_) : -1;
  log::info("sweep: {}/{} runs done, {} failed, ETA {} ({}: {}{})", done_, to_run_, failed_,
            format_eta(eta), row.name, row.status,
            row.message.empty() ? "" : ": " + row.message.substr(0, 200));
}

std::vector<std::size_t> start_sweep(const Sweep& sweep, const SweepOptions& options,
                                     SweepReport& report) {
  std::error_code ec;
  fs::create_directories(options.output_dir, ec);
  if (ec)
    throw IoError(options.output_dir, "", "cannot create the results folder: " + ec.message());
  std::vector<std::size_t> pending;
  for (std::size_t i = 0; i < sweep.runs.size(); ++i) {
    const auto& run = sweep.runs[i];
    if (run_is_finished(options, run)) {
      report.rows.push_back(collect_row(sweep, run, run_directory(options, run)));
      ++report.skipped;
    } else {
      report.rows.push_back(collect_row(sweep, run, ""));
      pending.push_back(i);
    }
  }
  write_table(sweep, report.rows, options.output_dir);
  return pending;
}

void choose_gpu_wait(const SweepOptions& options) {
  if (options.settings.device == "cpu" || !simulator::cuda_device_available()) return;
  const int cores = std::max(1, omp_get_num_procs() / std::max(1, options.ranks_on_machine));
  const bool block = options.gpu_wait == "block" ||
                     (options.gpu_wait == "auto" && options.settings.concurrent > cores);
  simulator::set_cuda_blocking_wait(options.cuda_device, block);
}

SweepReport run_sweep(const Sweep& sweep, const SweepOptions& options) {
  const int concurrent = std::max(1, options.settings.concurrent);
  choose_gpu_wait(options);
  SweepReport report;
  const auto pending = start_sweep(sweep, options, report);

  SweepProgress progress(std::int64_t(pending.size()), report.skipped, options.quiet);
  std::mutex mutex;  // rows, progress, table
  double last_table = now_s();
  std::atomic<std::size_t> next{0};
  std::exception_ptr table_error;
  simulator::ModelCache models;
  const auto worker = [&] {
    for (std::size_t k = next++; k < pending.size() && !simulator::interrupt_requested();
         k = next++) {
      const auto& run = sweep.runs[pending[k]];
      Row row = execute_run(sweep, run, options, &models);
      std::lock_guard lock(mutex);
      report.rows[pending[k]] = std::move(row);
      ++report.ran;
      progress.finished(report.rows[pending[k]]);
      if (now_s() - last_table > 2.0) {
        try {
          write_table(sweep, report.rows, options.output_dir);
        } catch (...) {
          table_error = std::current_exception();
        }
        last_table = now_s();
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < concurrent; ++t) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  report.failed = progress.failed();
  report.interrupted = simulator::interrupt_requested();
  write_table(sweep, report.rows, options.output_dir);
  if (table_error) std::rethrow_exception(table_error);
  return report;
}

}  // namespace sinew::sweep
