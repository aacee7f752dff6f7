#pragma once
// Reads a visual surface's animation out of a sinew results file (results.h5, written by
// ResultsWriter; layout in docs/results-format.md) for the renderers and exporters of this folder.
//
// Read: /frames/time (F64 F), /surfaces/<name>/triangles (I32 T × 3) and
// /surfaces/<name>/positions (F64 F' × V × 3, m, F' ≥ F: a frame is complete once its time is
// written, so rows past F are ignored), and when present /surfaces/<name>/uvs (F64 Q × 2) with
// /surfaces/<name>/uv_triangles (I32 T × 3). Positions are kept as float (m): the renderers and the
// glTF/PC2/OBJ files all use 32-bit floats.
//
// The rest pose is frame 0's positions: frame 0 is the engine's step 0 (t = 0), where every
// displacement is zero. A file whose first frame is not step 0 (it exists only if a writer broke
// that rule) is still read, with a warning in the log, and "displacement" then means the
// displacement from frame 0.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sinew::postprocess {

struct SurfaceAnimation {
  std::string file;                     // the results file it came from ("" when built in memory)
  std::string name;                     // the surface's name (its group under /surfaces)
  std::vector<std::int32_t> triangles;  // T × 3 vertex ids, counter-clockwise seen from outside
  std::vector<float> rest;              // V × 3, m (frame 0)
  std::vector<std::vector<float>> frames;  // F entries of V × 3, m
  std::vector<double> times;               // F frame times, s (scene time), strictly increasing
  // Texture coordinates (optional, from /surfaces/<name>/uvs and uv_triangles): Q × 2 (u, v) in
  // OBJ's convention ((0, 0) bottom-left, v up), and T × 3 ids into them, triangle t's corner k
  // at uv_triangles[3t + k]; both empty when the surface has none.
  std::vector<float> uvs;
  std::vector<std::int32_t> uv_triangles;
  // The volume's boundary only (read_volume_boundary): the mesh node of each vertex.
  std::vector<std::int32_t> volume_nodes;

  std::size_t vertex_count() const { return rest.size() / 3; }
  std::size_t triangle_count() const { return triangles.size() / 3; }
  std::size_t frame_count() const { return frames.size(); }
  bool has_uvs() const { return !uv_triangles.empty(); }
};

// Names of the visual surfaces stored in a results file (sorted). Throws FormatError when the
// file is not a sinew results file, IoError when it cannot be opened.
std::vector<std::string> list_surfaces(const std::string& path);

// Reads one surface; `name` empty picks the only surface, or the volume's boundary when the file
// has no surface (FormatError when there are several and none is named); `name` "volume" (when
// no surface has that name) reads the volume's boundary (read_volume_boundary).
// Throws FormatError on a missing dataset, a wrong shape, a triangle vertex id out of range,
// non-increasing frame times or a non-finite position, naming the file, dataset and index.
SurfaceAnimation read_surface(const std::string& path, const std::string& name = "");

// The name under which read_surface offers the volume's boundary.
inline constexpr const char* kVolumeBoundaryName = "volume";

// The boundary of the hexahedral volume as a surface animation named "volume": every element
// face (hex8/VTK order, outward: (0,3,2,1), (4,5,6,7), (0,1,5,4), (1,2,6,5), (2,3,7,6), (3,0,4,7))
// that belongs to one element only, split into two triangles; vertices are the boundary nodes
// (renumbered in increasing node id) at /mesh/rest_positions + /frames/displacement[f]. For
// results without a visual surface (e.g. the box scenes). Throws FormatError like read_surface.
SurfaceAnimation read_volume_boundary(const std::string& path);

// Checks the invariants above on an animation built in memory; throws FormatError.
void validate(const SurfaceAnimation& animation);

// Per-vertex displacement magnitude |x_f − x_rest| of frame f, V values, m.
std::vector<float> displacement_magnitude(const SurfaceAnimation& animation, std::size_t frame);

// Largest displacement magnitude over all frames and vertices, m.
float max_displacement(const SurfaceAnimation& animation);

}  // namespace sinew::postprocess
