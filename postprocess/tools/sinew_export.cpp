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

#include <algorithm>
#include <cstdio>
#include <string>

#include "results_options.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/postprocess/element_fields.hpp"
#include "sinew/postprocess/gltf_writer.hpp"
#include "sinew/postprocess/pc2_writer.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/postprocess/vertex_attributes.hpp"

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
    if (glb.empty() && pc2.empty() && obj_dir.empty()) {
      throw ConfigError("", "command line",
                        "nothing to export: give --glb, --pc2 or --obj-sequence");
    }
    if (!pc2.empty() && rest_obj.empty()) {
      throw ConfigError("", "--rest-obj",
                        "--pc2 needs --rest-obj: the cache applies to a mesh of the same vertex "
                        "order");
    }
    const auto vertex_scalar = parse_vertex_scalar(color);
    const auto anim = read_surface(results, surface);
    std::printf("%s: surface \"%s\", %zu vertices, %zu triangles, %zu frames (t = %g .. %g s)%s\n",
                results.c_str(), anim.name.c_str(), anim.vertex_count(), anim.triangle_count(),
                anim.frame_count(), anim.times.front(), anim.times.back(),
                anim.has_uvs() ? ", texture coordinates" : "");
    // Von Mises stress at the vertices: element values averaged to nodes and interpolated.
    const auto color_values = vertex_scalar == VertexScalar::von_mises
                                  ? element_field_at_vertices(results, anim, "/frames/von_mises")
                                  : std::vector<std::vector<float>>{};
    if (!color_values.empty()) {
      float max = 0;
      for (const float s : peak_over_frames(color_values)) max = std::max(max, s);
      std::printf("von Mises stress at the surface: 0 .. %g Pa (viridis)\n", max);
    }
    if (!glb.empty()) {
      GltfOptions o;
      o.color_values = color_values;
      o.up = parse_up_axis(up);
      o.fps = fps;
      o.time_scale = time_scale;
      o.linear = linear;
      o.color = vertex_scalar;
      const auto timing = write_glb(glb, anim, o);
      std::printf(
          "wrote %s (%zu morph targets, %s): %g fps, results frame 0 at frame 0, "
          "frame %zu at frame %lld\n",
          glb.c_str(), anim.frame_count(), linear ? "linear" : "step", timing.fps,
          anim.frame_count() - 1, static_cast<long long>(timing.frame.back()));
    }
    if (!pc2.empty()) {
      write_pc2(pc2, anim);
      ObjAttributes attributes = texture_attributes(anim);
      attributes.normals = smooth_normals(anim.rest, anim.triangles);
      write_obj(rest_obj, anim.rest, anim.triangles,
                "sinew surface " + anim.name + " rest pose (vertex order of " + pc2 + ")",
                attributes);
      std::printf("wrote %s (%zu samples, results frame k at frame k) and %s\n", pc2.c_str(),
                  anim.frame_count(), rest_obj.c_str());
    }
    if (!obj_dir.empty()) {
      const auto paths = write_obj_sequence(obj_dir, anim, "frame", vertex_scalar, color_values);
      std::printf("wrote %zu OBJ files into %s\n", paths.size(), obj_dir.c_str());
    }
    return tool::kExitOk;
  });
}
