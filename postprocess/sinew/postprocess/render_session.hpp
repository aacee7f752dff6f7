#pragma once
// What sinew-render does with a surface animation, as library functions the tool and the tests
// share: a fixed camera for all frames, the displacement colouring, frame captions, a frame
// selection for contact sheets.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/postprocess/results_reader.hpp"

namespace sinew::postprocess {

struct FrameRenderSettings : ViewSettings {
  bool color_displacement = false;  // colour by |x_f − x_rest| (m, bar labelled in mm)
  ColorMap map = ColorMap::viridis;
  bool caption = true;  // "frame k  t=... s" at the bottom left
};

// Renders frame `frame` of `animation` with a camera framing the bounding box of all frames
// (the same camera for every frame) and, with colour, a range [0, max displacement over all
// frames] common to every frame.
class FrameRenderer {
 public:
  FrameRenderer(const SurfaceAnimation& animation, const FrameRenderSettings& settings);
  Image render(std::size_t frame) const;
  const Camera& camera() const { return camera_; }
  float max_displacement() const { return max_displacement_; }

 private:
  const SurfaceAnimation& animation_;
  FrameRenderSettings settings_;
  Camera camera_;
  float max_displacement_ = 0.0f;
};

// A short label for a frame: "frame 12  t=0.125 s" (time with 4 significant digits).
std::string frame_label(const SurfaceAnimation& animation, std::size_t frame);

// `count` frame indices evenly spread over [0, F − 1], first and last included, no repeats
// (all frames when count ≥ F; the last frame alone when count = 1).
std::vector<std::size_t> spread_frames(std::size_t frames, std::size_t count);

}  // namespace sinew::postprocess
