#pragma once
// Blender's Point Cache 2 (.pc2) — read by the Mesh Cache modifier — and the OBJ files that go
// with it.
//
// PC2 layout (little endian):
//   char[12]  "POINTCACHE2\0"
//   int32     file version = 1
//   int32     number of points V
//   float32   start frame
//   float32   sample rate (frames between samples)
//   int32     number of samples F
//   then F × V × 3 float32: the points' x, y, z per sample, m.
// The points are the surface's vertices in their stored order, so the mesh the cache is applied
// to must have exactly that vertex order: the rest-pose OBJ written by write_obj.
//
// Timing: sample k is results frame k. Blender's Mesh Cache modifier (time mode "Frame", its
// default) shows sample (scene frame − the modifier's Frame Start, default 0) and ignores the
// header's start frame and rate, so results frame k shows at Blender frame k, as in the glTF
// export by default; the header says the same (start frame 0, one sample per frame) for readers
// that use it. Every file is written to a temporary name and renamed (common/atomic_file.hpp).
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/postprocess/results_reader.hpp"
#include "sinew/postprocess/vertex_attributes.hpp"

namespace sinew::postprocess {

inline constexpr std::size_t kPc2HeaderBytes = 32;

struct Pc2Options {
  float start_frame = 0.0f;  // the frame of results frame 0, as in the glTF export
  float sample_rate = 1.0f;  // frames between samples: one results frame per frame
};

// Writes every frame of `animation`; throws IoError when the file cannot be written.
void write_pc2(const std::string& path, const SurfaceAnimation& animation,
               const Pc2Options& options = {});

// Optional data of an OBJ: normals and colours empty or V × 3 floats; texture coordinates empty
// or Q × 2 floats (u, v; OBJ's convention, v up) with T × 3 corner ids into them.
struct ObjAttributes {
  std::vector<float> normals;  // unit normals: "vn" lines, faces "f a//a b//b c//c"
  std::vector<float> colors;   // RGB in [0, 1]: "v x y z r g b" (read by Blender 3.4's importer)
  std::vector<float> uvs;      // "vt u v" lines, faces "f a/ta b/tb c/tc" (a/ta/a with normals)
  std::vector<std::int32_t> uv_triangles;
};

// The surface's texture coordinates as OBJ attributes (both empty when it has none).
ObjAttributes texture_attributes(const SurfaceAnimation& animation);

// A Wavefront OBJ of one pose: "v x y z" per vertex (m, 9 significant digits), the attributes'
// lines, then "f a b c" per triangle (1-based; "a//a" with normals, "a/ta/a" with texture
// coordinates too); the vertex order is the surface's (texture seams are in the vt indices, not
// in split vertices). `comment` goes into a leading "# " line when not empty. Throws ConfigError
// when an attribute's size does not match, IoError when the file cannot be written.
void write_obj(const std::string& path, const std::vector<float>& positions,
               const std::vector<std::int32_t>& triangles, const std::string& comment = "",
               const ObjAttributes& attributes = {});

// One OBJ per frame into `directory` (created when missing): <prefix>_0000.obj, ... (4 digits,
// more when there are more than 10000 frames), with each frame's smooth normals
// (vertex_attributes.hpp), the surface's texture coordinates when it has them, and, with
// color = displacement, the frame's |u| through viridis over
// [0, the animation's max |u|] as vertex colours (sRGB). Returns the paths written.
// With color = von_mises, `color_values` holds each frame's V values (Pa,
// element_field_at_vertices) and the range is [0, their max over all frames].
std::vector<std::string> write_obj_sequence(
    const std::string& directory, const SurfaceAnimation& animation,
    const std::string& prefix = "frame", VertexScalar color = VertexScalar::none,
    const std::vector<std::vector<float>>& color_values = {});

}  // namespace sinew::postprocess
