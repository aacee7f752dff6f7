#pragma once
// A spec's mesh source (a file, a primitive or a generated mesh: spec.hpp's MeshSource) loaded as a
// triangle mesh in metres. Used by the pipeline (voxelize.cpp) and the rig (rig.cpp), which both
// read the skin and the skull; kept apart from both so that neither includes the other.
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/spec.hpp"

namespace sinew::voxelizer {

// Loads one mesh source in metres (its transform applied), without cleaning; the mesh's `source`
// names it for messages. Throws what load_mesh throws for a file.
TriangleMesh load_mesh_source(const MeshSource& source);

}  // namespace sinew::voxelizer
