#pragma once
// Reading a mesh file with assimp, and the byte stream that carries what it read out of the helper
// process `sinew-mesh-import` (mesh_isolation.hpp says why the import runs in a process of its
// own: assimp 5.2 crashes, aborts or loops on some broken files).
//
// This is the child's side: import_with_assimp() runs in the helper, never in a tool. Before
// assimp sees the file it checks what assimp trusts without checking (import_precheck): a PLY
// header that ends (assimp loops for ever on one without `end_header`, and on an ASCII body with
// fewer lines than the header declares), element counts that the file is large enough to hold.
// After assimp has read the file and before its post-processing, every coordinate must be finite:
// aiProcess_JoinIdenticalVertices merges a NaN vertex into another, silently.
//
// The mesh is in the file's units with assimp's node transforms applied; load_mesh (mesh.hpp)
// does the rest (texture-coordinate policy, finite coordinates, the spec's transform).
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sinew/common/math.hpp"

namespace sinew::voxelizer {

// What assimp read: every triangle of every assimp mesh of the scene, vertices with identical
// positions inside one assimp mesh joined. corner_uvs: one entry per triangle (its corners'
// (u, v), as mesh.hpp's CornerUvs) when every triangle has texture coordinates, else empty and
// missing_uvs counts the triangles without them.
struct ImportedMesh {
  std::vector<Vec3d> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::array<std::array<double, 2>, 3>> corner_uvs;
  std::int64_t missing_uvs = 0;
  std::int64_t parts = 0;  // assimp meshes in the scene
};

// How an import ended: a mesh, or the error load_mesh throws for it (with its field, problem and
// index; -1: none).
struct ImportOutcome {
  enum class Kind : std::uint8_t { mesh = 0, format_error = 1, geometry_error = 2, io_error = 3 };
  Kind kind = Kind::mesh;
  std::string field, problem;
  std::int64_t index = -1;
  ImportedMesh mesh;
};

// The checks made before assimp reads the file (above); nullopt when it may go to assimp. Reads
// the header of a PLY, OFF or STL file, and counts the lines of an ASCII PLY.
std::optional<ImportOutcome> import_precheck(const std::filesystem::path& file);

// import_precheck, then assimp: the file read with aiProcess_ValidateDataStructure (out-of-range
// indices refused before the triangulation trusts them), the coordinates checked, then the
// post-processing (triangulation, joined vertices). Bad content is an outcome, not an exception;
// assimp itself may still crash, which is why this runs in the helper.
ImportOutcome import_with_assimp(const std::filesystem::path& file);

// The outcome as the helper writes it to its stdout, and back. decode_outcome checks every count
// against the bytes received and throws FormatError(file, ...) on a stream that is cut short or
// malformed (a helper that died while writing).
std::string encode_outcome(const ImportOutcome& outcome);
ImportOutcome decode_outcome(std::string_view bytes, const std::string& file);

}  // namespace sinew::voxelizer
