#pragma once
// The linear response model of sinew-fit (docs/fit.md, "Method"): the marker displacements as a
// linear function of the activations at the knots.
//
// Activations are piecewise linear in time with knots t_j = j·τ (j = 0 … J), 0 at t_0 = 0 (the
// face starts at rest) and held after t_J. A response run drives one muscle k alone with
// g(t) = a0·clamp(t/τr, 0, 1) (τr: the response ramp, independent of the knots) and records
// every marker's displacement G_{k,m}(t). By superposition the response to the unit ramp
// r(t) = max(t, 0) is R(t) = (τr/a0) Σ_{i≥0} G(t − i·τr), and the hat function of knot j,
// (r(t − t_{j−1}) − 2 r(t − t_j) + r(t − t_{j+1})) / τ (the last knot's:
// (r(t − t_{J−1}) − r(t − t_J)) / τ), moves marker m by the same combination of R, so
//   u_m(t) ≈ Σ_k Σ_j c_{k,j} hat-response_{k,j,m}(t).
#include <array>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "sinew/fit/markers.hpp"

namespace sinew::fit {

// One displacement probe's CSV (output/probes.hpp: time,step,ux,uy,uz; m).
struct ProbePath {
  std::vector<double> times;
  std::vector<std::array<double, 3>> u;
  // u at t, linear between rows; 0 at t ≤ 0 (the run starts at rest), the last row after it.
  std::array<double, 3> at(double t) const;
};

// Reads probe_<name>.csv; FormatError naming the file and line when it is not one.
ProbePath read_probe_path(const std::string& path);

// The knots: t_j = j·interval, j = 1 … count are the unknowns (t_0 = 0 is held at 0).
struct Knots {
  double interval = 0;
  int count = 0;
  double time(int j) const { return j * interval; }
};

// One observation row: frame f, marker m, component d.
struct Observation {
  int frame = 0, marker = 0, component = 0;
};

// Every seen (frame, marker, component) of the markers, in that order.
std::vector<Observation> observations(const Markers& markers);

// The design matrix, rows × (K · J): responses[k][m] is muscle k's response run at marker m,
// driven to a0 over `ramp` s; values in mm per unit of activation.
Eigen::MatrixXd design_matrix(const std::vector<std::vector<ProbePath>>& responses, double a0,
                              double ramp, const Knots& knots, const std::vector<double>& times,
                              const std::vector<Observation>& rows);

}  // namespace sinew::fit
