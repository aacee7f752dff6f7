#include "sinew/fit/bounded_least_squares.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sinew/common/error.hpp"

namespace sinew::fit {
namespace {

// The active-set step: the unknowns strictly inside (lower, upper) solved exactly with the others
// held. True (and x replaced) when the result is the optimum.
bool active_set_step(const Eigen::MatrixXd& Q, const Eigen::VectorXd& q,
                     const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                     Eigen::VectorXd& x, double tolerance) {
  const Eigen::Index n = x.size();
  std::vector<Eigen::Index> free;
  const double eps = 1e-12;
  for (Eigen::Index i = 0; i < n; ++i)
    if (x[i] > lower[i] + eps && x[i] < upper[i] - eps) free.push_back(i);
  Eigen::VectorXd candidate = x;
  if (!free.empty()) {
    const auto f = static_cast<Eigen::Index>(free.size());
    Eigen::MatrixXd qff(f, f);
    Eigen::VectorXd rhs(f);
    for (Eigen::Index a = 0; a < f; ++a) {
      rhs[a] = q[free[a]];
      for (Eigen::Index b = 0; b < f; ++b) qff(a, b) = Q(free[a], free[b]);
    }
    // rhs − Q_fb x_b: the held unknowns' share.
    Eigen::VectorXd held = x;
    for (const auto i : free) held[i] = 0;
    const Eigen::VectorXd qx = Q * held;
    for (Eigen::Index a = 0; a < f; ++a) rhs[a] -= qx[free[a]];
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(qff);
    if (ldlt.info() != Eigen::Success) return false;
    const Eigen::VectorXd xf = ldlt.solve(rhs);
    for (Eigen::Index a = 0; a < f; ++a) {
      const auto i = free[a];
      if (!std::isfinite(xf[a]) || xf[a] < lower[i] - tolerance || xf[a] > upper[i] + tolerance)
        return false;
      candidate[i] = std::clamp(xf[a], lower[i], upper[i]);
    }
  }
  // Optimality of the held ones: at the lower bound the gradient Qx − q must be ≥ 0, at the upper
  // bound ≤ 0 (to a tolerance relative to the diagonal).
  const Eigen::VectorXd g = Q * candidate - q;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double slack = 1e-8 * std::max(1.0, Q(i, i));
    if (candidate[i] <= lower[i] + eps && g[i] < -slack) return false;
    if (candidate[i] >= upper[i] - eps && g[i] > slack) return false;
  }
  x = candidate;
  return true;
}

}  // namespace

Eigen::MatrixXd second_difference_penalty(int curves, int values) {
  const Eigen::Index n = static_cast<Eigen::Index>(curves) * values;
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < curves; ++k) {
    const Eigen::Index base = static_cast<Eigen::Index>(k) * values;
    // Row j of D: x_{j−1} − 2 x_j + x_{j+1}, with x_{−1} = 0.
    for (int j = 0; j + 1 < values; ++j) {
      std::vector<std::pair<Eigen::Index, double>> row;
      if (j >= 1) row.push_back({base + j - 1, 1.0});
      row.push_back({base + j, -2.0});
      row.push_back({base + j + 1, 1.0});
      for (const auto& [a, va] : row)
        for (const auto& [b, vb] : row) p(a, b) += va * vb;
    }
  }
  return p;
}

BoundedSolution solve_box_qp(const Eigen::MatrixXd& Q, const Eigen::VectorXd& q,
                             const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                             const Eigen::VectorXd& start, int max_sweeps, double tolerance) {
  const Eigen::Index n = q.size();
  if (Q.rows() != n || Q.cols() != n || lower.size() != n || upper.size() != n ||
      (start.size() != 0 && start.size() != n))
    throw ConfigError("", "bounded least squares",
                      fmt::format("inconsistent sizes: Q {}×{}, q {}, bounds {} and {}, start {}",
                                  Q.rows(), Q.cols(), n, lower.size(), upper.size(),
                                  start.size()));
  for (Eigen::Index i = 0; i < n; ++i)
    if (!(lower[i] <= upper[i]))
      throw ConfigError("", "bounded least squares",
                        fmt::format("unknown {}: bounds [{}, {}]", i, lower[i], upper[i]));
  BoundedSolution s;
  s.x = start.size() == n ? Eigen::VectorXd(start) : Eigen::VectorXd(lower);
  for (Eigen::Index i = 0; i < n; ++i) s.x[i] = std::clamp(s.x[i], lower[i], upper[i]);
  Eigen::VectorXd g = Q * s.x - q;  // the gradient, kept up to date
  while (s.sweeps < max_sweeps) {
    double largest = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!(Q(i, i) > 0)) continue;  // an unknown nothing depends on keeps its start
      const double xi = std::clamp(s.x[i] - g[i] / Q(i, i), lower[i], upper[i]);
      const double d = xi - s.x[i];
      if (d == 0) continue;
      s.x[i] = xi;
      g.noalias() += d * Q.col(i);
      largest = std::max(largest, std::abs(d));
    }
    ++s.sweeps;
    if (s.sweeps % 25 == 0 || largest <= tolerance) {
      if (active_set_step(Q, q, lower, upper, s.x, 1e-9)) {
        s.exact = true;
        break;
      }
      g = Q * s.x - q;
    }
    if (largest <= tolerance) break;
  }
  return s;
}

BoundedSolution solve_bounded_least_squares(const Eigen::MatrixXd& a, const Eigen::VectorXd& y,
                                            int curves, int values, const Eigen::VectorXd& lower,
                                            const Eigen::VectorXd& upper,
                                            const Eigen::VectorXd& start,
                                            const BoundedOptions& options) {
  const Eigen::Index n = static_cast<Eigen::Index>(curves) * values;
  if (curves < 1 || values < 1 || a.cols() != n || a.rows() != y.size())
    throw ConfigError("", "bounded least squares",
                      fmt::format("inconsistent sizes: A {}×{}, y {}, {} curves of {} values",
                                  a.rows(), a.cols(), y.size(), curves, values));
  if (!(options.smoothing > 0) || !std::isfinite(options.smoothing))
    throw ConfigError("", "smoothing", fmt::format("must be > 0, not {}", options.smoothing));
  if (!(options.effort >= 0) || !std::isfinite(options.effort))
    throw ConfigError("", "effort", fmt::format("must be ≥ 0, not {}", options.effort));
  Eigen::MatrixXd Q = a.transpose() * a;
  const double scale = Q.trace() / static_cast<double>(n);
  const double lambda = options.smoothing * (scale > 0 ? scale : 1.0);
  const double mu = options.effort * (scale > 0 ? scale : 1.0);
  const Eigen::MatrixXd penalty = second_difference_penalty(curves, values);
  Q += lambda * penalty;
  const Eigen::VectorXd weights = options.effort_weights.size() == static_cast<Eigen::Index>(n)
                                      ? options.effort_weights
                                      : Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n));
  const Eigen::VectorXd q = a.transpose() * y - mu * weights;
  BoundedSolution s = solve_box_qp(Q, q, lower, upper, start, options.max_sweeps,
                                   options.tolerance);
  s.lambda = lambda;
  s.mu = mu;
  s.misfit = (a * s.x - y).squaredNorm();
  s.objective = s.misfit + lambda * s.x.dot(penalty * s.x) + 2 * mu * weights.dot(s.x);
  return s;
}

}  // namespace sinew::fit
