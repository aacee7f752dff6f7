// sinew-voxelize SPEC [-o MODEL] [--json] [--quiet] [--threads N] [--force]
// Reads a voxelizer spec (docs/voxelizer.md), builds the model and writes the model file; prints a
// summary (or, with --json, the same as JSON on stdout). Any error: a message on stderr, exit
// code 1 (2 for command-line errors), and no model file.
#include <CLI/CLI.hpp>
#include <iostream>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/threads.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"

int main(int argc, char** argv) {
  sinew::threads::prefer_passive_wait(argv);
  CLI::App app{"sinew-voxelize: layered surface meshes -> a voxel finite-element model"};
  std::string spec_path, output;
  bool json = false, quiet = false, force = false;
  int threads = 0;
  app.add_option("spec", spec_path, "the voxelizer spec (YAML)")->required();
  app.add_option("-o,--output", output, "model file to write (default: the spec's output)");
  app.add_flag("--json", json, "print the summary as JSON on stdout");
  app.add_flag("-q,--quiet", quiet, "no progress bar, no log messages below errors");
  app.add_option("--threads", threads, "OpenMP threads (default: all)")->check(CLI::PositiveNumber);
  app.add_flag("--force", force,
               "go past the bounds on the meshes (extent against the units, element count, "
               "negative volume) with a warning each");
  CLI11_PARSE(app, argc, argv);

  sinew::log::set_level(quiet ? sinew::log::Level::error : sinew::log::Level::info);
  return sinew::tool::run("sinew-voxelize", [&] {
    auto spec = sinew::voxelizer::read_spec(spec_path);
    if (!output.empty()) spec.output = output;
    if (spec.output.empty()) {
      throw sinew::ConfigError(spec_path, "output",
                               "no output path: give `output:` in the spec or -o MODEL");
    }
    sinew::voxelizer::VoxelizeOptions options;
    options.threads = threads;
    options.progress = !quiet && !json;
    options.force = force;
    auto result = sinew::voxelizer::voxelize(spec, options);
    sinew::formats::write_model(result.model, spec.output.string());
    result.summary.output = spec.output.string();
    if (json) {
      std::cout << sinew::voxelizer::summary_json(result.summary) << '\n';
    } else if (!quiet) {
      std::cout << sinew::voxelizer::summary_text(result.summary);
    }
    return sinew::tool::kExitOk;
  });
}
