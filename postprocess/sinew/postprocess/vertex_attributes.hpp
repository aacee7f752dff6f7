#pragma once
// Per-vertex attributes the exports add to a surface's positions: smooth normals for shading and
// a displacement colour for artists (glTF NORMAL / COLOR_0 / _DISPLACEMENT, OBJ vn and
// "v x y z r g b").
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/postprocess/results_reader.hpp"

namespace sinew::postprocess {

// What the exports colour the vertices by: nothing, or |u| = |x − x_rest| (m).
enum class VertexScalar { none, displacement };
// Parses "none" or "displacement"; throws ConfigError naming `field`.
VertexScalar parse_vertex_scalar(const std::string& text, const std::string& field = "--color");

// Smooth vertex normals of a pose (positions V × 3, m; triangles T × 3, counter-clockwise seen
// from outside): the area-weighted average of the adjacent faces' normals, unit length. A vertex
// of no non-degenerate triangle gets `fallback` (glTF requires unit normals everywhere).
std::vector<float> smooth_normals(const std::vector<float>& positions,
                                  const std::vector<std::int32_t>& triangles,
                                  const float (&fallback)[3] = {0.0f, 0.0f, 1.0f});

// Per-vertex peak of |x_f − x_rest| over all frames, V values, m.
std::vector<float> peak_displacement(const SurfaceAnimation& animation);

// Linear RGB colours (V × 3 floats in [0, 1]) of `values` through viridis over [0, max]; max ≤ 0
// maps everything to viridis(0). Colours are linear, as glTF's COLOR_0 is: the sRGB of the colour
// map decoded with the sRGB transfer function.
std::vector<float> viridis_colors(const std::vector<float>& values, float max);

}  // namespace sinew::postprocess
