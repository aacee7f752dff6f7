#pragma once
// sinew-fit's picture (docs/fit.md, "Outputs"): the fitted activation curves, one colour per
// muscle with a legend, over the marker RMS error per frame; drawn as polylines with
// postprocess's image and 5 × 7 font.
#include "sinew/fit/fit_run.hpp"
#include "sinew/postprocess/image.hpp"

namespace sinew::fit {

postprocess::Image draw_activation_plot(const FitResult& result);

}  // namespace sinew::fit
