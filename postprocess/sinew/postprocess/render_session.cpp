#include "sinew/postprocess/render_session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace sinew::postprocess {

FrameRenderer::FrameRenderer(const SurfaceAnimation& a, const FrameRenderSettings& s)
    : animation_(a), settings_(s) {
  float lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<float>::max();
    hi[k] = std::numeric_limits<float>::lowest();
  }
  for (const auto& frame : a.frames) {
    for (std::size_t i = 0; i + 2 < frame.size(); i += 3) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], frame[i + k]);
        hi[k] = std::max(hi[k], frame[i + k]);
      }
    }
  }
  std::vector<float> corners;
  for (int c = 0; c < 8; ++c) {
    corners.push_back(c & 1 ? hi[0] : lo[0]);
    corners.push_back(c & 2 ? hi[1] : lo[1]);
    corners.push_back(c & 4 ? hi[2] : lo[2]);
  }
  const int strip = s.color_displacement ? color_bar_strip_width(s.width) : 0;
  camera_ =
      aim_camera(frame_view(corners, s.view, static_cast<double>(s.width - strip) / s.height, s.up),
                 s.target, s.zoom);
  if (s.color_displacement) max_displacement_ = postprocess::max_displacement(a);
}

Image FrameRenderer::render(std::size_t frame) const {
  RenderOptions o;
  o.width = settings_.width;
  o.height = settings_.height;
  o.camera = camera_;
  ScalarColoring coloring;
  if (settings_.color_displacement) {
    coloring.values = displacement_magnitude(animation_, frame);
    coloring.min = 0.0f;
    // A still animation would give an empty range: keep the map's bottom colour then.
    coloring.max = max_displacement_ > 0 ? max_displacement_ : 1e-3f;
    coloring.map = settings_.map;
    coloring.label = "|u| mm";
    coloring.label_scale = 1000.0;
    o.coloring = &coloring;
  }
  if (settings_.caption) o.caption = frame_label(animation_, frame);
  Image image = postprocess::render(animation_.frames.at(frame), animation_.triangles, o);
  if (!settings_.crop) return image;
  const auto& c = *settings_.crop;
  return crop(image, c[0], c[1], c[2], c[3]);
}

std::string frame_label(const SurfaceAnimation& a, std::size_t frame) {
  return fmt::format("frame {}  t={:.4g} s", frame, a.times.at(frame));
}

std::vector<std::size_t> spread_frames(std::size_t frames, std::size_t count) {
  std::vector<std::size_t> out;
  if (frames == 0 || count == 0) return out;
  if (count == 1) return {frames - 1};
  if (count >= frames) {
    for (std::size_t k = 0; k < frames; ++k) out.push_back(k);
    return out;
  }
  for (std::size_t i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(
        std::lround(static_cast<double>(i) * static_cast<double>(frames - 1) / (count - 1)));
    if (out.empty() || out.back() != k) out.push_back(k);
  }
  return out;
}

}  // namespace sinew::postprocess
