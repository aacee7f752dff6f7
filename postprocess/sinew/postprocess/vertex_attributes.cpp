#include "sinew/postprocess/vertex_attributes.hpp"

#include <algorithm>
#include <cmath>

#include "sinew/common/error.hpp"
#include "sinew/postprocess/rasterizer.hpp"

namespace sinew::postprocess {
namespace {

// sRGB 8-bit → linear [0, 1] (IEC 61966-2-1).
float srgb_to_linear(std::uint8_t c) {
  const double s = c / 255.0;
  return static_cast<float>(s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4));
}

}  // namespace

VertexScalar parse_vertex_scalar(const std::string& text, const std::string& field) {
  if (text == "none") return VertexScalar::none;
  if (text == "displacement") return VertexScalar::displacement;
  throw ConfigError("", field, "expected none or displacement, got \"" + text + "\"");
}

std::vector<float> smooth_normals(const std::vector<float>& positions,
                                  const std::vector<std::int32_t>& triangles,
                                  const float (&fallback)[3]) {
  // The rasteriser's normals are the same average; only the degenerate case differs (zero there).
  auto n = vertex_normals(positions, triangles);
  for (std::size_t v = 0; v + 2 < n.size(); v += 3) {
    if (n[v] == 0.0f && n[v + 1] == 0.0f && n[v + 2] == 0.0f) {
      for (int k = 0; k < 3; ++k) n[v + static_cast<std::size_t>(k)] = fallback[k];
    }
  }
  return n;
}

std::vector<float> peak_displacement(const SurfaceAnimation& a) {
  std::vector<float> peak(a.vertex_count(), 0.0f);
  for (std::size_t f = 0; f < a.frame_count(); ++f) {
    const auto d = displacement_magnitude(a, f);
    for (std::size_t i = 0; i < peak.size(); ++i) peak[i] = std::max(peak[i], d[i]);
  }
  return peak;
}

std::vector<float> viridis_colors(const std::vector<float>& values, float max) {
  std::vector<float> out;
  out.reserve(values.size() * 3);
  for (float v : values) {
    const Rgb c = map_color(ColorMap::viridis, max > 0 ? v / max : 0.0);
    out.push_back(srgb_to_linear(c.r));
    out.push_back(srgb_to_linear(c.g));
    out.push_back(srgb_to_linear(c.b));
  }
  return out;
}

}  // namespace sinew::postprocess
