#pragma once
// Mesh files are read in a process of their own, so that a file that crashes, aborts or hangs the
// reader ends in an error naming the file instead of taking the tool down.
//
// Why: assimp 5.2.5 segfaults, hits a bus error or fails an assertion (TriangulateProcess.cpp) on
// some damaged PLY, OFF and glTF files, and loops for ever on others (issue 33: 51 of 460 broken
// meshes crashed sinew-voxelize). aiProcess_ValidateDataStructure and the prechecks of
// mesh_import.hpp turn most of those into errors; the rest cannot be caught in-process.
//
// How: posix_spawn of the helper executable `sinew-mesh-import FILE`, which runs
// import_with_assimp and writes the outcome to a pipe (mesh_import.hpp's stream); the parent
// reads it with a deadline, then waits for the child. A child killed by a signal, one that exits
// without a whole outcome, or one still running at the deadline (then killed) is a FormatError
// naming the file ("assimp crashed reading it (signal 11: Segmentation fault)").
//
// Why posix_spawn and not fork(): the voxelizer runs OpenMP and TBB (OpenVDB) thread pools, and
// its loader is a library function that any thread may call after those pools exist. A forked
// child of a multi-threaded process inherits locks held by threads that do not exist in it (the
// allocator's, the OpenMP runtime's, the logger's) and may only call async-signal-safe functions,
// which an assimp import is not; posix_spawn starts a fresh program (glibc: clone + exec, no copy
// of the parent's memory), safe whatever threads run. The helper also starts with a clean address
// space: a 2 GB file of zeros named .ply never touches the tool's memory.
//
// Cost: the spawn, the helper's start (it links assimp only) and the copy through the pipe: the
// Lee Perry-Smith head scan (558 KB OBJ) loads in 96-101 ms instead of 94 (docs/voxelizer.md).
#include <filesystem>
#include <string>

#include "sinew/voxelizer/mesh_import.hpp"

namespace sinew::voxelizer {

struct MeshImportOptions {
  // The helper; empty: find_mesh_import_helper().
  std::filesystem::path helper;
  // Seconds before the import is stopped; 0: the default, SINEW_MESH_IMPORT_TIMEOUT if set, else
  // 30 s + 1 s per MiB of the file (assimp reads over 10 MB per second; a hang is the point).
  double timeout_seconds = 0;
};

// Where the helper is: $SINEW_MESH_IMPORT if set, else `sinew-mesh-import` next to the running
// executable (the tools), else the build tree's (tests). Throws IoError naming the places tried.
std::filesystem::path find_mesh_import_helper();

// Reads `file` in the helper process. Throws what load_mesh documents: IoError (the helper cannot
// be started; an unreadable file), FormatError (assimp refuses it, crashes, or runs past the
// deadline), GeometryError (a NaN or infinite number the precheck found).
ImportedMesh import_mesh_isolated(const std::filesystem::path& file,
                                  const MeshImportOptions& options = {});

}  // namespace sinew::voxelizer
