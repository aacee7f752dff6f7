#pragma once
// sinew-fit as a library call (docs/fit.md): marker trajectories + a base scene → per-frame
// activations of the rig's muscles, a scene that replays them, and a report.
//
//   markers.csv, scene.yaml ─ check ─ K response runs (one per muscle) ─ bounded least squares
//     ─ forward run ─ [refit the residual with the same response, forward run] × corrections
//     ─ outputs in <output>.tmp-<pid>/, renamed to <output> at the end
//
// Outputs (docs/fit.md, "Outputs"): fitted_scene.yaml, activations.csv, marker_error.csv,
// fit_summary.json, runs/ (the forward runs; the responses too unless a cache folder is given),
// and what the caller's `before_commit` adds (sinew-fit: activations.png).
#include <functional>
#include <string>

#include "sinew/fit/fit_options.hpp"

namespace sinew::fit {

// Runs the fit. Bad input (markers, scene, options) throws before any run: FormatError or
// ConfigError naming the file, the line and the value; nothing is left under the output's name.
// before_commit(tmp_dir, result) is called with the temporary folder before it is renamed.
FitResult run_fit(const FitOptions& options,
                  const std::function<void(const std::string&, const FitResult&)>& before_commit =
                      {});

}  // namespace sinew::fit
