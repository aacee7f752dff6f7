#include "sinew/simulator/run/runner.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string_view>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/progress.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/checkpoint.hpp"
#include "sinew/simulator/output/frame_writer.hpp"
#include "sinew/simulator/output/output_schedule.hpp"
#include "sinew/simulator/output/probes.hpp"
#include "sinew/simulator/output/results_writer.hpp"
#include "sinew/simulator/run/run_limits.hpp"
#include "sinew/simulator/run/run_setup.hpp"
#include "sinew/simulator/run/scene_jaw.hpp"

namespace sinew::simulator {

namespace fs = std::filesystem;

namespace {

std::atomic<int> g_interrupt{0};

extern "C" void on_signal(int sig) {
  g_interrupt.store(sig);
}

// Wall time of the step loop by stage (RunSummary::loop_stages): each timed call adds to its stage;
// "other" is the rest of the loop.
class StageClock {
 public:
  enum Stage { steps, frames, probes, checkpoints, summary, count };
  template <typename F>
  void time(Stage stage, F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    seconds_[stage] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  std::vector<std::pair<std::string, double>> stages(double loop_seconds) const {
    static constexpr const char* kNames[count] = {"steps", "frames", "probes", "checkpoints",
                                                  "summary"};
    std::vector<std::pair<std::string, double>> out;
    double timed = 0;
    for (int k = 0; k < count; ++k) {
      out.emplace_back(kNames[k], seconds_[k]);
      timed += seconds_[k];
    }
    out.emplace_back("other", std::max(0.0, loop_seconds - timed));
    return out;
  }

 private:
  double seconds_[count] = {};
};

std::string hourglass_warning(const Energies& e, double yardstick) {
  return fmt::format(
      "hourglass energy is {:.0f}% of the elastic energy at t = {:.6g} s (step {}): above {:.0f}% "
      "the mesh may be folding in hourglass modes that no Jacobian check sees; refine the model, "
      "raise hourglass.kappa, or use hourglass.modulus p_wave where bending does not matter "
      "(docs/stability.md)",
      100.0 * e.hourglass / yardstick, e.time, e.step, 100.0 * kHourglassWarningShare);
}

double largest_elastic(const std::vector<Energies>& energies) {
  double peak = 0;
  for (const auto& e : energies)
    if (std::isfinite(e.elastic)) peak = std::max(peak, e.elastic);
  return peak;
}

double unix_seconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

void install_interrupt_handlers() {
  clear_interrupt();
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

bool interrupt_requested() {
  return g_interrupt.load() != 0;
}

void request_interrupt() {
  g_interrupt.store(SIGINT);
}

void clear_interrupt() {
  g_interrupt.store(0);
}

std::size_t first_hourglass_dominated(const std::vector<Energies>& energies) {
  const double floor = kHourglassFloorShare * largest_elastic(energies);
  for (std::size_t k = 0; k < energies.size(); ++k) {
    const Energies& e = energies[k];
    if (!std::isfinite(e.elastic) || !std::isfinite(e.hourglass)) continue;
    const double yardstick = std::max(e.elastic, floor);
    if (yardstick > 0 && e.hourglass > kHourglassWarningShare * yardstick) return k;
  }
  return energies.size();
}

RunResult run_scene(const RunOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  const auto print =
      options.print ? options.print : [](const std::string& s) { std::fputs(s.c_str(), stdout); };

  LoadedRun run = load_run(options);
  const Scene& scene = run.scene;
  const formats::Model& model = *run.model;
  const ResolvedScene& resolved = run.resolved;
  const Setup& setup = resolved.setup;
  std::unique_ptr<Backend>& backend = run.backend;
  const Plan& plan = backend->plan();
  const auto& counts = run.counts;

  RunResult result;
  result.output_dir = options.output_dir;
  result.summary = run.summary;
  RunSummary& summary = result.summary;
  if (options.explain) print(explain_run(run, options));
  if (!options.run) return result;
  check_output_limits(counts, resolved, options.scene_path, options.force);

  const auto outputs_start = std::chrono::steady_clock::now();
  if (options.output_dir.empty()) throw ConfigError("", "--output", "no output directory given");
  std::error_code ec;
  fs::create_directories(options.output_dir, ec);
  if (ec)
    throw IoError(options.output_dir, "", "cannot create the output directory: " + ec.message());
  const auto out = [&](const std::string& name) {
    return (fs::path(options.output_dir) / name).string();
  };
  const auto summary_path = out("run_summary.json");
  const auto checkpoint_path = out("checkpoint.h5");
  const auto digest =
      run.model_sha256.empty()
          ? run_digest(run.scene_text, scene.model_path, summary.precision)
          : run_digest_from_hash(run.scene_text, run.model_sha256, summary.precision);

  const ResultsOptions ropt = results_options(scene, options.scene_path);
  const bool want_fields = ropt.stress || ropt.jacobian || ropt.energy_density;

  std::unique_ptr<ResultsWriter> results;
  std::unique_ptr<ProbeWriter> probes;
  if (!options.restart.empty()) {
    const auto ckpt = read_checkpoint(options.restart);
    if (ckpt.digest != digest) {
      throw ConfigError(
          options.restart, "digest",
          "the checkpoint was written by another scene, model or precision (the scene file, the "
          "model file and the precision must be exactly those of the interrupted run)");
    }
    // A step past the plan "completed" at once with a time far beyond the scene's (a step of 1e15
    // gave 1.24e10 s simulated: issue 33); the engine checks time against step · Δt.
    if (ckpt.state.step > plan.steps) {
      throw ConfigError(options.restart, "step",
                        fmt::format("step {} is past the {} steps this run plans (duration / Δt): "
                                    "not a checkpoint of this run",
                                    ckpt.state.step, plan.steps));
    }
    try {
      backend->restore(ckpt.state);
    } catch (const ConfigError& e) {
      throw ConfigError(options.restart, e.field(), e.problem());
    }
    summary.restart_step = ckpt.state.step;
    // The energy history of the interrupted run up to the checkpoint, when its summary is there.
    for (const auto& e : read_energy_history(summary_path)) {
      if (e.step <= ckpt.state.step) summary.energies.push_back(e);
    }
    summary.restart_file = options.restart;
    results = ResultsWriter::resume(options.output_dir, model, ropt, ckpt.state.step);
    probes = ProbeWriter::resume(options.output_dir, resolved.probes, ckpt.state.step);
    log::info("resumed from {} at step {} (t = {:.6g} s)", options.restart, ckpt.state.step,
              backend->time() / setup.time_scaling);
  } else {
    results = std::make_unique<ResultsWriter>(options.output_dir, model, ropt);
    probes = std::make_unique<ProbeWriter>(options.output_dir, resolved.probes);
  }

  const auto first_frame_start = std::chrono::steady_clock::now();
  const std::int64_t total = plan.steps;
  const double dt = backend->dt();
  const double s = setup.time_scaling;
  const auto scene_time = [&] { return backend->time() / s; };
  OutputSchedule frames(resolved.output_interval, s, dt, total, false);
  // Probe rows only where there are probes: a scene without any would otherwise keep the default
  // "every step" schedule and cut every batch of steps to one (on an H100 the 1 mm forehead's
  // double step took 0.139 ms through the runner so, 0.051 ms in batches; bench/python_bench.py).
  const bool any_probe = !resolved.probes.empty();
  OutputSchedule rows(any_probe ? resolved.probe_interval : 0.0, s, dt, total,
                      any_probe && !(resolved.probe_interval > 0));

  // Frames are written on another thread while a GPU steps on (frame_writer.hpp).
  FrameWriter frame_writer(*results, backend->host_idle_while_stepping(), s);
  const auto write_summary = [&] {
    summary.steps_done = backend->step_index();
    summary.simulated_time = scene_time();
    summary.frames = frame_writer.frames_written();
    summary.frame_writing_s = frame_writer.write_seconds();
    summary.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    write_run_summary(summary_path, summary);
  };
  // The hourglass warning, once, when the run ends (runner.hpp): its frames' energies are all known.
  const auto judge_hourglass = [&] {
    const std::size_t k = first_hourglass_dominated(summary.energies);
    if (k == summary.energies.size()) return;
    const Energies& e = summary.energies[k];
    const double yardstick =
        std::max(e.elastic, kHourglassFloorShare * largest_elastic(summary.energies));
    summary.warnings.push_back(hourglass_warning(e, yardstick));
    log::warn("{}", summary.warnings.back());
  };
  // The lips' smallest gap is reported whenever the model has pairs, with `contact` or without.
  const std::optional<LipContact> lips = lip_contact_of(model);
  const auto write_frame = [&] {
    Frame frame = backend->frame(want_fields);
    if (lips) {
      const double gap = smallest_lip_gap(*lips, model, frame.displacements);
      if (gap < summary.contact_min_gap) {
        summary.contact_min_gap = gap;
        summary.contact_min_gap_time = frame.time / s;
      }
    }
    auto e = frame.energies;
    frame_writer.push(std::move(frame));
    e.time /= s;  // the summary speaks scene time throughout
    summary.energies.push_back(e);
  };
  const auto write_row = [&] {
    if (probes->empty()) return;
    probes->record_probed(
        scene_time(), backend->step_index(), backend->displacements(probes->displacement_nodes()),
        [&](const std::vector<Index>& nodes) { return backend->reaction(nodes); });
  };
  const auto write_ckpt = [&] {
    frame_writer.finish();  // never a checkpoint ahead of the frames on disk
    Checkpoint c;
    c.state = backend->state();
    c.digest = digest;
    c.scene_file = options.scene_path;
    c.model_file = scene.model_path;
    write_checkpoint(checkpoint_path, c);
  };

  // Step 0 (or the checkpoint's step) already has its frame and row when resuming.
  if (options.restart.empty()) {
    write_frame();
    write_row();
  }
  write_summary();

  ProgressOptions popt;
  popt.quiet = options.quiet;
  popt.unit = "steps";
  ProgressReporter progress("simulate", total, popt);
  const std::int64_t first_step = backend->step_index();
  const auto loop_start = std::chrono::steady_clock::now();
  summary.setup_s = std::chrono::duration<double>(loop_start - wall_start).count();
  summary.setup_stages = {
      {"model", run.model_s},
      {"engine", run.engine_s},
      {"outputs", std::chrono::duration<double>(first_frame_start - outputs_start).count()},
      {"first_frame", std::chrono::duration<double>(loop_start - first_frame_start).count()}};
  summary.loop_start_unix_s = unix_seconds();
  StageClock clock;
  std::int64_t next_frame = frames.next_after(first_step);
  std::int64_t next_row = rows.next_after(first_step);
  const std::int64_t every = options.checkpoint_every;
  const auto finish_loop = [&] {
    summary.steps_this_run = backend->step_index() - first_step;
    const double loop_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
    summary.time_per_step_s =
        summary.steps_this_run > 0 ? loop_s / double(summary.steps_this_run) : 0.0;
    summary.loop_stages = clock.stages(loop_s);
    summary.loop_end_unix_s = unix_seconds();
  };
  // After a failure `reported`: every frame queued so far into the file (an unstable run keeps its
  // frames), then the file closed, each in its own try; a failure of either that is not the one
  // being reported is logged (a results file that cannot be finished is moved out of its name,
  // results_writer.hpp, and the message says where).
  const auto wind_down = [&](const Error& reported) {
    const auto attempt = [&](auto&& f) {
      try {
        f();
      } catch (const Error& failure) {
        if (std::string_view(failure.what()) != reported.what()) log::warn("{}", failure.what());
      }
    };
    attempt([&] { frame_writer.finish(); });
    attempt([&] { results->close(); });
  };
  try {
    while (backend->step_index() < total) {
      const std::int64_t n = backend->step_index();
      std::int64_t target =
          std::min({total, next_frame, next_row, n + backend->preferred_step_count()});
      if (every > 0) target = std::min(target, (n / every + 1) * every);
      if (options.stop_at_step >= 0)
        target = std::min(target, std::max(options.stop_at_step, n + 1));
      clock.time(StageClock::steps, [&] { backend->step(target - n); });
      const std::int64_t now = backend->step_index();
      if (now == next_frame) {
        clock.time(StageClock::frames, write_frame);
        next_frame = frames.next_after(now);
        clock.time(StageClock::summary, write_summary);
      }
      if (now == next_row) {
        clock.time(StageClock::probes, write_row);
        next_row = rows.next_after(now);
      }
      if (every > 0 && now % every == 0 && now < total)
        clock.time(StageClock::checkpoints, write_ckpt);
      progress.update(
          now, [&] { return fmt::format("t = {:.4g} / {:.4g} s", scene_time(), scene.duration); });
      const bool stop = options.stop_at_step >= 0 && now >= options.stop_at_step && now < total;
      if ((g_interrupt.load() != 0 || stop) && now < total) {
        write_ckpt();
        results->close();  // a failure of its last write is this run's error, not a bad file
        finish_loop();
        judge_hourglass();
        summary.status = "interrupted";
        summary.message = fmt::format("stopped at step {} (t = {:.6g} s); resume with --restart {}",
                                      now, scene_time(), checkpoint_path);
        write_summary();
        progress.finish();
        log::warn("{}", summary.message);
        result.ran = true;
        return result;
      }
    }
    progress.finish();
    clock.time(StageClock::frames, [&] {
      frame_writer.finish();
      results->close();  // a failure of its last write is this run's error, not a bad file
    });
  } catch (const InstabilityError& e) {
    wind_down(e);
    finish_loop();
    judge_hourglass();
    summary.status = "unstable";
    summary.message = e.what();
    write_summary();
    throw;
  } catch (const Error& e) {
    wind_down(e);
    finish_loop();
    summary.status = "failed";
    summary.message = e.what();
    try {
      write_summary();
    } catch (const Error&) {
      // The original error is the one to report (run_summary.cpp removes a summary it cannot
      // rewrite).
    }
    throw;
  }
  finish_loop();
  judge_hourglass();
  summary.status = "completed";
  write_summary();
  result.ran = true;
  return result;
}

}  // namespace sinew::simulator
