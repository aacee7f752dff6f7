// sinew-export: writes a results file's visual surface animation for artists' tools: glTF 2.0
// (.glb, Blender and three.js), a PC2 point cache with its rest-pose OBJ (Blender's Mesh Cache
// modifier) and an OBJ sequence. docs/visual-output.md.
//
//   sinew-export RESULTS [--surface NAME] [--list] [--glb OUT.glb [--linear]]
//                [--pc2 OUT.pc2 --rest-obj REST.obj] [--obj-sequence DIR] [--up y|z]
//                [--fps F] [--time-scale S] [--color none|displacement|von_mises]
//
// Timing (frame_timing.hpp): by default results frame k is frame k at F fps, F = 24 or 30 from the
// scene's output rate; --time-scale S plays scene time × S instead, snapped to whole frames.
//
// Exit status: 0 done, 1 bad input or I/O error, 2 bad command line.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

#include "results_options.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/postprocess/export_results.hpp"
#include "sinew/postprocess/results_reader.hpp"

int main(int argc, char** argv) {
  using namespace sinew;
  using namespace sinew::postprocess;
  CLI::App app{"sinew-export: glTF, PC2 + OBJ and OBJ sequences of a sinew results file's surface"};
  std::string results, surface, glb, pc2, rest_obj, obj_dir, up = "y";
  std::string color = "none";
  double time_scale = 0.0, fps = 0.0;
  bool linear = false, list = false;
  add_results_options(app, results, surface);
  app.add_flag("--list", list, "List the stored visual surfaces and exit");
  app.add_option("--glb", glb, "glTF 2.0 binary: rest mesh + one morph target per frame");
  app.add_option("--fps", fps,
                 "Frames per second of the animation (default: 24 or 30, from the output rate)")
      ->check(CLI::PositiveNumber);
  app.add_option("--time-scale", time_scale,
                 "glTF animation time = scene time × this, snapped to frames (default: one "
                 "results frame per frame)")
      ->check(CLI::PositiveNumber);
  app.add_option("--color", color,
                 "Per-vertex colour: none, displacement or von_mises (glTF COLOR_0 + _DISPLACEMENT "
                 "/ _VON_MISES of the peak value, OBJ sequence vertex colours of each frame's)")
      ->check(CLI::IsMember({"none", "displacement", "von_mises"}));
  app.add_flag("--linear", linear, "Interpolate linearly between frames (default: step)");
  auto* pc2_opt = app.add_option("--pc2", pc2, "Point Cache 2 file, one sample per frame");
  app.add_option("--rest-obj", rest_obj, "Rest-pose OBJ (the mesh the PC2 applies to)")
      ->needs(pc2_opt);
  app.add_option("--obj-sequence", obj_dir, "Folder for one OBJ per frame (frame_0000.obj, ...)");
  app.add_option("--up", up, "The results' up axis: y or z (glTF is turned to +Y up)")
      ->check(CLI::IsMember({"y", "z"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help exits 0; every command-line mistake exits 2.
    return app.exit(e) == 0 ? 0 : 2;
  }

  const tool::ExitCodes codes{.config = tool::kExitUsage};
  return tool::run("sinew-export", codes, [&] {
    if (list) {
      for (const auto& name : list_surfaces(results)) std::printf("%s\n", name.c_str());
      return tool::kExitOk;
    }
    ExportRequest request;
    request.results = results;
    request.surface = surface;
    request.glb = glb;
    request.pc2 = pc2;
    request.rest_obj = rest_obj;
    request.obj_sequence = obj_dir;
    request.up = up;
    request.color = color;
    request.fps = fps;
    request.time_scale = time_scale;
    request.linear = linear;
    for (const auto& line : export_results(request)) std::printf("%s\n", line.c_str());
    return tool::kExitOk;
  });
}
