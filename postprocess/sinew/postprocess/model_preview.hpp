#pragma once
// A preview of a model file before simulating (docs/visual-output.md, "Preview of a model"):
// `sinew-render MODEL.h5 -o preview.png` draws the muscles and their fibre streamlines under a
// translucent skin, so that a muscle placed too deep, too shallow or with fibres the wrong way is
// seen before any run.
//  - skin: a visual surface of the model at rest (by name, default the first), or the boundary of
//    the elements when the model has none;
//  - muscles: per muscle, the boundary faces of its elements whose muscle fraction is at least
//    `min_fraction` (voxel faces, m), drawn opaque in muscle red;
//  - fibre streamlines: from seeds every `seed_spacing` muscle elements (in lattice steps along each
//    axis), traced both ways through the element-wise fibre field by midpoint (RK2) steps of h/2,
//    the field's sign aligned with the step before (fibres are directions), while inside the
//    muscle's elements (any fraction) and for at most 4 × the grid's largest dimension steps;
//  - the skin drawn over them with opacity `skin_opacity`: out = α · skin + (1 − α) · inside where
//    the skin covers a pixel.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/postprocess/image.hpp"
#include "sinew/postprocess/rasterizer.hpp"

namespace sinew::postprocess {

struct PreviewMesh {
  std::string name;
  std::vector<float> positions;         // V × 3, m
  std::vector<std::int32_t> triangles;  // T × 3
};

struct Streamline {
  std::size_t muscle = 0;     // index into the model's muscles
  std::vector<Point> points;  // m, along the fibre
};

struct ModelPreview {
  PreviewMesh skin;
  std::vector<PreviewMesh> muscles;  // one per model muscle (possibly empty)
  std::vector<Streamline> streamlines;
};

// Whether `path` is a sinew model file (an HDF5 file whose format attribute says so). Never throws.
bool is_model_file(const std::string& path);

// skin: a visual surface's name ("": the first; throws ConfigError (field "--surface") naming the
// known ones when absent). seed_spacing ≥ 1; min_fraction in (0, 1].
ModelPreview make_model_preview(const formats::Model& model, const std::string& skin = "",
                                int seed_spacing = 3, double min_fraction = 0.25);

struct PreviewSettings : ViewSettings {
  PreviewSettings() { view = View::front; }
  double skin_opacity = 0.35;  // in [0, 1]
  bool fibres = true;
};

inline constexpr Rgb kMuscleColor{178, 52, 44};
inline constexpr Rgb kFibreColor{255, 236, 140};

Image render_model_preview(const ModelPreview& preview, const PreviewSettings& settings);

}  // namespace sinew::postprocess
