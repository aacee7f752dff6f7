#pragma once
// Measures wrinkles on a visual surface (docs/wrinkles.md): along vertical profiles of the skin,
// the displacement against the rest shape is split into a smooth global part and a short-wave
// remainder; the remainder's folds are counted and their wavelength and depth measured, next to
// the compressive strain of the smooth part. Pure analysis: positions in, numbers out.
//
// Axes and profiles. `up` is the axis along which the skin's height is measured (its outward
// direction: z for the forehead specs, whose brow-to-hairline direction is y); `across` is the
// axis along which the profiles are spaced; the third axis, `along`, is the direction each profile
// runs in. Profile k (k = 0 .. P−1) is the curve on the rest surface where the across coordinate
// is c_k = a0 + (k + 1)(a1 − a0)/(P + 1), [a0, a1] the across extent of the candidate triangles:
// those whose rest normal n (unit, from the triangle's winding) has n·e_up ≥ min_facing and, with
// a region, whose sample points lie in it. Where several candidates lie over a point (a closed
// surface), the one with the largest rest height is used: the sheet seen from +up.
//
// Sampling. Points are placed on the line across = c_k every `spacing` in the along coordinate;
// each gets its triangle's barycentric coordinates in the rest projection, which give its rest
// position X_j, its deformed position x_j (the same material point) and the deformed normal
// (area-weighted vertex normals, interpolated). The longest run of consecutive valid points is the
// profile. s_j = the rest arc length along it, m: the arc length of the rest curve smoothed by the
// fit below (made in the along coordinate), so that a voxel staircase (the volume's boundary,
// `--surface volume`) gets the length of the surface it approximates, not that of its risers.
//
// Detrending (the smooth global motion). u_j = x_j − X_j. A local quadratic fit with Gaussian
// weights w = exp(−(s − s_j)²/(2σ²)) (|s − s_j| ≤ 4σ; σ = detrend_width) gives the smooth part
// ū_j (and likewise X̄_j, x̄_j = X̄_j + ū_j, n̄_j from the deformed normals, renormalised). The
// wrinkle signal is the normal part of the remainder:
//     r_j = (u_j − ū_j) · n̄_j      (m; positive outward, a trough is a valley)
// In the interior the fit acts as the 4th-order kernel K(t) = ½(3 − t²/σ²) G_σ(t), whose transfer
// function is H(k) = (1 + k²σ²/2) exp(−k²σ²/2): a wave of length λ keeps the fraction
//     retention(λ) = 1 − H(2π/λ)                       (detrend_retention)
// of its amplitude in r (0.90 at λ = 2.25σ, 0.50 at λ = 3.43σ), and a smooth motion of length Λ
// leaks 1 − H(2π/Λ) into r (≤ 0.10 for Λ ≥ 6.1σ). Quadratic trends pass exactly.
//
// Folds. A zigzag filter with hysteresis δ = min_depth walks r: a crest (trough) is confirmed once
// r has fallen (risen) by ≥ δ after it. A fold is a confirmed trough with a crest on each side
// that is a true local maximum, not a profile end. Its depth is the mean of its two drops:
//     d = ½[(r_left crest − r_trough) + (r_right crest − r_trough)]   (≥ δ)
// Fold positions: the trough's rest arc length s and its deformed arc length S along the smooth
// deformed curve, S_j = Σ_{i<j} |x̄_{i+1} − x̄_i|. Wavelength: the distances S between consecutive
// folds (mean, sample standard deviation). Spectral wavelength: the peak of the Hann-windowed
// periodogram of r (resampled uniformly in s) over wavelengths max(4·spacing, 2·edge) .. length/2
// (edge = the median rest edge length: shorter waves are not carried by the mesh), mapped to the
// deformed length by the profile's mean stretch (1 + strain).
//
// Voxel layers. With the model's lattice (voxel size h, a node's rest position o), each fold gets
// the phase of its trough's rest height within the voxel layers, φ = frac((X_up − o_up)/h), and
// the summary the phase locking R = |Σ exp(2πiφ)| / n over all n folds (Rayleigh's statistic: about
// 1/√n for phases at random, 1 when every trough sits at the same height within its layer). Where
// a sloping surface crosses the voxel layers it leaves a periodic imprint (the top elements' fill
// and material fractions repeat every h / slope along the profile) whose troughs are locked to
// the layers: R near 1 over troughs spanning several layers says "discretisation", not wrinkles.
// The imprint's period at a trough is the layer period h / |dX̄_up/ds| (the along-profile distance
// in which the smoothed rest surface rises by one voxel); folds spaced like it are suspect.
//
// Strain of the smooth motion along the profile: strain = L/L0 − 1 with L0 = Σ|X̄_{j+1} − X̄_j| and
// L = Σ|x̄_{j+1} − x̄_j| (negative = compression); strain_min = the most compressive local value
// |x̄_{j+1} − x̄_j| / |X̄_{j+1} − X̄_j| − 1 (dimensionless).
//
// Units: SI throughout (m); positions are V × 3 arrays (float, as read by results_reader).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/postprocess/results_reader.hpp"

