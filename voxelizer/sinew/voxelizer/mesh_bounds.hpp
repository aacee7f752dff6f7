#pragma once
// Bounds on what a spec's meshes may make. A damaged file can still read as a mesh: a 16 KB
// bit-rotted STL read as a 2.2 m long, inside-out soup made sinew-voxelize run 62 s and write a
// 2.1-million-element model with only a "not closed" warning (issue 33). Each check gives the
// problem in words, or nothing; the pipeline (voxelize.cpp) refuses the spec with it, naming the
// mesh, or with --force (VoxelizeOptions::force) logs it as a warning and goes on.
#include <cstdint>
#include <optional>
#include <string>

#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

// A mesh may span at most this many of the spec's `units` along any axis: 1 m in a spec in mm,
// 10 m in cm, 1 km in m. A face is about 0.2 m; a mesh a thousand units long is a file in other
// units than the spec says (give the mesh's `unit:` or `scale:`) or a damaged one.
inline constexpr double kMaxExtentInUnits = 1000;

// The default of resolution.max_elements: twenty times the paper's forehead at 0.5 mm (478,857
// elements); data/specs/lee_perry_smith_1mm.yaml expects 2.4 million (725,327 once cropped).
inline constexpr std::int64_t kDefaultMaxElements = 10'000'000;

// The mesh's largest bounding-box side (m) against kMaxExtentInUnits of `units`.
std::optional<std::string> extent_problem(const TriangleMesh& mesh, LengthUnit units);

// The elements the meshes are expected to make at voxel size h (m) against the limit: the tissue
// volume (outer minus inner enclosed volume, at most skin area × tissue_thickness) over h³ plus a
// shell of 2 × skin area / h², at most the grid (voxelize.cpp).
std::optional<std::string> element_count_problem(double expected_elements, std::int64_t limit,
                                                 double h, LengthUnit units);

// A mesh that bounds tissue (outer, inner, a muscle, tendon or region) must enclose a positive
// volume once a closed, consistently oriented mesh pointing inward has been flipped: a negative
// one is inside out in a way that cannot be repaired by flipping (mixed orientation, holes) or a
// soup of unrelated triangles, and its winding number marks the wrong side as inside.
std::optional<std::string> volume_problem(const MeshDiagnostics& d, LengthUnit units);

// "2.2 m" / "2200 mm": a length (m) in `units` with up to 4 significant digits, for messages.
std::string format_length(double metres, LengthUnit units);

}  // namespace sinew::voxelizer
