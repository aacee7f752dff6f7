#pragma once
// glTF 2.0 binary (.glb) of a surface animation, for Blender (File > Import > glTF 2.0) and
// three.js (GLTFLoader).
//
// Content: one mesh (triangles, base POSITION = the rest pose, NORMAL = its smooth normals) with
// one morph target per results frame (target k's POSITION = frame k − rest, m; NORMAL = frame k's
// smooth normal − the rest normal, so base + target is frame k's unit normal), a material, a
// node using the mesh, and one animation "simulation" whose sampler drives the node's morph
// weights: at results frame k's key time (frame_timing.hpp: k / fps by default) the weights are e_k
// (1 for target k, 0 for the others), with interpolation STEP (the frames shown as stored) or
// LINEAR (interpolated between keys). Blender imports the targets as shape keys with their values
// animated, results frame k at Blender frame n_k (= k by default); three.js as
// morphTargetInfluences driven by an AnimationClip. The animation's extras give "fps" and the
// frames n_k ("frames").
//
// With color = displacement the primitive also has COLOR_0 (VEC3 float, linear RGB: viridis of the
// vertex's peak |u| over the animation, over [0, max peak]) and "_DISPLACEMENT" (SCALAR float, the
// peak |u| in m); the material's base colour is then white so COLOR_0 shows unchanged. glTF and
// Blender's importer animate positions and normals but not colours, hence the peak. With
// color = von_mises the same with the peak von Mises stress: COLOR_0 viridis over [0, max peak]
// and "_VON_MISES" (SCALAR float, Pa); the range is in the material's extras.
//
// A surface with texture coordinates gets TEXCOORD_0 (VEC2 float, (u, 1 − v): glTF's origin is
// the image's top-left corner) and its vertices split at texture seams (vertex_attributes.hpp,
// split_at_seams): a seam vertex is one glTF vertex per (u, v), all with the same position and
// the normal of the unsplit surface, so shading stays smooth across the seam.
//
// Layout (glTF 2.0 §4.4 GLB): 12-byte header (magic "glTF", version 2, total length), a JSON
// chunk padded with spaces to 4 bytes, a BIN chunk padded with zeros to 4 bytes. Every
// bufferView starts at a multiple of 4 bytes; POSITION accessors carry min and max (required by
// the specification), as does the animation's input accessor. Indices are UNSIGNED_INT.
// glTF is +Y up, metres: with up = z the coordinates are turned (x, y, z) → (x, z, −y).
#include <string>
#include <vector>

#include "sinew/postprocess/frame_timing.hpp"
#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/postprocess/vertex_attributes.hpp"

namespace sinew::postprocess {

struct GltfOptions {
  UpAxis up = UpAxis::y;    // the results' up axis
  double fps = 0.0;         // frames per second; 0: the default of frame_timing.hpp
  double time_scale = 0.0;  // 0: one results frame per frame; > 0: animation time = scene time × S
  bool linear = false;      // LINEAR instead of STEP weights interpolation
  VertexScalar color = VertexScalar::none;  // COLOR_0 and _DISPLACEMENT / _VON_MISES
  // Per frame the V values of `color` (von_mises: element_field_at_vertices, Pa; required for it).
  // Empty with color = displacement: |u| from the animation.
  std::vector<std::vector<float>> color_values;
};

// Writes the .glb (common/atomic_file.hpp: never half-written under `path`) and returns the timing used;
// throws IoError when the file cannot be written, ConfigError on a bad fps or time scale
// (frame_timing).
FrameTiming write_glb(const std::string& path, const SurfaceAnimation& animation,
                      const GltfOptions& options = {});

}  // namespace sinew::postprocess
