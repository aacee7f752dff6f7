// sinew-sample-model: writes the generated sample models of the paper's Table 2 / Fig. 7 as model
// files, each with a visual surface "skin" (the volume's boundary) for sinew-render and
// sinew-export. docs/sample-models.md.
//
//   sinew-sample-model skin-block [--dims 120 120 9] [--voxel-size 0.00025] [--press-width 0] -o F
//   sinew-sample-model soft-body  [--scale 1.085] [--voxel-size 0.002] -o F
//
// Exit status: 0 written, 1 bad value or I/O error, 2 bad command line.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/benchmark_models.hpp"

namespace {

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

void check_positive(double v, const char* option) {
  if (!(v > 0)) throw sinew::ConfigError("", option, "must be > 0, got " + number(v));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Write the sample models of docs/sample-models.md as sinew model files (HDF5), each with a "
      "visual surface 'skin' (the boundary of the volume) so that sinew-render and sinew-export "
      "can draw the results. Scenes for them: data/scenes/skin_block_press.yaml and "
      "data/scenes/soft_body_gravity.yaml.",
      "sinew-sample-model"};
  app.footer(
      "Examples:\n  sinew-sample-model skin-block -o skin_block.h5\n"
      "  sinew-sample-model skin-block --dims 80 80 6 --voxel-size 0.000375 -o skin_block.h5"
      "   (the same block for a CPU: 38,400 elements)\n"
      "  sinew-sample-model soft-body -o soft_body.h5");
  app.set_version_flag("--version", std::string("sinew-sample-model ") + sinew::kVersion);
  app.require_subcommand(1);
  std::string output;
  bool quiet = false;

  auto* block = app.add_subcommand(
      "skin-block",
      "the paper's skin block (Table 2): nx x ny x nz voxels (default 120 x 120 x 9 of 0.25 mm: "
      "30 x 30 x 2.25 mm, 129,600 elements, 146,410 nodes), layers from the bottom: hypodermis "
      "(34 kPa), dermis 1.8 mm (81.4 kPa), stratum corneum 0.02 mm (48 MPa; a cut top voxel gets "
      "volume fractions), nu = 0.49, rho = 11,000 kg/m^3 (paper Table 1). Node sets x_min .. z_max "
      "(faces) and 'press' (top-centre patch); surface 'skin' without the bottom face");
  std::vector<int> dims{120, 120, 9};
  double block_h = 0.25e-3;
  int press_width = 0;
  block->add_option("--dims", dims, "voxels along x, y, z")->expected(3)->default_str("120 120 9");
  block->add_option("--voxel-size", block_h, "voxel side h, m")->default_val(block_h);
  block
      ->add_option("--press-width", press_width,
                   "side of the 'press' patch in voxels (0: nx / 10, at least 1)")
      ->default_val(0);
  block->add_option("-o,--output", output, "model file to write (.h5)")->required();
  block->add_flag("-q,--quiet", quiet, "no log output");

  auto* body = app.add_subcommand(
      "soft-body",
      "a multi-material Armadillo-like soft body (paper Fig. 7): body, head, ears, arms, tail and "
      "four legs on flat foot pads, ellipsoids of voxels, one connected piece (scale 1.085, h = 2 "
      "mm: 16,354 elements, 20,992 nodes, 162 x 64 x 106 mm, 0.1308 kg); three nested materials "
      "by distance from the body centre (core 400 kPa, flesh 200 kPa, skin 100 kPa; nu = 0.45, "
      "rho = 1000 kg/m^3). Node set 'feet' (the bottom nodes of the pads); surface 'skin' (the "
      "whole boundary)");
  double scale = 1.085, body_h = 2e-3;
  body->add_option("--scale", scale,
                   "size in voxels relative to the reference shape (smaller: fewer elements, "
                   "about scale^3)")
      ->default_val(scale);
  body->add_option("--voxel-size", body_h, "voxel side h, m")->default_val(body_h);
  body->add_option("-o,--output", output, "model file to write (.h5)")->required();
  body->add_flag("-q,--quiet", quiet, "log only errors");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  return sinew::tool::run("sinew-sample-model", [&] {
    if (quiet) sinew::log::set_level(sinew::log::Level::error);
    sinew::formats::Model model;
    if (block->parsed()) {
      for (int d : dims)
        if (d < 1) throw sinew::ConfigError("", "--dims", "every size must be >= 1");
      check_positive(block_h, "--voxel-size");
      if (press_width < 0) throw sinew::ConfigError("", "--press-width", "must be >= 0");
      model = sinew::simulator::make_skin_block_sample_model(dims[0], dims[1], dims[2], block_h,
                                                             press_width);
      model.provenance.tool = "sinew-sample-model skin-block";
      model.provenance.parameters_json = "{\"model\": \"skin-block\", \"dims\": [" +
                                         std::to_string(dims[0]) + ", " + std::to_string(dims[1]) +
                                         ", " + std::to_string(dims[2]) +
                                         "], \"voxel_size\": " + number(block_h) +
                                         ", \"press_width\": " + std::to_string(press_width) + "}";
    } else {
      check_positive(scale, "--scale");
      check_positive(body_h, "--voxel-size");
      model = sinew::simulator::make_soft_body_sample_model(scale, body_h);
      if (model.element_count() == 0)
        throw sinew::ConfigError("", "--scale", "too small: the body has no element");
      model.provenance.tool = "sinew-sample-model soft-body";
      model.provenance.parameters_json = "{\"model\": \"soft-body\", \"scale\": " + number(scale) +
                                         ", \"voxel_size\": " + number(body_h) + "}";
    }
    model.provenance.tool_version = sinew::kVersion;
    sinew::formats::write_model(model, output);
    const auto& skin = model.surfaces.back();
    sinew::log::info(
        "wrote {}: {} nodes, {} elements, {} materials, mass {:.6g} kg; surface '{}': {} "
        "vertices, {} triangles",
        output, model.node_count(), model.element_count(), model.materials.size(),
        sinew::simulator::model_mass(model), skin.name, skin.vertices.size(),
        skin.triangles.size());
    return sinew::tool::kExitOk;
  });
}
