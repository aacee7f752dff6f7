#pragma once
// What a caller asks of a fit (FitOptions: sinew-fit's options) and what it gets back (FitResult):
// the arguments of run_fit (fit_run.hpp), also read by the report (fit_report.hpp). Apart from
// fit_run.hpp so that the report, which the fit calls, does not include the fit.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace sinew::fit {

struct FitOptions {
  std::string scene_path;    // the base scene (its muscles' curves are replaced)
  // The marker CSV (markers.hpp), or a run's output folder: its probe_<name>.csv of every
  // displacement probe of the scene become the markers (rest position + displacement).
  std::string markers_path;
  // Or (markers_path empty) a target manifest (target_shapes.hpp): sculpted meshes of a visual
  // surface at key times, whose vertices become markers on their nearest nodes.
  std::string targets_path;
  std::string target_surface;  // the visual surface the targets sculpt ("": the model's first)
  int target_markers = 200;    // vertices sampled as markers (farthest-point); 0: every vertex
  std::string output_dir;    // written as <output_dir>.tmp-<pid>, renamed at the end
  std::vector<std::string> muscles;  // the muscles fitted; empty: every muscle of the model
  // The jaw's degrees of freedom fitted (the scene's `jaw:` keys, docs/scene-format.md): "auto"
  // (opening_deg, protrusion_mm and lateral_mm when the model has a jaw, else none), "none", or
  // a comma-separated list of them. Fitted, they replace the base scene's `jaw:`.
  std::string jaw = "auto";
  double max_activation = 1;         // upper bound of every activation, (0, 1]
  double knot_interval = 0;          // s between knots; 0: the markers' median frame interval
  double step_activation = 0.3;      // a0 of the response runs
  double response_ramp = 0;          // s over which they ramp to a0; 0: the median frame interval
  double smoothing = 1e-3;           // λ relative to trace(AᵀA)/n (bounded_least_squares.hpp)
  double effort = 0;                 // μ relative to trace(AᵀA)/n (bounded_least_squares.hpp)
  int corrections = 4;               // refits of the forward run's residual
  double marker_unit = 0;            // m per marker length unit; 0: the base scene's `units`
  double sample_interval = 0;        // s between probe rows of the runs; 0: every step
  std::string cache_dir;  // response runs kept and reused here ("" : under the output's runs/)
  std::string device = "cpu";
  int threads = 0;
  bool quiet = true;  // no progress bars in the runs
};

struct FitResult {
  std::vector<std::string> muscles;               // K
  std::vector<double> knot_times;                 // J + 1, from 0
  std::vector<std::vector<double>> activations;   // K × (J + 1), 0 at t = 0
  std::vector<std::string> jaw;                   // D fitted jaw keys (opening_deg, ...)
  std::vector<std::vector<double>> jaw_values;    // D × (J + 1): degrees or mm, 0 at t = 0
  std::vector<double> frame_times;                // F, the markers'
  std::vector<double> frame_rms_mm;               // F, NaN for a frame with no marker seen
  std::vector<double> frame_max_mm;               // F
  double rms_mm = 0;                              // over every seen (frame, marker)
  double max_mm = 0;
  std::vector<double> iteration_rms_mm;           // each forward run's, in order
  int best_iteration = 0;                         // the one returned
  int response_runs = 0, response_runs_reused = 0, forward_runs = 0;
  double response_s = 0, forward_s = 0, solve_s = 0, total_s = 0;  // wall time
  std::int64_t steps_per_run = 0;
  std::string output_dir;                         // the final name

  // Per marker (M, the markers' order), in the returned forward run: the residual
  // |simulated − target| over the frames it was seen (mm; NaN when never seen), its rest
  // position (the node's, m) and, for target shapes, its surface vertex (-1 otherwise).
  std::vector<std::string> marker_names;
  std::vector<std::array<double, 3>> marker_rest;
  std::vector<std::int32_t> marker_vertex;
  std::vector<double> marker_rms_mm, marker_max_mm;
  // The frame with the largest marker RMS and every marker's residual there (mm; NaN unseen).
  int worst_frame = -1;
  std::vector<double> worst_frame_residual_mm;
  std::string model_path;  // the base scene's model (absolute)
  std::string surface;     // the visual surface of the targets ("" for marker input)
};

}  // namespace sinew::fit
