#pragma once
// glTF 2.0 binary (.glb) of a surface animation, for Blender (File > Import > glTF 2.0) and
// three.js (GLTFLoader).
//
// Content: one mesh (triangles, base POSITION = the rest pose) with one morph target per results
// frame (target k's POSITION = frame k − rest, m), a node using it, and one animation
// "simulation" whose sampler drives the node's morph weights: at frame k's time (s, scene time ×
// time_scale) the weights are e_k (1 for target k, 0 for the others), with interpolation STEP
// (the frames shown as stored) or LINEAR (x between frames k and k + 1 interpolated linearly).
// Blender imports the targets as shape keys with their values animated; three.js as
// morphTargetInfluences driven by an AnimationClip.
//
// Layout (glTF 2.0 §4.4 GLB): 12-byte header (magic "glTF", version 2, total length), a JSON
// chunk padded with spaces to 4 bytes, a BIN chunk padded with zeros to 4 bytes. Every
// bufferView starts at a multiple of 4 bytes; POSITION accessors carry min and max (required by
// the specification), as does the animation's input accessor. Indices are UNSIGNED_INT.
// glTF is +Y up, metres: with up = z the coordinates are turned (x, y, z) → (x, z, −y).
#include <string>

#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/postprocess/results_reader.hpp"

namespace sinew::postprocess {

struct GltfOptions {
  UpAxis up = UpAxis::y;    // the results' up axis
  double time_scale = 1.0;  // animation time = scene time × time_scale (slow motion > 1)
  bool linear = false;      // LINEAR instead of STEP weights interpolation
};

// Writes the .glb; throws IoError when the file cannot be written, ConfigError on a
// non-positive time_scale.
void write_glb(const std::string& path, const SurfaceAnimation& animation,
               const GltfOptions& options = {});

}  // namespace sinew::postprocess
