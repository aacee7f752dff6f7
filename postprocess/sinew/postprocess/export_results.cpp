#include "sinew/postprocess/export_results.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "sinew/common/error.hpp"
#include "sinew/postprocess/element_fields.hpp"
#include "sinew/postprocess/gltf_writer.hpp"
#include "sinew/postprocess/pc2_writer.hpp"
#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/postprocess/vertex_attributes.hpp"

namespace sinew::postprocess {

std::vector<std::string> export_results(const ExportRequest& r) {
  if (r.glb.empty() && r.pc2.empty() && r.obj_sequence.empty()) {
    throw ConfigError("", "command line", "nothing to export: give --glb, --pc2 or --obj-sequence");
  }
  if (!r.pc2.empty() && r.rest_obj.empty()) {
    throw ConfigError("", "--rest-obj",
                      "--pc2 needs --rest-obj: the cache applies to a mesh of the same vertex "
                      "order");
  }
  // Checked before anything is read, so a typo costs no read of a large file.
  const auto vertex_scalar = parse_vertex_scalar(r.color);
  const auto up = parse_up_axis(r.up);
  if (!(r.fps >= 0) || !(r.time_scale >= 0)) {
    throw ConfigError("", r.fps >= 0 ? "--time-scale" : "--fps", "must be a positive number");
  }
  std::vector<std::string> lines;
  const auto anim = read_surface(r.results, r.surface);
  lines.push_back(fmt::format(
      "{}: surface \"{}\", {} vertices, {} triangles, {} frames (t = {:g} .. {:g} s){}", r.results,
      anim.name, anim.vertex_count(), anim.triangle_count(), anim.frame_count(), anim.times.front(),
      anim.times.back(), anim.has_uvs() ? ", texture coordinates" : ""));
  // Von Mises stress at the vertices: element values averaged to nodes and interpolated.
  const auto color_values = vertex_scalar == VertexScalar::von_mises
                                ? element_field_at_vertices(r.results, anim, "/frames/von_mises")
                                : std::vector<std::vector<float>>{};
  if (!color_values.empty()) {
    float max = 0;
    for (const float s : peak_over_frames(color_values)) max = std::max(max, s);
    lines.push_back(fmt::format("von Mises stress at the surface: 0 .. {:g} Pa (viridis)", max));
  }
  if (!r.glb.empty()) {
    GltfOptions o;
    o.color_values = color_values;
    o.up = up;
    o.fps = r.fps;
    o.time_scale = r.time_scale;
    o.linear = r.linear;
    o.color = vertex_scalar;
    const auto timing = write_glb(r.glb, anim, o);
    lines.push_back(fmt::format(
        "wrote {} ({} morph targets, {}): {:g} fps, results frame 0 at frame 0, frame {} at "
        "frame {}",
        r.glb, anim.frame_count(), r.linear ? "linear" : "step", timing.fps, anim.frame_count() - 1,
        static_cast<long long>(timing.frame.back())));
  }
  if (!r.pc2.empty()) {
    write_pc2(r.pc2, anim);
    ObjAttributes attributes = texture_attributes(anim);
    attributes.normals = smooth_normals(anim.rest, anim.triangles);
    write_obj(r.rest_obj, anim.rest, anim.triangles,
              "sinew surface " + anim.name + " rest pose (vertex order of " + r.pc2 + ")",
              attributes);
    lines.push_back(fmt::format("wrote {} ({} samples, results frame k at frame k) and {}", r.pc2,
                                anim.frame_count(), r.rest_obj));
  }
  if (!r.obj_sequence.empty()) {
    const auto paths =
        write_obj_sequence(r.obj_sequence, anim, "frame", vertex_scalar, color_values);
    lines.push_back(fmt::format("wrote {} OBJ files into {}", paths.size(), r.obj_sequence));
  }
  return lines;
}

}  // namespace sinew::postprocess
