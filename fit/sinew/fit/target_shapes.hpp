#pragma once
// Target shapes (docs/fit.md, "Target shapes"): sculpted meshes with the exported skin's
// topology, one per key time, turned into markers on the model's nodes.
//
// The manifest, a CSV listing the key times and their meshes (paths relative to the manifest):
//
//   # comments and blank lines are skipped
//   time,mesh
//   0.05,smile_half.obj
//   0.1,smile.obj
//
// time in s of scene time, > 0 and strictly increasing. Each mesh is a Wavefront OBJ with the
// vertices and triangles of the model's visual surface in their order: sinew-export's rest OBJ
// (`--pc2 ... --rest-obj`) sculpted with its vertex order kept. Only `v` (x y z in m, as sinew-export
// writes them; extra colour values ignored) and `f` lines (1-based or negative indices, `a`,
// `a/ta`, `a//na`, `a/ta/na`) are read; other lines (vn, vt, o, g, s, usemtl, ...) are skipped.
//
// A target vertex v becomes a marker that moves as the surface's vertex does in a run: the
// trilinear interpolation of its embedding element's 8 nodes, u_v = Σ_a N_a(ξ, η, ζ) u_a,
// N_a = Π_d (1 + s_a,d ξ_d)/2 (s_a the node's natural-coordinate signs, model.hpp). The runs
// record a displacement probe on each node used ("target_n<node>"); the marker's path is that
// weighted sum, its rest position Σ N_a X_a (the vertex's), its target the sculpt's x_v. Markers
// are a subset of the vertices, chosen by farthest-point sampling on the rest surface (every
// vertex when there are fewer).
//
// Errors are FormatErrors naming the file, the line and the value: a manifest line that is not
// `time,mesh`, a time not finite, ≤ 0 or not after the previous one; a mesh of another topology
// (vertex count, face count, a face's indices differ from the model's surface), a coordinate that
// is not a finite number.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/fit/markers.hpp"
#include "sinew/fit/response.hpp"
#include "sinew/formats/model.hpp"

namespace sinew::fit {

struct TargetManifest {
  std::string file;                 // as given, for messages
  std::vector<double> times;        // s, strictly increasing, > 0
  std::vector<std::string> meshes;  // the paths, resolved against the manifest's folder
  std::vector<int> lines;           // the manifest line of each (1-based)
};

// Reads the manifest (IoError when it cannot be read, FormatError otherwise).
TargetManifest read_target_manifest(const std::string& path);
// The same from text; `file` names it in messages, `directory` resolves relative mesh paths.
TargetManifest parse_target_manifest(const std::string& text, const std::string& file,
                                     const std::string& directory);

// A triangle mesh read from an OBJ: vertices as written (the file's unit, m for sinew-export's),
// triangles as 0-based vertex ids, and the file line of each for messages.
struct ObjMesh {
  std::string file;
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<int> vertex_lines, face_lines;
};

ObjMesh read_obj_mesh(const std::string& path);
// The same from text. A face of other than three vertices, an index out of range, a coordinate
// that is not a finite number: FormatError naming the file, the line and the value.
ObjMesh parse_obj_mesh(const std::string& text, const std::string& file);

// Throws FormatError (the mesh's file, the line, the value) unless `mesh` has the surface's
// vertex count, face count and every face's vertex ids in order.
void check_target_topology(const ObjMesh& mesh, const formats::Surface& surface);

// Throws FormatError (the mesh's file, "v", both sizes and the fix) unless the target's size, the
// diagonal of its vertices' bounding box times `unit` (m per unit of the mesh), lies within a
// factor of kTargetScaleTolerance of the surface's at rest: a sculpt moves the skin by
// millimetres, a mesh in other units (mm or cm read as m; sinew-export writes m) by a factor of
// 10 to 1000, which the fit would take for a displacement of metres.
inline constexpr double kTargetScaleTolerance = 2;
void check_target_scale(const ObjMesh& mesh, const formats::Surface& surface, double unit);

// The surface vertex of each target marker and the probes that record it.
struct TargetMarkers {
  Markers markers;                     // names "target_v<vertex>", positions in m
  std::vector<std::int32_t> vertices;  // M, ids into the surface
  std::vector<formats::Point> rest;    // M, Σ N_a X_a (m)
  std::vector<formats::Index> nodes;   // P probe nodes (sorted, unique)
  std::vector<std::string> probes;     // P, "target_n<node>"
  // M: (probe index, trilinear weight) of each node of the marker's element (weights > 0).
  std::vector<std::vector<std::pair<std::size_t, double>>> weights;
};

// The trilinear weights N_a at natural coordinates `local` of the 8 nodes in hex8 order.
std::array<double, 8> trilinear_weights(const formats::Point& local);

// The markers' paths from the probes' (P paths, the same rows): Σ_a N_a u_a per row.
std::vector<ProbePath> marker_paths(const TargetMarkers& targets,
                                    const std::vector<ProbePath>& probes);

// `count` vertices of the surface spread by farthest-point sampling over the rest positions,
// seeded at `seed` (deterministic; every vertex, in order, when count ≥ the vertex count).
std::vector<std::int32_t> spread_vertices(const formats::Surface& surface, std::size_t count,
                                          std::int32_t seed);

// The markers of the targets: for each key time a frame with every chosen vertex seen. `meshes`
// are the manifest's, already checked against `surface`. `count` 0 takes every vertex; sampling
// is seeded at the vertex that moves most in any target.
TargetMarkers target_markers(const TargetManifest& manifest, const std::vector<ObjMesh>& meshes,
                             const formats::Model& model, const formats::Surface& surface,
                             std::size_t count);

}  // namespace sinew::fit
