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

Eigen::MatrixXd design_matrix(const std::vector<std::vector<ProbePath>>& responses, double a0,
                              const Knots& knots, const std::vector<double>& times,
                              const std::vector<Observation>& rows) {
  const int K = static_cast<int>(responses.size());
  const int J = knots.count;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()),
                                            static_cast<Eigen::Index>(K) * J);
  const double scale = 1e3 / a0;  // m per a0 → mm per unit activation
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto& o = rows[r];
    const double t = times[static_cast<std::size_t>(o.frame)];
    for (int k = 0; k < K; ++k) {
      const ProbePath& g = responses[static_cast<std::size_t>(k)][static_cast<std::size_t>(o.marker)];
      for (int j = 1; j <= J; ++j) {
        const double before = t - knots.time(j - 1);
        if (before <= 0) break;  // knot j and later start after t
        double v = g.at(before)[o.component];
        if (j < J) v -= g.at(t - knots.time(j))[o.component];
        a(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k) * J + (j - 1)) = scale * v;
      }
    }
  }
  return a;
}

}  // namespace sinew::fit
