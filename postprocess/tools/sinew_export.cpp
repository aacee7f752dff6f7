// sinew-export: writes a results file's visual surface animation for artists' tools: glTF 2.0
// (.glb, Blender and three.js), a PC2 point cache with its rest-pose OBJ (Blender's Mesh Cache
// modifier) and an OBJ sequence. docs/visual-output.md.
//
//   sinew-export RESULTS [--surface NAME] [--list] [--glb OUT.glb [--time-scale S] [--linear]]
//                [--pc2 OUT.pc2 --rest-obj REST.obj] [--obj-sequence DIR] [--up y|z]
//
// Exit status: 0 done, 1 bad input or I/O error, 2 bad command line.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

#include "results_options.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/postprocess/gltf_writer.hpp"
#include "sinew/postprocess/pc2_writer.hpp"
#include "sinew/postprocess/results_reader.hpp"

int main(int argc, char** argv) {
  using namespace sinew;
  using namespace sinew::postprocess;
  CLI::App app{"sinew-export: glTF, PC2 + OBJ and OBJ sequences of a sinew results file's surface"};
  std::string results, surface, glb, pc2, rest_obj, obj_dir, up = "y";
  double time_scale = 1.0;
  bool linear = false, list = false;
  add_results_options(app, results, surface);
  app.add_flag("--list", list, "List the stored visual surfaces and exit");
  app.add_option("--glb", glb, "glTF 2.0 binary: rest mesh + one morph target per frame");
  app.add_option("--time-scale", time_scale,
                 "glTF animation time = scene time × this (e.g. 10 for slow motion)")
      ->check(CLI::PositiveNumber);
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
    if (glb.empty() && pc2.empty() && obj_dir.empty()) {
      throw ConfigError("", "command line",
                        "nothing to export: give --glb, --pc2 or --obj-sequence");
    }
    if (!pc2.empty() && rest_obj.empty()) {
      throw ConfigError("", "--rest-obj",
                        "--pc2 needs --rest-obj: the cache applies to a mesh of the same vertex "
                        "order");
    }
    const auto anim = read_surface(results, surface);
    std::printf("%s: surface \"%s\", %zu vertices, %zu triangles, %zu frames (t = %g .. %g s)\n",
                results.c_str(), anim.name.c_str(), anim.vertex_count(), anim.triangle_count(),
                anim.frame_count(), anim.times.front(), anim.times.back());
    if (!glb.empty()) {
      GltfOptions o;
      o.up = parse_up_axis(up);
      o.time_scale = time_scale;
      o.linear = linear;
      write_glb(glb, anim, o);
      std::printf("wrote %s (%zu morph targets, %s)\n", glb.c_str(), anim.frame_count(),
                  linear ? "linear" : "step");
    }
    if (!pc2.empty()) {
      write_pc2(pc2, anim);
      write_obj(rest_obj, anim.rest, anim.triangles,
                "sinew surface " + anim.name + " rest pose (vertex order of " + pc2 + ")");
      std::printf("wrote %s (%zu samples from frame 1) and %s\n", pc2.c_str(), anim.frame_count(),
                  rest_obj.c_str());
    }
    if (!obj_dir.empty()) {
      const auto paths = write_obj_sequence(obj_dir, anim);
      std::printf("wrote %zu OBJ files into %s\n", paths.size(), obj_dir.c_str());
    }
    return tool::kExitOk;
  });
}
