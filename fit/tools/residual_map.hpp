#pragma once
// sinew-fit's residual map (docs/fit.md, "Outputs"): the skin at rest seen from the front,
// coloured by the distance (mm) between each marker's target and its simulated position in the
// returned forward run at the frame of the largest marker RMS, with a colour bar in mm.
//
// The skin: the targets' visual surface, or for marker input the model's first visual surface
// (the volume's boundary when it has none), as postprocess::make_model_preview picks it. A vertex
// x within R of a marker seen in that frame gets the weighted mean of those markers' residuals d_m,
// Σ w_m d_m / Σ w_m, w_m = (1 − r_m/R)² / r_m², r_m = |x − X_m| (inverse-square weights that fade to
// 0 at R, so the map is continuous where markers' reaches meet; R = 1.5 × the median distance from a marker to its nearest
// other marker); farther vertices keep the skin's grey (no marker says anything there).
// Every marker on skin facing the camera (its nearest vertex's normal) is drawn as a disc of its
// own residual with a rim (white on the dark half of the map, dark on the light half). The
// colour map (viridis) spans 0 to the frame's largest residual; the caption gives the frame's time,
// RMS and max.
#include "sinew/fit/fit_options.hpp"
#include "sinew/postprocess/image.hpp"

namespace sinew::fit {

postprocess::Image draw_residual_map(const FitResult& result);

}  // namespace sinew::fit
