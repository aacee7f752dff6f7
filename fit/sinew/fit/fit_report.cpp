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
  const std::size_t markers_n = markers.marker_count();
  std::vector<double> marker_sum(markers_n, 0.0), marker_max(markers_n, 0.0);
  std::vector<std::size_t> marker_seen(markers_n, 0);
  for (std::size_t f = 0; f < markers.frame_count(); ++f) {
    double frame_sum = 0, frame_max = 0;
    std::size_t n = 0;
    e.distance_mm.emplace_back(markers_n, NAN);
    for (std::size_t m = 0; m < markers_n; ++m) {
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
      e.distance_mm[f][m] = std::sqrt(d2);
      marker_sum[m] += d2;
      marker_max[m] = std::max(marker_max[m], std::sqrt(d2));
      ++marker_seen[m];
    }
    e.frame_rms_mm.push_back(n ? std::sqrt(frame_sum / static_cast<double>(n)) : NAN);
    e.frame_max_mm.push_back(n ? frame_max : NAN);
    sum += frame_sum;
    count += n;
    e.max_mm = std::max(e.max_mm, frame_max);
  }
  e.rms_mm = count ? std::sqrt(sum / static_cast<double>(count)) : 0;
  for (std::size_t m = 0; m < markers_n; ++m) {
    const bool seen = marker_seen[m] > 0;
    e.marker_rms_mm.push_back(seen ? std::sqrt(marker_sum[m] / static_cast<double>(marker_seen[m]))
                                   : NAN);
    e.marker_max_mm.push_back(seen ? marker_max[m] : NAN);
  }
  for (std::size_t f = 0; f < e.frame_rms_mm.size(); ++f)
    if (!std::isnan(e.frame_rms_mm[f]) &&
        (e.worst_frame < 0 ||
         e.frame_rms_mm[f] > e.frame_rms_mm[static_cast<std::size_t>(e.worst_frame)]))
      e.worst_frame = static_cast<int>(f);
  return e;
}

void write_fit_tables(const std::string& dir, const FitResult& r, const FitOptions& o) {
  const std::filesystem::path d(dir);
  std::string act = "time";
  for (const auto& m : r.muscles) act += "," + m;
  for (const auto& k : r.jaw) act += ",jaw." + k;
  act += '\n';
  for (std::size_t j = 0; j < r.knot_times.size(); ++j) {
    act += fmt::format("{:.9g}", r.knot_times[j]);
    for (const auto& curve : r.activations) act += fmt::format(",{:.9g}", curve[j]);
    for (const auto& curve : r.jaw_values) act += fmt::format(",{:.9g}", curve[j]);
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

  // Per marker: where it is and how far the returned forward run left it from its target.
  auto cell = [](double v) { return std::isnan(v) ? std::string() : fmt::format("{:.6f}", v); };
  std::string res = "marker,vertex,x_mm,y_mm,z_mm,rms_mm,max_mm,worst_frame_mm\n";
  for (std::size_t m = 0; m < r.marker_names.size(); ++m) {
    res +=
        fmt::format("{},{},{:.3f},{:.3f},{:.3f},{},{},{}\n", r.marker_names[m],
                    r.marker_vertex[m] < 0 ? std::string() : std::to_string(r.marker_vertex[m]),
                    1e3 * r.marker_rest[m][0], 1e3 * r.marker_rest[m][1], 1e3 * r.marker_rest[m][2],
                    cell(r.marker_rms_mm[m]), cell(r.marker_max_mm[m]),
                    cell(r.worst_frame_residual_mm.empty() ? NAN : r.worst_frame_residual_mm[m]));
  }
  write_text_atomically((d / "marker_residual.csv").string(), res);

  nlohmann::json j;
  j["scene"] = o.scene_path;
  j["markers"] = o.markers_path;
  j["muscles"] = r.muscles;
  j["jaw"] = r.jaw;
  j["knot_interval_s"] = r.knot_times.size() > 1 ? r.knot_times[1] : 0.0;
  j["knots"] = r.knot_times.size();
  j["frames"] = r.frame_times.size();
  j["marker_rms_mm"] = r.rms_mm;
  j["marker_max_mm"] = r.max_mm;
  j["iteration_marker_rms_mm"] = r.iteration_rms_mm;
  j["best_iteration"] = r.best_iteration;
  if (r.worst_frame >= 0) {
    const auto f = static_cast<std::size_t>(r.worst_frame);
    j["worst_frame"] = {
        {"time_s", r.frame_times[f]}, {"rms_mm", r.frame_rms_mm[f]}, {"max_mm", r.frame_max_mm[f]}};
  }
  // The markers furthest from their targets (by RMS over their frames), largest first.
  std::vector<std::size_t> order;
  for (std::size_t m = 0; m < r.marker_names.size(); ++m)
    if (!std::isnan(r.marker_rms_mm[m])) order.push_back(m);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return r.marker_rms_mm[a] > r.marker_rms_mm[b]; });
  nlohmann::json worst = nlohmann::json::array();
  for (std::size_t i = 0; i < std::min<std::size_t>(10, order.size()); ++i) {
    const auto m = order[i];
    nlohmann::json w = {
        {"marker", r.marker_names[m]},
        {"rms_mm", r.marker_rms_mm[m]},
        {"max_mm", r.marker_max_mm[m]},
        {"rest_mm",
         {1e3 * r.marker_rest[m][0], 1e3 * r.marker_rest[m][1], 1e3 * r.marker_rest[m][2]}}};
    if (r.marker_vertex[m] >= 0) w["vertex"] = r.marker_vertex[m];
    worst.push_back(w);
  }
  j["worst_markers"] = worst;
  if (!o.targets_path.empty())
    j["targets"] = {
        {"manifest", o.targets_path}, {"surface", r.surface}, {"markers", r.marker_names.size()}};
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
