#pragma once
// Bounded, regularised linear least squares, the solver of sinew-fit (docs/fit.md, "Method"):
//
//   minimise  ‖A x − y‖² + λ ‖D x‖² + 2μ Σ x   subject to  lower ≤ x ≤ upper
//
// where x holds K curves of J values each (curve k's values at x[k·J .. k·J + J − 1]) and D takes
// second differences along each curve, with a fixed value 0 before its first entry (the
// activations start at rest): (D x)_{k,j} = x_{k,j−1} − 2 x_{k,j} + x_{k,j+1}, j = 0 … J − 2,
// x_{k,−1} = 0. λ is given relative to the data: λ = smoothing × trace(AᵀA) / n, so the same
// smoothing suits any number of markers, frames and units; likewise μ = effort × trace(AᵀA) / n.
// The effort term (with lower = 0 the sum is the L1 norm) prefers the fewest and smallest
// activations among those that explain the data equally well: a muscle the markers hardly see
// stays at 0 instead of wandering.
//
// Method: the normal equations Q x = q (Q = AᵀA + λ DᵀD, n × n, dense) solved by projected
// Gauss–Seidel (each unknown in turn set to its unconstrained minimiser, clamped to its bounds),
// and every 25 sweeps an active-set step: the unknowns strictly inside their bounds are solved
// exactly with the others held (Cholesky, LDLᵀ), accepted when the result lies inside the bounds
// and the held ones satisfy the optimality conditions (their gradient points outwards). Q is
// positive definite when λ > 0, so Gauss–Seidel converges and the minimiser is unique.
#include <Eigen/Dense>

namespace sinew::fit {

struct BoundedSolution {
  Eigen::VectorXd x;
  int sweeps = 0;          // Gauss–Seidel sweeps done
  bool exact = false;      // the active-set step found the optimum (optimality conditions hold)
  double objective = 0;    // ‖A x − y‖² + λ ‖D x‖² + 2μ Σ x
  double misfit = 0;       // ‖A x − y‖²
  double lambda = 0;       // λ used
  double mu = 0;           // μ used
};

struct BoundedOptions {
  double smoothing = 1e-3;  // λ relative to trace(AᵀA) / n; > 0
  double effort = 0;        // μ relative to trace(AᵀA) / n; ≥ 0
  // The unknowns the effort term weighs (1) and leaves out (0), e.g. a jaw's shift, which may
  // be negative; empty: all of them (the term is then 2μ Σ w_i x_i).
  Eigen::VectorXd effort_weights;
  int max_sweeps = 20000;
  double tolerance = 1e-10;  // on the largest change of an unknown in a sweep
};

// The penalty matrix DᵀD for K curves of J values (block diagonal, n = K·J).
Eigen::MatrixXd second_difference_penalty(int curves, int values);

// Solves the problem above. A: rows × n with n = curves × values; y: rows; lower, upper: n, with
// lower ≤ upper; start: n (clamped to the bounds) or empty for the bounds' lower values. Throws
// ConfigError on inconsistent sizes or a smoothing ≤ 0.
BoundedSolution solve_bounded_least_squares(const Eigen::MatrixXd& a, const Eigen::VectorXd& y,
                                            int curves, int values, const Eigen::VectorXd& lower,
                                            const Eigen::VectorXd& upper,
                                            const Eigen::VectorXd& start,
                                            const BoundedOptions& options = {});

// The same on the normal equations (Q, q) directly: minimise ½ xᵀQx − qᵀx on the box.
BoundedSolution solve_box_qp(const Eigen::MatrixXd& q_matrix, const Eigen::VectorXd& q,
                             const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                             const Eigen::VectorXd& start, int max_sweeps, double tolerance);

}  // namespace sinew::fit
