// The solver of sinew-fit (fit/sinew/fit/bounded_least_squares.hpp) on synthetic linear systems
// with known answers: inside the bounds it recovers the generating values; with bounds active its
// answer satisfies the optimality conditions and beats every feasible perturbation.
#include <gtest/gtest.h>

#include <random>

#include "sinew/common/error.hpp"
#include "sinew/fit/bounded_least_squares.hpp"

namespace sinew::fit {
namespace {

// A random well-posed system: rows × (curves · values) with columns of mixed scale.
Eigen::MatrixXd random_matrix(int rows, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixXd a(rows, n);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < n; ++j) a(i, j) = g(rng) * (1 + j % 3);
  return a;
}

TEST(BoundedLeastSquares, RecoversSmoothCurvesInsideTheBounds) {
  const int curves = 3, values = 12, n = curves * values;
  Eigen::VectorXd truth(n);
  for (int k = 0; k < curves; ++k)
    for (int j = 0; j < values; ++j)
      truth[k * values + j] = 0.2 + 0.1 * k + 0.3 * std::sin(0.2 * (j + 1) + k);
  const Eigen::MatrixXd a = random_matrix(200, n, 1);
  const Eigen::VectorXd y = a * truth;
  BoundedOptions o;
  o.smoothing = 1e-9;
  const auto s = solve_bounded_least_squares(a, y, curves, values, Eigen::VectorXd::Zero(n),
                                             Eigen::VectorXd::Ones(n), {}, o);
  EXPECT_TRUE(s.exact);
  EXPECT_LT((s.x - truth).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(BoundedLeastSquares, ActiveBoundsMeetTheOptimalityConditions) {
  const int curves = 2, values = 10, n = curves * values;
  Eigen::VectorXd truth(n);
  for (int i = 0; i < n; ++i) truth[i] = 1.4 * std::sin(0.7 * i);  // outside [0, 1] in places
  const Eigen::MatrixXd a = random_matrix(80, n, 2);
  const Eigen::VectorXd y = a * truth;
  BoundedOptions o;
  o.smoothing = 1e-3;
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(n), upper = Eigen::VectorXd::Ones(n);
  const auto s = solve_bounded_least_squares(a, y, curves, values, lower, upper, {}, o);
  EXPECT_TRUE(s.exact);
  int at_bounds = 0;
  for (int i = 0; i < n; ++i) {
    EXPECT_GE(s.x[i], 0.0);
    EXPECT_LE(s.x[i], 1.0);
    at_bounds += s.x[i] == 0.0 || s.x[i] == 1.0;
  }
  EXPECT_GT(at_bounds, 0);
  // No feasible step along a coordinate lowers the objective.
  const Eigen::MatrixXd p = second_difference_penalty(curves, values);
  auto objective = [&](const Eigen::VectorXd& x) {
    return (a * x - y).squaredNorm() + s.lambda * x.dot(p * x);
  };
  EXPECT_NEAR(objective(s.x), s.objective, 1e-9 * s.objective);
  for (int i = 0; i < n; ++i)
    for (const double step : {-1e-4, 1e-4}) {
      Eigen::VectorXd x = s.x;
      x[i] = std::clamp(x[i] + step, 0.0, 1.0);
      EXPECT_GE(objective(x), s.objective - 1e-9 * s.objective) << i;
    }
}

TEST(BoundedLeastSquares, SmoothingFollowsASmoothCurveThroughNoise) {
  // One curve observed directly with noise: the regulariser brings it closer to the truth.
  const int values = 60;
  Eigen::VectorXd truth(values);
  for (int j = 0; j < values; ++j) truth[j] = 0.5 * (1 - std::cos(3.14159 * (j + 1) / values));
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0, 0.05);
  Eigen::VectorXd y = truth;
  for (int j = 0; j < values; ++j) y[j] += g(rng);
  const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(values, values);
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(values), upper = Eigen::VectorXd::Ones(values);
  BoundedOptions rough, smooth;
  rough.smoothing = 1e-8;
  smooth.smoothing = 3;
  const auto r = solve_bounded_least_squares(a, y, 1, values, lower, upper, {}, rough);
  const auto s = solve_bounded_least_squares(a, y, 1, values, lower, upper, {}, smooth);
  EXPECT_LT((s.x - truth).norm(), 0.6 * (r.x - truth).norm());
}

TEST(BoundedLeastSquares, PenaltyIsTheSecondDifferenceFromRest) {
  const Eigen::MatrixXd p = second_difference_penalty(1, 4);
  // A straight line from 0 (x_{-1} = 0) costs nothing; a constant costs its start.
  Eigen::VectorXd line(4), constant(4);
  line << 1, 2, 3, 4;
  constant << 1, 1, 1, 1;
  EXPECT_NEAR(line.dot(p * line), 0, 1e-12);
  EXPECT_NEAR(constant.dot(p * constant), 1, 1e-12);  // (0 − 2 + 1)² = 1, then zeros
}

TEST(BoundedLeastSquares, InconsistentSizesAreTypedErrors) {
  const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(4, 4);
  const Eigen::VectorXd y = Eigen::VectorXd::Ones(3);
  EXPECT_THROW(solve_bounded_least_squares(a, y, 2, 2, Eigen::VectorXd::Zero(4),
                                           Eigen::VectorXd::Ones(4), {}),
               ConfigError);
  BoundedOptions o;
  o.smoothing = 0;
  EXPECT_THROW(solve_bounded_least_squares(a, Eigen::VectorXd::Ones(4), 2, 2,
                                           Eigen::VectorXd::Zero(4), Eigen::VectorXd::Ones(4), {},
                                           o),
               ConfigError);
}

}  // namespace
}  // namespace sinew::fit
