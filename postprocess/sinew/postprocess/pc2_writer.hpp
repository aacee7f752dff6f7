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
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/postprocess/results_reader.hpp"

namespace sinew::postprocess {

inline constexpr std::size_t kPc2HeaderBytes = 32;

struct Pc2Options {
  float start_frame = 1.0f;  // Blender's default first frame
  float sample_rate = 1.0f;  // one results frame per Blender frame
};

// Writes every frame of `animation`; throws IoError when the file cannot be written.
void write_pc2(const std::string& path, const SurfaceAnimation& animation,
               const Pc2Options& options = {});

// A Wavefront OBJ of one pose: "v x y z" per vertex (m, 9 significant digits) then
// "f a b c" per triangle (1-based), no normals, no texture coordinates: the vertex order is the
// surface's. `comment` goes into a leading "# " line when not empty.
void write_obj(const std::string& path, const std::vector<float>& positions,
               const std::vector<std::int32_t>& triangles, const std::string& comment = "");

// One OBJ per frame into `directory` (created when missing): <prefix>_0000.obj, ... (4 digits,
// more when there are more than 10000 frames). Returns the paths written.
std::vector<std::string> write_obj_sequence(const std::string& directory,
                                            const SurfaceAnimation& animation,
                                            const std::string& prefix = "frame");

}  // namespace sinew::postprocess
