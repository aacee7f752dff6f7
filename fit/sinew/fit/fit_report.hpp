#pragma once
// What sinew-fit reports (docs/fit.md, "Outputs"): the marker error of a forward run, and the
// tables activations.csv, marker_error.csv and fit_summary.json.
#include <array>
#include <string>
#include <vector>

#include "sinew/fit/fit_options.hpp"
#include "sinew/fit/markers.hpp"
#include "sinew/fit/response.hpp"

namespace sinew::fit {

struct MarkerErrors {
  std::vector<double> frame_rms_mm;  // F; NaN where no marker was seen
  std::vector<double> frame_max_mm;  // F
  double rms_mm = 0, max_mm = 0;     // over every seen (frame, marker)
  // F × M distances (mm; NaN where the marker was not seen), and per marker over its frames.
  std::vector<std::vector<double>> distance_mm;
  std::vector<double> marker_rms_mm, marker_max_mm;  // M; NaN for a marker never seen
  int worst_frame = -1;                              // the frame of the largest RMS
};

// The distance (mm) between each seen marker and the simulated point (rest + the probe's
// displacement at the marker's time). rest: m; unit: m per marker length unit.
MarkerErrors marker_errors(const Markers& markers, const std::vector<std::array<double, 3>>& rest,
                           double unit, const std::vector<ProbePath>& simulated);

// Writes activations.csv, marker_error.csv, marker_residual.csv (marker, its surface vertex, rest
// position in mm, frames seen, rms_mm, max_mm, the residual at the worst frame) and
// fit_summary.json (with the worst frame and the ten markers of the largest RMS) into `dir`.
void write_fit_tables(const std::string& dir, const FitResult& result, const FitOptions& options);

}  // namespace sinew::fit
