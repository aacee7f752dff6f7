#pragma once
// sinew-rig's pictures (docs/landmarks.md, docs/faces.md): the skin from the front with the
// landmarks numbered and listed, and the rig's muscles seen through a half-transparent skin. Drawn
// with the project's own software rasteriser (postprocess/rasterizer.hpp).
#include <string>
#include <vector>

#include "sinew/voxelizer/landmarks.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

struct PictureMuscle {
  std::string name;
  const TriangleMesh* mesh;
};

// Writes a PNG of the skin (metres) from the front (+z, y up) framed on the landmarks, each
// landmark a numbered dot, with a legend; muscles (may be empty) drawn in colours under a skin
// blended to 45% opacity.
void write_rig_picture(const std::string& path, const TriangleMesh& skin,
                       const Landmarks& landmarks, const std::vector<PictureMuscle>& muscles,
                       bool numbered_landmarks);

// Writes a PNG of the jaw (rig.jaw, jaw.hpp) from the subject's left: the skull under a
// half-transparent skin with the mandible (the skull's part in the mandible's region) in orange,
// the hinge axis end on through the pivot, the occlusal plane and the incisal point, and a legend
// with the pivot, the axis and the condyles' distance. Throws ConfigError as jaw_geometry does.
void write_jaw_picture(const std::string& path, const TriangleMesh& skin, const TriangleMesh& skull,
                       const Landmarks& landmarks);

}  // namespace sinew::voxelizer
