#include "sinew/fit/fit_report.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "sinew/common/atomic_file.hpp"

namespace sinew::fit {

MarkerErrors marker_errors(const Markers& markers, const std::vector<std::array<double, 3>>& rest,
                           double unit, const std::vector<ProbePath>& simulated) {
  MarkerErrors e;
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t f = 0; f < markers.frame_count(); ++f) {
    double frame_sum = 0, frame_max = 0;
    std::size_t n = 0;
    for (std::size_t m = 0; m < markers.marker_count(); ++m) {
      if (!markers.seen[f][m]) continue;
      const auto u = simulated[m].at(markers.times[f]);
      double d2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double diff = 1e3 * (rest[m][d] + u[d] - markers.positions[f][m][d] * unit);
        d2 += diff * diff;
      }
      frame_sum += d2;
      frame_max = std::max(frame_max, std::sqrt(d2));
      ++n;
    }
    e.frame_rms_mm.push_back(n ? std::sqrt(frame_sum / static_cast<double>(n)) : NAN);
    e.frame_max_mm.push_back(n ? frame_max : NAN);
    sum += frame_sum;
    count += n;
    e.max_mm = std::max(e.max_mm, frame_max);
  }
  e.rms_mm = count ? std::sqrt(sum / static_cast<double>(count)) : 0;
  return e;
}

void write_fit_tables(const std::string& dir, const FitResult& r, const FitOptions& o) {
  const std::filesystem::path d(dir);
  std::string act = "time";
  for (const auto& m : r.muscles) act += "," + m;
  act += '\n';
  for (std::size_t j = 0; j < r.knot_times.size(); ++j) {
    act += fmt::format("{:.9g}", r.knot_times[j]);
    for (const auto& curve : r.activations) act += fmt::format(",{:.9g}", curve[j]);
    act += '\n';
  }
  write_text_atomically((d / "activations.csv").string(), act);

  std::string err = "time,rms_mm,max_mm\n";
  for (std::size_t f = 0; f < r.frame_times.size(); ++f) {
    if (std::isnan(r.frame_rms_mm[f]))
      err += fmt::format("{:.9g},,\n", r.frame_times[f]);
    else
      err += fmt::format("{:.9g},{:.6f},{:.6f}\n", r.frame_times[f], r.frame_rms_mm[f],
                         r.frame_max_mm[f]);
  }
  write_text_atomically((d / "marker_error.csv").string(), err);

  nlohmann::json j;
  j["scene"] = o.scene_path;
  j["markers"] = o.markers_path;
  j["muscles"] = r.muscles;
  j["knot_interval_s"] = r.knot_times.size() > 1 ? r.knot_times[1] : 0.0;
  j["knots"] = r.knot_times.size();
  j["frames"] = r.frame_times.size();
  j["marker_rms_mm"] = r.rms_mm;
  j["marker_max_mm"] = r.max_mm;
  j["iteration_marker_rms_mm"] = r.iteration_rms_mm;
  j["best_iteration"] = r.best_iteration;
  j["options"] = {{"max_activation", o.max_activation},
                  {"step_activation", o.step_activation},
                  {"response_ramp_s", o.response_ramp},
                  {"smoothing", o.smoothing},
                  {"effort", o.effort},
                  {"corrections", o.corrections},
                  {"device", o.device}};
  j["runs"] = {{"response", r.response_runs},
               {"response_reused", r.response_runs_reused},
               {"forward", r.forward_runs},
               {"steps_per_run", r.steps_per_run}};
  j["wall_time_s"] = {{"responses", r.response_s},
                      {"forward", r.forward_s},
                      {"solve", r.solve_s},
                      {"total", r.total_s}};
  write_text_atomically((d / "fit_summary.json").string(), j.dump(2) + "\n");
}

}  // namespace sinew::fit
