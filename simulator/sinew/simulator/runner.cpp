#include "sinew/simulator/runner.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/progress.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/checkpoint.hpp"
#include "sinew/simulator/cuda_backend.hpp"
#include "sinew/simulator/engine.hpp"
#include "sinew/simulator/frame_writer.hpp"
#include "sinew/simulator/probes.hpp"
#include "sinew/simulator/results_writer.hpp"
#include "sinew/simulator/run_estimate.hpp"
#include "sinew/simulator/run_limits.hpp"

namespace sinew::simulator {

namespace fs = std::filesystem;

namespace {

std::atomic<int> g_interrupt{0};

extern "C" void on_signal(int sig) {
  g_interrupt.store(sig);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "", "cannot open the scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The step of event k for events every `interval` of scene time: the first step at or after
// k · interval. A function of k alone, so a resumed run picks the same steps.
std::int64_t event_step(std::int64_t k, double interval, double time_scaling, double dt) {
  const double x = double(k) * interval * time_scaling / dt;
  return static_cast<std::int64_t>(std::ceil(x - 1e-9 * std::max(1.0, x)));
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

// Iterates the event steps of one output stream (frames or probe rows) past a given step.
class Schedule {
 public:
  Schedule(double interval, double time_scaling, double dt, std::int64_t last_step, bool every_step)
      : interval_(interval),
        scaling_(time_scaling),
        dt_(dt),
        last_(last_step),
        every_(every_step) {}
  // The first event step strictly after `step` (last_step when none before it).
  std::int64_t next_after(std::int64_t step) {
    if (step >= last_) return std::numeric_limits<std::int64_t>::max();
    if (every_) return step + 1;
    if (!(interval_ > 0)) return last_;
    // Jump to the events of this step first: with an interval far below Δt, counting up one
    // event at a time would take interval/Δt iterations per step.
    const double first = std::min(double(step) * dt_ / (interval_ * scaling_), 0x1p62);
    k_ = std::max(k_, static_cast<std::int64_t>(first) - 1);
    while (event_step(k_, interval_, scaling_, dt_) <= step) ++k_;
    return std::min(event_step(k_, interval_, scaling_, dt_), last_);
  }

 private:
  double interval_, scaling_, dt_;
  std::int64_t last_;
  bool every_;
  std::int64_t k_ = 0;
};

std::string device_text(const std::string& backend, int threads) {
  return fmt::format("{} (OpenMP, {} thread{})", backend, threads, threads == 1 ? "" : "s");
}

std::string hourglass_warning(const Energies& e) {
  return fmt::format(
      "hourglass energy is {:.0f}% of the strain energy at t = {:.6g} s (step {}): above {:.0f}% "
      "the mesh may be folding in hourglass modes that no Jacobian check sees; refine the model, "
      "raise hourglass.kappa, or use hourglass.modulus p_wave where bending does not matter "
      "(docs/stability.md)",
      100.0 * e.hourglass / e.strain, e.time, e.step, 100.0 * kHourglassWarningShare);
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

void clear_interrupt() {
  g_interrupt.store(0);
}

RunResult run_scene(const RunOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  const auto print =
      options.print ? options.print : [](const std::string& s) { std::fputs(s.c_str(), stdout); };

  // Device first: a request this build cannot satisfy is refused before any work.
  if (options.device != "cpu" && options.device != "auto" && options.device != "cuda") {
    throw ConfigError(
        "", "--device",
        fmt::format("unknown device '{}' (expected cpu, cuda or auto)", options.device));
  }
  bool cuda = false;
  if (options.device == "cuda") {
    if (!cuda_device_available()) {
#if defined(SINEW_CUDA_ENABLED)
      throw ResourceError(
          "", "--device",
          "no CUDA device is available to this process; use --device cpu (or auto)");
#else
      throw ResourceError(
          "", "--device",
          "this build of sinew has no CUDA backend (configure with "
          "-DSINEW_WITH_CUDA=ON where nvcc is available); use --device cpu (or auto)");
#endif
    }
    cuda = true;
  } else if (options.device == "auto") {
    cuda = cuda_device_available();
  }

  const auto scene_text = read_text(options.scene_path);
  const auto scene = parse_scene_text(scene_text, options.scene_path,
                                      fs::path(options.scene_path).parent_path().string());
  if (!fs::exists(scene.model_path)) {
    throw ConfigError(options.scene_path, "model",
                      fmt::format("the model file '{}' does not exist (model: {}, relative to the "
                                  "scene's folder)",
                                  scene.model_path, scene.model));
  }
  const formats::Model model = formats::read_model(scene.model_path);
  ResolveOptions ro;
  ro.precision = options.precision;
  ro.threads = options.threads;
  const auto resolved = resolve_scene(scene, model, ro);
  const auto& setup = resolved.setup;

  std::unique_ptr<Backend> backend;
  try {
    CudaOptions cuda_options;
    cuda_options.device = options.cuda_device;
    if (options.make_backend) cuda = false;  // the caller's engine, on the host
    backend = options.make_backend ? options.make_backend(model, setup)
              : cuda               ? make_cuda_backend(model, setup, cuda_options)
                                   : make_cpu_backend(model, setup);
  } catch (const ConfigError& e) {
    // The engine names Setup fields; point at the scene key the user wrote instead.
    if (!e.file().empty()) throw;
    static const std::pair<const char*, const char*> kKeys[] = {
        {"time_step.user_dt", "time_step.value"},
        {"time_step.safety_factor", "time_step.safety_factor"},
        {"duration", "duration"},
        {"damping_alpha", "damping"},
        {"mass_scaling", "mass_scaling"},
        {"time_scaling", "time_scaling"},
        {"hourglass.kappa", "hourglass.kappa"},
        {"gravity", "gravity"}};
    std::string key = e.field();
    for (const auto& [field, scene_key] : kKeys) {
      if (key == field) key = scene_key;
    }
    auto err = ConfigError(options.scene_path, key, e.problem());
    if (e.index()) err.at(*e.index());
    throw err;
  }
  const Plan& plan = backend->plan();
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();

  RunResult result;
  result.output_dir = options.output_dir;
  RunSummary& summary = result.summary;
  summary.scene_file = options.scene_path;
  summary.model_file = scene.model_path;
  summary.device =
      cuda ? "cuda (" + cuda_device_name() + ")" : device_text(backend->name(), threads);
  summary.precision = precision_name(setup.precision);
  summary.threads = threads;
  summary.effects = resolved.effects;
  summary.duration = scene.duration;
  summary.time_scaling = setup.time_scaling;
  summary.mass_scaling = setup.mass_scaling;
  summary.dt = plan.dt;
  summary.dt_critical = plan.dt_critical;
  summary.dt_reason = plan.dt_reason;
  summary.steps_planned = plan.steps;
  summary.warnings = plan.warnings;
  for (const auto& p : resolved.probes) {
    if (p.distance > model.grid.voxel_size) {
      summary.warnings.push_back(
          fmt::format("probe '{}': the nearest node is {:.6g} m from the point (more than a voxel)",
                      p.name, p.distance));
    }
  }

  const auto counts = count_outputs(model, plan, resolved);
  if (options.explain) {
    std::string text = plan.explain();
    if (!text.empty() && text.back() != '\n') text += '\n';
    text += fmt::format("Device: {}\n", summary.device);
    text +=
        fmt::format("Outputs: {}\n", options.output_dir.empty() ? "(none)" : options.output_dir);
    std::string fields;
    for (auto f : resolved.fields)
      fields += (fields.empty() ? "" : ", ") + std::string(to_string(f));
    text += fmt::format(
        "  frames every {} s of scene time ({}), fields: {}\n",
        resolved.output_interval > 0 ? fmt::format("{:.6g}", resolved.output_interval) : "-",
        resolved.output_interval > 0 ? "plus the first and last" : "first and last only", fields);
    text += describe_outputs(counts);
    for (const auto& p : resolved.probes)
      text += fmt::format("  probe '{}': {}\n", p.name, p.description);
    for (const auto& w : summary.warnings) text += fmt::format("  warning: {}\n", w);
    const bool element_fields =
        std::any_of(resolved.fields.begin(), resolved.fields.end(), [](auto f) {
          return f == OutputField::stress || f == OutputField::jacobian ||
                 f == OutputField::energy_density;
        });
    text += describe(estimate_run(*backend, resolved, counts, element_fields));
    if (options.explain_more) text += options.explain_more(model, plan);
    print(text);
  }
  if (!options.run) return result;
  check_output_limits(counts, resolved, options.scene_path, options.force);

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
  const auto digest = run_digest(scene_text, scene.model_path, summary.precision);

  ResultsOptions ropt;
  ropt.stress = scene.output.has(OutputField::stress);
  ropt.jacobian = scene.output.has(OutputField::jacobian);
  ropt.energy_density = scene.output.has(OutputField::energy_density);
  ropt.surfaces = scene.output.has(OutputField::surfaces);
  ropt.model_file = scene.model_path;
  ropt.scene_file = options.scene_path;
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

  const std::int64_t total = plan.steps;
  const double dt = backend->dt();
  const double s = setup.time_scaling;
  const auto scene_time = [&] { return backend->time() / s; };
  Schedule frames(resolved.output_interval, s, dt, total, false);
  Schedule rows(resolved.probe_interval, s, dt, total, !(resolved.probe_interval > 0));

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
  bool hourglass_warned = false;
  const auto write_frame = [&] {
    Frame frame = backend->frame(want_fields);
    auto e = frame.energies;
    frame_writer.push(std::move(frame));
    e.time /= s;  // the summary speaks scene time throughout
    summary.energies.push_back(e);
    // One-point elements can fold into hourglass modes that the centre Jacobian does not see
    // (docs/stability.md); explicit codes (LS-DYNA, Abaqus) flag this share of the internal energy.
    if (!hourglass_warned && e.hourglass > kHourglassWarningShare * e.strain && e.strain > 0) {
      hourglass_warned = true;
      summary.warnings.push_back(hourglass_warning(e));
      log::warn("{}", summary.warnings.back());
    }
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
        finish_loop();
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
  } catch (const InstabilityError& e) {
    try {
      frame_writer.finish();  // every frame so far in the file
    } catch (const Error&) {
      // The instability is the error to report; the summary is written below.
    }
    finish_loop();
    summary.status = "unstable";
    summary.message = e.what();
    write_summary();
    throw;
  } catch (const Error& e) {
    finish_loop();
    summary.status = "failed";
    summary.message = e.what();
    try {
      frame_writer.finish();
      write_summary();
    } catch (const Error&) {
      // The original error is the one to report.
    }
    throw;
  }
  progress.finish();
  clock.time(StageClock::frames, [&] { frame_writer.finish(); });
  finish_loop();
  summary.status = "completed";
  write_summary();
  result.ran = true;
  return result;
}

}  // namespace sinew::simulator
