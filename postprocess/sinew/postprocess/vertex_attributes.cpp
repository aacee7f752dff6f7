#include "sinew/postprocess/vertex_attributes.hpp"

#include <algorithm>
#include <cmath>
#include <map>

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
  if (text == "von_mises") return VertexScalar::von_mises;
  throw ConfigError("", field, "expected none, displacement or von_mises, got \"" + text + "\"");
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

std::vector<float> peak_over_frames(const std::vector<std::vector<float>>& frames) {
  std::vector<float> peak(frames.empty() ? 0 : frames.front().size(), 0.0f);
  for (const auto& f : frames)
    for (std::size_t i = 0; i < peak.size(); ++i) peak[i] = std::max(peak[i], f[i]);
  return peak;
}

const char* gltf_attribute_name(VertexScalar scalar) {
  return scalar == VertexScalar::von_mises ? "_VON_MISES" : "_DISPLACEMENT";
}

const char* unit_of(VertexScalar scalar) {
  return scalar == VertexScalar::von_mises ? "Pa" : "m";
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

SeamSplit split_at_seams(const SurfaceAnimation& a) {
  SeamSplit out;
  if (!a.has_uvs()) {
    out.vertex.resize(a.vertex_count());
    for (std::size_t i = 0; i < out.vertex.size(); ++i)
      out.vertex[i] = static_cast<std::int32_t>(i);
    out.triangles = a.triangles;
    return out;
  }
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> id;
  out.triangles.reserve(a.triangles.size());
  for (std::size_t c = 0; c < a.triangles.size(); ++c) {
    const std::pair<std::int32_t, std::int32_t> key{a.triangles[c], a.uv_triangles[c]};
    const auto [at, added] = id.emplace(key, static_cast<std::int32_t>(out.vertex.size()));
    if (added) {
      out.vertex.push_back(key.first);
      out.uv.push_back(key.second);
    }
    out.triangles.push_back(at->second);
  }
  return out;
}

std::vector<float> gather_rows(const std::vector<float>& values, std::size_t width,
                               const std::vector<std::int32_t>& rows) {
  std::vector<float> out;
  out.reserve(rows.size() * width);
  for (const auto r : rows) {
    const auto* row = values.data() + static_cast<std::size_t>(r) * width;
    out.insert(out.end(), row, row + width);
  }
  return out;
}

}  // namespace sinew::postprocess
