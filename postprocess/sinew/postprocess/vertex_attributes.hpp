#pragma once
// Per-vertex attributes the exports add to a surface's positions: smooth normals for shading and
// a displacement colour for artists (glTF NORMAL / COLOR_0 / _DISPLACEMENT, OBJ vn and
// "v x y z r g b").
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/postprocess/results_reader.hpp"

namespace sinew::postprocess {

// What the exports colour the vertices by: nothing, |u| = |x − x_rest| (m), or the von Mises
// stress (Pa) of the elements around the vertex (element_fields.hpp).
enum class VertexScalar { none, displacement, von_mises };
// Parses "none", "displacement" or "von_mises"; throws ConfigError naming `field`.
VertexScalar parse_vertex_scalar(const std::string& text, const std::string& field = "--color");

// Smooth vertex normals of a pose (positions V × 3, m; triangles T × 3, counter-clockwise seen
// from outside): the area-weighted average of the adjacent faces' normals, unit length. A vertex
// of no non-degenerate triangle gets `fallback` (glTF requires unit normals everywhere).
std::vector<float> smooth_normals(const std::vector<float>& positions,
                                  const std::vector<std::int32_t>& triangles,
                                  const float (&fallback)[3] = {0.0f, 0.0f, 1.0f});

// Per-vertex peak of |x_f − x_rest| over all frames, V values, m.
std::vector<float> peak_displacement(const SurfaceAnimation& animation);

// Per-vertex peak over frames of per-frame values (F entries of V values).
std::vector<float> peak_over_frames(const std::vector<std::vector<float>>& frames);

// The name of the glTF attribute that carries a scalar's raw values ("_DISPLACEMENT",
// "_VON_MISES"; application-specific names start with "_") and its unit ("m", "Pa").
const char* gltf_attribute_name(VertexScalar scalar);
const char* unit_of(VertexScalar scalar);

// glTF keeps one texture coordinate per vertex: a surface vertex whose triangle corners carry
// several (u, v) (a texture seam) becomes one output vertex per distinct (vertex, uv id) pair, in
// order of first use along the triangles. Per-vertex data (positions, normals computed on the
// unsplit surface, so shading stays smooth across a seam, colours) is copied with gather_rows.
// Without texture coordinates the split is the identity.
struct SeamSplit {
  std::vector<std::int32_t> vertex;     // per output vertex: the surface vertex it copies
  std::vector<std::int32_t> uv;         // per output vertex: its uv id (empty without UVs)
  std::vector<std::int32_t> triangles;  // T × 3 output vertex ids
};
SeamSplit split_at_seams(const SurfaceAnimation& animation);

// The rows `rows` of `values` (a row-major array of rows of `width` floats), in that order.
std::vector<float> gather_rows(const std::vector<float>& values, std::size_t width,
                               const std::vector<std::int32_t>& rows);

// Linear RGB colours (V × 3 floats in [0, 1]) of `values` through viridis over [0, max]; max ≤ 0
// maps everything to viridis(0). Colours are linear, as glTF's COLOR_0 is: the sRGB of the colour
// map decoded with the sRGB transfer function.
std::vector<float> viridis_colors(const std::vector<float>& values, float max);

}  // namespace sinew::postprocess
