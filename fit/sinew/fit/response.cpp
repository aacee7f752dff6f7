#include "sinew/fit/response.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>

#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"

namespace sinew::fit {

std::array<double, 3> ProbePath::at(double t) const {
  if (t <= 0 || times.empty()) return {0, 0, 0};
  if (t >= times.back()) return u.back();
  const auto it = std::upper_bound(times.begin(), times.end(), t);
  if (it == times.begin()) {
    // Before the first row (which is at t = 0 for a run from rest): from 0 at t = 0.
    const double w = times.front() > 0 ? t / times.front() : 1.0;
    return {w * u.front()[0], w * u.front()[1], w * u.front()[2]};
  }
  const auto i = static_cast<std::size_t>(it - times.begin());
  const double t0 = times[i - 1], t1 = times[i];
  const double w = t1 > t0 ? (t - t0) / (t1 - t0) : 1.0;
  std::array<double, 3> r{};
  for (int d = 0; d < 3; ++d) r[d] = (1 - w) * u[i - 1][d] + w * u[i][d];
  return r;
}

ProbePath read_probe_path(const std::string& path) {
  const std::string text = read_text_file(path, "probe file");
  ProbePath p;
  std::size_t start = 0;
  int line = 0;
  while (start < text.size()) {
    const auto nl = text.find('\n', start);
    const std::string row = text.substr(start, nl == std::string::npos ? nl : nl - start);
    start = nl == std::string::npos ? text.size() : nl + 1;
    ++line;
    if (line == 1) {
      if (row != "time,step,ux,uy,uz")
        throw FormatError(path, "line 1", "not a displacement probe (header time,step,ux,uy,uz)");
      continue;
    }
    if (row.empty()) continue;
    double v[5];
    std::size_t at = 0;
    for (int c = 0; c < 5; ++c) {
      const auto comma = row.find(',', at);
      const auto end = comma == std::string::npos ? row.size() : comma;
      const auto [ptr, ec] = std::from_chars(row.data() + at, row.data() + end, v[c]);
      if (ec != std::errc() || ptr != row.data() + end || !std::isfinite(v[c]) ||
          (c < 4 && comma == std::string::npos))
        throw FormatError(path, fmt::format("line {}", line), fmt::format("bad row '{}'", row));
      at = end + 1;
    }
    p.times.push_back(v[0]);
    p.u.push_back({v[2], v[3], v[4]});
  }
  if (p.times.empty()) throw FormatError(path, "", "no rows");
  return p;
}

std::vector<Observation> observations(const Markers& markers) {
  std::vector<Observation> rows;
  for (std::size_t f = 0; f < markers.frame_count(); ++f)
    for (std::size_t m = 0; m < markers.marker_count(); ++m)
      if (markers.seen[f][m])
        for (int d = 0; d < 3; ++d)
          rows.push_back({static_cast<int>(f), static_cast<int>(m), d});
  return rows;
}

namespace {

// The unit-ramp response R(t) of one response path on a uniform grid of step h = ramp / 8 up to
// `end`, by R(t) = (ramp/a0) G(t) + R(t − ramp), and read back linearly.
class RampResponse {
 public:
  RampResponse(const ProbePath& g, double a0, double ramp, double end)
      : h_(ramp / kSub), values_(static_cast<std::size_t>(std::ceil(end / h_)) + 2) {
    for (std::size_t i = 0; i < values_.size(); ++i) {
      const auto gi = g.at(static_cast<double>(i) * h_);
      for (int d = 0; d < 3; ++d) {
        values_[i][d] = ramp / a0 * gi[d];
        if (i >= static_cast<std::size_t>(kSub)) values_[i][d] += values_[i - kSub][d];
      }
    }
  }
  double at(double t, int d) const {
    if (t <= 0) return 0;
    const double x = t / h_;
    const auto i = std::min(static_cast<std::size_t>(x), values_.size() - 2);
    const double w = std::min(x - static_cast<double>(i), 1.0);
    return (1 - w) * values_[i][d] + w * values_[i + 1][d];
  }

 private:
  static constexpr int kSub = 8;
  double h_;
  std::vector<std::array<double, 3>> values_;
};

}  // namespace

Eigen::MatrixXd design_matrix(const std::vector<std::vector<ProbePath>>& responses, double a0,
                              double ramp, const Knots& knots, const std::vector<double>& times,
                              const std::vector<Observation>& rows) {
  const int K = static_cast<int>(responses.size());
  const int J = knots.count;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()),
                                            static_cast<Eigen::Index>(K) * J);
  double end = 0;
  for (const double t : times) end = std::max(end, t);
  std::vector<std::vector<RampResponse>> ramps(responses.size());
  for (std::size_t k = 0; k < responses.size(); ++k)
    for (const auto& g : responses[k]) ramps[k].emplace_back(g, a0, ramp, end);
  const double scale = 1e3 / knots.interval;  // m → mm, and the hat's 1/τ
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto& o = rows[r];
    const double t = times[static_cast<std::size_t>(o.frame)];
    for (int k = 0; k < K; ++k) {
      const RampResponse& R = ramps[static_cast<std::size_t>(k)][static_cast<std::size_t>(o.marker)];
      for (int j = 1; j <= J; ++j) {
        if (t <= knots.time(j - 1)) break;  // knot j and later start after t
        double v = R.at(t - knots.time(j - 1), o.component) - R.at(t - knots.time(j), o.component);
        if (j < J) v -= R.at(t - knots.time(j), o.component) - R.at(t - knots.time(j + 1), o.component);
        a(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k) * J + (j - 1)) = scale * v;
      }
    }
  }
  return a;
}

}  // namespace sinew::fit
