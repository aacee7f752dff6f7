// sinew-fit: per-frame muscle activations from marker trajectories (docs/fit.md).
//
//   sinew-fit SCENE MARKERS.csv|RUN_FOLDER -o OUTDIR [options]
//   sinew-fit SCENE --targets TARGETS.csv [--target-surface NAME] [--target-markers N] -o OUTDIR
//             [--muscles a,b,...] [--jaw auto|none|KEYS] [--max-activation A]
//             [--knot-interval S] [--smoothing L] [--effort E] [--corrections N] [--step-activation A0]
//             [--response-ramp S]
//             [--marker-unit m|cm|mm] [--sample-interval S] [--cache DIR]
//             [--device cpu|cuda|auto] [--threads N] [--quiet]
//
// Exit status: 0 done, 1 bad input or I/O error (nothing written under OUTDIR), 2 bad command
// line, 3 a run became unstable, 130 interrupted.
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <map>
#include <string>
#include <vector>

#include "activation_plot.hpp"
#include "residual_map.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/threads.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/fit/fit_run.hpp"
#include "sinew/postprocess/png_writer.hpp"
#include "sinew/simulator/run/runner.hpp"

int main(int argc, char** argv) {
  using namespace sinew;
  threads::prefer_passive_wait(argv);
  CLI::App app{
      "sinew-fit: the rig's muscle activations per frame from marker trajectories "
      "or target shapes (docs/fit.md); writes a scene that replays them, the marker error per "
      "frame and per marker, a plot of the curves and a residual map on the skin"};
  fit::FitOptions o;
  std::string unit;
  bool quiet = false;
  app.add_option("scene", o.scene_path, "Base scene (YAML): model, effects, probes")
      ->required();
  app.add_option("markers", o.markers_path,
                 "Marker CSV: time,NAME.x,NAME.y,NAME.z,... or a run's folder (docs/fit.md)");
  app.add_option("--targets", o.targets_path,
                 "Target shapes instead of markers: a CSV 'time,mesh' of OBJ meshes with the "
                 "skin's topology (sinew-export's rest OBJ, sculpted), one per key time");
  app.add_option("--target-surface", o.target_surface,
                 "The visual surface the targets sculpt (default: the model's first)");
  app.add_option("--target-markers", o.target_markers,
                 "Target vertices sampled as markers, farthest-point (200; 0: every vertex)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("-o,--output", o.output_dir, "Output folder")->required();
  app.add_option("--muscles", o.muscles, "Muscles to fit (default: every muscle of the model)")
      ->delimiter(',');
  app.add_option("--jaw", o.jaw,
                 "The jaw's keys to fit: auto (opening_deg, protrusion_mm, lateral_mm when the "
                 "model has a jaw), none, or a comma-separated list (auto)");
  app.add_option("--max-activation", o.max_activation, "Upper bound of every activation (1)");
  app.add_option("--knot-interval", o.knot_interval,
                 "s between activation knots (default: the markers' median frame interval)");
  app.add_option("--smoothing", o.smoothing,
                 "Weight of the second-difference regulariser, relative (1e-3)");
  app.add_option("--effort", o.effort,
                 "Weight of the sum of activations (prefers the fewest muscles), relative (0)");
  app.add_option("--corrections", o.corrections,
                 "Refits of the forward run's residual (4)");
  app.add_option("--step-activation", o.step_activation,
                 "Activation of each response run (0.3)");
  app.add_option("--response-ramp", o.response_ramp,
                 "s over which each response run ramps to its activation (default: the markers' "
                 "median frame interval)");
  app.add_option("--marker-unit", unit, "Length unit of the markers (default: the scene's units)")
      ->check(CLI::IsMember({"m", "cm", "mm"}));
  app.add_option("--sample-interval", o.sample_interval,
                 "s between probe rows of the runs (default: every step)");
  app.add_option("--cache", o.cache_dir,
                 "Keep the response runs here and reuse them when the scene and model match");
  app.add_option("--device", o.device, "cpu, cuda or auto (cpu)")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  app.add_option("--threads", o.threads, "OpenMP threads (default: every core)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("-q,--quiet", quiet, "Warnings and errors only");
  app.set_version_flag("--version", std::string(sinew::kVersion));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  log::set_level(quiet ? log::Level::warn : log::Level::info);
  const std::map<std::string, double> units{{"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}};
  if (!unit.empty()) o.marker_unit = units.at(unit);
  simulator::install_interrupt_handlers();
  tool::ExitCodes codes;
  codes.instability = tool::kExitUnstable;
  const int status = tool::run("sinew-fit", codes, [&] {
    const auto r = fit::run_fit(o, [](const std::string& dir, const fit::FitResult& result) {
      postprocess::write_png(dir + "/activations.png", fit::draw_activation_plot(result));
      postprocess::write_png(dir + "/residual_map.png", fit::draw_residual_map(result));
    });
    log::info("sinew-fit: {} muscles, {} frames: marker RMS {:.3f} mm (max {:.3f} mm); {} "
              "response runs ({} reused) and {} forward runs in {:.1f} s -> {}",
              r.muscles.size(), r.frame_times.size(), r.rms_mm, r.max_mm, r.response_runs,
              r.response_runs_reused, r.forward_runs, r.total_s, r.output_dir);
    return tool::kExitOk;
  });
  return simulator::interrupt_requested() ? tool::kExitInterrupted : status;
}