namespace sinew::postprocess {

struct WrinkleOptions {
  int up = 2;                   // axis of the height (0 = x, 1 = y, 2 = z)
  int across = 0;               // axis along which the profiles are spaced (≠ up)
  int profiles = 9;             // P ≥ 1
  double detrend_width = 4e-3;  // σ, m (> 0)
  double min_depth = 2e-5;      // δ, m (> 0): fold threshold
  double spacing = 0;           // sample spacing along a profile, m; 0: min(edge/4, σ/10), edge =
                                // the median rest edge length
  double min_facing = 0.5;      // candidate triangles: n·e_up ≥ this (in (0, 1])
  // Optional box on the rest positions, m: samples outside are dropped.
  std::optional<std::array<double, 6>> region;  // xmin, xmax, ymin, ymax, zmin, zmax
  // Optional voxel lattice of the model, m: voxel size h > 0 and a node's rest position o.
  double voxel_size = 0;  // 0: unknown (no layer phases)
  std::array<double, 3> lattice_origin{0, 0, 0};
};

struct Fold {
  double s = 0;             // rest arc length of the trough, m
  double arc = 0;           // deformed arc length (smooth curve) of the trough, m
  double depth = 0;         // peak-to-trough depth d, m
  double residual = 0;      // r at the trough, m (≤ 0 typically)
  double height = 0;        // rest height X_up of the trough, m
  double layer_phase = 0;   // φ in [0, 1), NaN without a voxel size
  double layer_period = 0;  // h / |dX̄_up/ds| at the trough, m (inf where level, NaN without h)
};

struct WrinkleProfile {
  double across = 0;        // c_k, m
  std::size_t samples = 0;  // points in the profile (0: the line misses the surface)
  double length_rest = 0;   // L0, m
  double length = 0;        // L (smooth deformed curve), m
  std::vector<Fold> folds;
  double wavelength_mean = 0;      // m, NaN with fewer than two folds
  double wavelength_std = 0;       // m, NaN with fewer than three folds
  double spectral_wavelength = 0;  // m, NaN when r is zero
  double depth_mean = 0;           // m, NaN without folds
  double depth_max = 0;            // m, 0 without folds
  double rms = 0;                  // RMS of r, m
  double strain = 0;               // L/L0 − 1
  double strain_min = 0;           // most compressive local strain
  // Per sample (size `samples`): rest arc length s (m), deformed arc length S (m), r (m), local
  // strain of the smooth motion, rest position X (3 per sample, m).
  std::vector<double> s, arc, residual, local_strain, rest;
};

struct WrinkleSummary {
  std::size_t profiles_used = 0;  // profiles with samples
  std::size_t folds = 0;          // Σ folds
  double folds_mean = 0;          // folds per used profile
  double wavelength_mean = 0;     // over all consecutive-fold distances, m (NaN if none)
  double wavelength_std = 0;      // m (NaN with fewer than two distances)
  std::size_t wavelength_count = 0;
  double spectral_wavelength = 0;  // median (upper) of the profiles' spectral wavelengths, m
  double depth_mean = 0;           // over all folds, m (NaN if none)
  double depth_max = 0;            // m
  double rms = 0;                  // RMS of r over all samples, m
  double strain = 0;               // mean of the profiles' strain
  double strain_min = 0;           // the most compressive local strain of all profiles
  double layer_locking = 0;        // R over all folds, NaN without folds or voxel size
  double layers_spanned = 0;       // (max − min trough height) / h, NaN likewise
  double layer_period = 0;         // median of the folds' layer periods, m, NaN likewise
  // detrend_retention(λ / (1 + strain), σ), λ = wavelength_mean or else spectral_wavelength
  // (the fit works in rest arc length); NaN if neither.
  double retention = 0;
};

struct WrinkleReport {
  WrinkleOptions options;  // with spacing resolved
  double edge_length = 0;  // median rest edge length of the surface, m
  std::vector<WrinkleProfile> profiles;
  WrinkleSummary summary;
};

// Measures frame `frame` of `animation` against its rest pose. Throws ConfigError on options out
// of range (naming the option), FormatError on inconsistent arrays (naming animation.file),
// GeometryError when no profile meets the surface.
WrinkleReport measure_wrinkles(const SurfaceAnimation& animation, std::size_t frame,
                               const WrinkleOptions& options);

// The same on arrays: triangles T × 3, rest and deformed V × 3 (m). `file` names the source in
// errors ("" when built in memory).
WrinkleReport measure_wrinkles(const std::vector<std::int32_t>& triangles,
                               const std::vector<float>& rest, const std::vector<float>& deformed,
                               const WrinkleOptions& options, const std::string& file = "");

// The local quadratic fit above: for samples (t_j, v_j) with t increasing, returns the fitted
// values at every t_j; `components` values per sample (v has size n × components).
std::vector<double> local_quadratic_smooth(const std::vector<double>& t,
                                           const std::vector<double>& v, std::size_t components,
                                           double sigma);

// Fraction of a wave of length λ kept in r by the detrending of width σ: 1 − H(2π/λ).
double detrend_retention(double wavelength, double sigma);

// Parses an axis name "x", "y" or "z" into 0, 1, 2; throws ConfigError naming `field`.
int parse_axis(const std::string& name, const std::string& field);

}  // namespace sinew::postprocess
