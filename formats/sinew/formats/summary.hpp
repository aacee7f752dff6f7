#pragma once
// A summary of a model, for sinew-inspect and for logs: counts, bounding box, voxel size, volume
// per material and per muscle, constraints, surfaces, named sets and provenance. All volumes in m³:
// an element's share of material m is fraction_m · h³ (h the voxel size), of a muscle likewise.
#include <cstddef>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"

namespace sinew::formats {

struct ModelSummary {
  struct Part {  // one material or muscle
    std::string name;
    double volume = 0;         // m³, Σ over elements of fraction · h³
    std::size_t elements = 0;  // elements with a non-zero fraction of it
  };
  struct SurfaceInfo {
    std::string name;
    SurfaceRole role = SurfaceRole::visual;
    std::size_t vertices = 0, triangles = 0;
    std::size_t sliding_nodes = 0;  // sliding bindings onto this surface
    bool embedded = false;          // every vertex has an element and local coordinates
    std::size_t uvs = 0;            // texture coordinates (0: the surface has none)
  };
  struct SetInfo {
    std::string name;
    std::size_t size = 0;
  };

  VoxelGrid grid;
  std::size_t nodes = 0, elements = 0;
  Point bbox_min{0, 0, 0}, bbox_max{0, 0, 0};  // m, over the present nodes
  double voxel_volume = 0;                     // m³, elements · h³
  double tissue_volume = 0;                    // m³, Σ of all material fractions · h³
  std::vector<Part> materials;                 // in the order of the materials table
  std::vector<Part> muscles;                   // in the order of the muscles
  std::size_t rigid_nodes = 0, sliding_nodes = 0, jaw_nodes = 0;
  std::vector<SurfaceInfo> surfaces;
  std::vector<SetInfo> node_sets, element_sets;
  Provenance provenance;
};

// Assumes a valid model (validate_model()).
ModelSummary summarize(const Model& model);
// Human-readable, several lines, ends with a newline.
std::string summary_text(const ModelSummary& summary);
// One JSON document (docs/model-format.md, "sinew-inspect --json"), 2-space indented.
std::string summary_json(const ModelSummary& summary);

}  // namespace sinew::formats
