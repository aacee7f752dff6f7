#pragma once
// Triangle meshes for the voxelizer: loading any format assimp reads into one indexed triangle
// soup in metres, and a cleaning pass that welds, drops degenerate triangles and reports what the
// mesh is (holes, non-manifold edges, components, orientation) without trying to repair it.
//
// Units: every coordinate of a TriangleMesh is in metres once load_mesh has returned.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "sinew/common/math.hpp"

namespace sinew::voxelizer {

// Texture coordinates (u, v) of a triangle's three corners, in assimp's (and OBJ's) convention:
// (0, 0) at the image's bottom-left corner, v up.
using CornerUvs = std::array<std::array<double, 2>, 3>;

// An indexed triangle mesh. vertices: [n_vertices] positions (m). triangles: [n_triangles] vertex
// indices, counter-clockwise seen from outside when the mesh is consistently oriented (the
// winding number is +1 inside such a mesh). corner_uvs: empty (no texture coordinates) or one
// entry per triangle, its corners' texture coordinates in the triangle's corner order: they
// follow the triangles through cleaning and flipping, so welding positions never merges two
// different (u, v) of a texture seam. source: where it came from (a path), for messages.
struct TriangleMesh {
  std::vector<sinew::Vec3d> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<CornerUvs> corner_uvs;
  std::string source;
};

// Reverses every triangle's orientation (swaps corners 1 and 2, with their texture coordinates).
void flip_orientation(TriangleMesh& mesh);

// The corner texture coordinates of a mesh as an indexed table, as OBJ's `vt` and `f v/vt` store
// them: `uvs` holds each distinct (u, v) once (first-use order), `triangles[t][k]` is the id of
// triangle t's corner k. Both empty when the mesh has no texture coordinates.
struct IndexedUvs {
  std::vector<std::array<double, 2>> uvs;
  std::vector<std::array<std::int32_t, 3>> triangles;
};
IndexedUvs indexed_uvs(const TriangleMesh& mesh);

// Length unit of the coordinates stored in a mesh file.
enum class LengthUnit { m, cm, mm };

// Metres per unit: m -> 1, cm -> 0.01, mm -> 0.001.
double metres_per_unit(LengthUnit unit);
// "m", "cm", "mm" -> LengthUnit; throws ConfigError(file="", field=`field`) naming the value
// otherwise.
LengthUnit parse_length_unit(const std::string& name, const std::string& field = "unit");
const char* to_string(LengthUnit unit);

// How file coordinates x become model coordinates (m):
//   x_m = R * (metres_per_unit(unit) * scale * x) + translate
// with R = Rz(rotate_deg.z) * Ry(rotate_deg.y) * Rx(rotate_deg.x): XYZ Euler angles in degrees,
// extrinsic (rotate about the fixed x axis first, then y, then z), right-handed.
struct MeshTransform {
  LengthUnit unit = LengthUnit::m;
  double scale = 1;
  sinew::Vec3d rotate_deg{0, 0, 0};  // XYZ Euler (degrees), applied after unit and scale
  sinew::Vec3d translate{0, 0, 0};   // metres, applied last
};

// The rotation matrix R of a MeshTransform (see above).
sinew::Mat3d rotation_matrix(const sinew::Vec3d& rotate_deg);
// Applies t to one point given in file units; returns metres.
sinew::Vec3d apply_transform(const MeshTransform& t, const sinew::Vec3d& x);
// Applies t to every vertex of mesh in place (file units -> metres).
void apply_transform(const MeshTransform& t, TriangleMesh& mesh);

// Loads any mesh format assimp reads (OBJ, PLY, STL, FBX, glTF/GLB, DAE, ...). All meshes of the
// scene are merged, each with its node transforms (the whole node chain) applied; polygons are
// triangulated; point and line primitives are ignored. Vertices with identical positions inside
// one assimp mesh are joined (formats like STL store each triangle's corners separately); further
// welding is clean_mesh's job. Texture coordinates (assimp's channel 0) become corner_uvs when
// every part of the file has them (otherwise none are kept, logged). Then t is applied: the
// result is in metres. Unit metadata inside a file (COLLADA <unit>, FBX UnitScaleFactor) is
// applied by assimp as part of the node transforms; t.unit says what the resulting numbers are in.
// assimp runs in the helper process sinew-mesh-import (mesh_isolation.hpp), after the checks of
// mesh_import.hpp (PLY, OFF and STL headers; NaN and infinity in ASCII PLY, OFF and STL).
// Throws IoError (missing/unreadable file; the helper cannot be started), FormatError (assimp
// cannot parse it: unknown format or broken file, with assimp's message; a header that does not
// fit the file; assimp crashed on it or ran past its deadline), GeometryError (no triangles; NaN
// or infinite coordinates, naming the vertex index or the line).
TriangleMesh load_mesh(const std::filesystem::path& path, const MeshTransform& t = {});

// Writes mesh with assimp's exporter; the format follows the extension: obj, ply (binary), stl
// (binary), glb, gltf (glTF 2), dae, fbx (ASCII FBX: assimp 5.2 cannot re-read its own binary
// FBX), and any other assimp export id. Coordinates are written as they are (metres), as floats.
// Throws IoError on failure.
void save_mesh(const TriangleMesh& mesh, const std::filesystem::path& path);

// Axis-aligned bounding box of the vertices (m); lo > hi componentwise for an empty mesh.
struct BoundingBox {
  sinew::Vec3d lo, hi;
};
BoundingBox bounding_box(const TriangleMesh& mesh);

// What clean_mesh found and did. Counts after cleaning unless named "...removed/merged".
struct MeshDiagnostics {
  std::int64_t vertices = 0;                   // after welding and dropping unreferenced vertices
  std::int64_t triangles = 0;                  // after dropping degenerate and duplicate triangles
  std::int64_t duplicate_vertices_merged = 0;  // vertices welded into an earlier one
  std::int64_t degenerate_triangles_removed = 0;  // repeated corner after welding, or zero area
  std::int64_t boundary_edges = 0;                // edges used by exactly one triangle (hole rims)
  std::int64_t non_manifold_edges = 0;            // edges used by three or more triangles
  std::int64_t components = 0;  // connected components (triangles sharing a vertex are connected)
  std::int64_t inconsistently_oriented_edges = 0;  // edges of two triangles traversed the same way
  bool closed = false;                             // no boundary and no non-manifold edges
  double area = 0;                                 // total area (m^2)
  // Signed enclosed volume (m^3), sum over triangles of det(v0, v1, v2) / 6 (divergence theorem);
  // positive for an outward-oriented closed mesh; meaningful only when closed.
  double enclosed_volume = 0;
  // Added: exact repeats of an earlier triangle (same corners, same cyclic order), removed since
  // they would count twice in the winding number.
  std::int64_t duplicate_triangles_removed = 0;
  std::int64_t unreferenced_vertices_removed = 0;  // added: vertices no triangle uses
};

// Cleans mesh in place and describes it:
// 1. welds vertices closer than weld_tolerance (m; 0 = exactly equal positions only) into the
//    first such vertex in index order (deterministic);
// 2. drops degenerate triangles: a repeated corner after welding, or zero area
//    (|(v1 - v0) x (v2 - v0)| <= 1e-14 * longest edge^2, i.e. collinear to rounding);
// 3. drops exact duplicate triangles (same corners in the same cyclic order) and unreferenced
//    vertices (kept vertices keep their relative order);
// 4. counts boundary, non-manifold and inconsistently oriented edges, components, area, volume.
// Holes, non-manifold edges and mixed orientation are reported, not repaired: the winding number
// copes with them. Throws GeometryError if weld_tolerance is negative or NaN.
MeshDiagnostics clean_mesh(TriangleMesh& mesh, double weld_tolerance);

// Throws GeometryError ("triangles": "vertex index out of range", at the first such triangle)
// unless every corner of every triangle names a vertex of the mesh.
void check_triangle_indices(const TriangleMesh& mesh);

// Diagnostics of a mesh as it is (no welding, nothing removed).
MeshDiagnostics describe_mesh(const TriangleMesh& mesh);

}  // namespace sinew::voxelizer
