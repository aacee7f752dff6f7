// sinew-rig SPEC -o DIR [--landmarks-png FILE] [--muscles-png FILE] [--jaw-png FILE]
//                       [--snap-landmarks FILE]
// Builds the muscle rig of a voxelizer spec's `rig:` section (docs/faces.md) without voxelizing:
// checks the landmarks and that each muscle lies in the tissue, writes every rig muscle as a
// closed OBJ (mm) into DIR for a look in any 3D package, and prints each muscle's size and fibres.
// --landmarks-png draws the skin from the front with the landmarks numbered and listed; it is
// drawn before the checks, so that a first guess whose points are off the skin can be corrected
// by eye (docs/landmarks.md); --muscles-png the muscles through a half-transparent skin
// (rig_picture.hpp); --jaw-png the jaw (`rig: {jaw: true}`) from the side: the mandible the
// voxelizer will cut from the skull, its hinge axis, the occlusal plane and the incisal point.
// --snap-landmarks FILE writes the spec's landmarks moved to their closest
// points on the skin (in the spec's units) and builds the rig from FILE instead.
// Any error: a message on stderr, exit code 1 (2 for command-line errors).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "rig_picture.hpp"
#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/voxelizer/forehead.hpp"
#include "sinew/voxelizer/mesh_source.hpp"
#include "sinew/voxelizer/rig.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"

int main(int argc, char** argv) {
  CLI::App app{"sinew-rig: build a spec's muscle rig from its landmarks and write the meshes"};
  std::string spec_path, dir;
  app.add_option("spec", spec_path, "voxelizer spec with a rig: section")->required();
  app.add_option("-o,--output", dir, "folder for the muscles' OBJ files (mm)")->required();
  std::string landmarks_png, muscles_png;
  app.add_option("--landmarks-png", landmarks_png, "PNG of the skin with the landmarks numbered");
  app.add_option("--muscles-png", muscles_png, "PNG of the muscles under a half-transparent skin");
  std::string jaw_png;
  app.add_option("--jaw-png", jaw_png,
                 "PNG of the jaw from the side: the mandible, its hinge axis, the occlusal plane");
  std::string snap;
  app.add_option("--snap-landmarks", snap,
                 "write the landmarks moved onto the skin to this file and use them");
  CLI11_PARSE(app, argc, argv);
  return sinew::tool::run("sinew-rig", [&] {
    using namespace sinew::voxelizer;
    Spec spec = read_spec(spec_path);
    if (!spec.rig) throw sinew::ConfigError(spec_path, "rig", "the spec has no rig: section");
    TriangleMesh skin = load_mesh_source(spec.outer);
    clean_mesh(skin, spec.weld_tolerance);
    Landmarks landmarks = read_landmarks(spec.rig->landmarks);
    if (!snap.empty()) {
      const Landmarks snapped = snap_landmarks(landmarks, skin);
      for (const auto& name : landmark_names()) {
        const double moved = norm(snapped.at(name) - landmarks.at(name));
        if (moved > 5e-4) std::printf("snapped %-20s by %5.1f mm\n", name.c_str(), 1e3 * moved);
      }
      sinew::write_text_atomically(
          snap,
          landmarks_yaml(snapped, spec.units,
                         {"sinew-rig --snap-landmarks: " + spec.rig->landmarks.string() +
                              " moved to the closest points of the skin " + spec.outer.describe(),
                          "check them on the --landmarks-png picture (docs/landmarks.md)"}));
      std::printf("wrote %s (the rig below is built from it)\n", snap.c_str());
      spec.rig->landmarks = snap;
      landmarks = read_landmarks(snap);
    }
    // The landmarks' picture comes before the checks: it is how points off the skin are found.
    if (!landmarks_png.empty()) write_rig_picture(landmarks_png, skin, landmarks, {}, true);
    if (!jaw_png.empty()) {
      if (!spec.rig->jaw)
        throw sinew::ConfigError(spec_path, spec.rig->field + ".jaw",
                                 "--jaw-png draws the jaw, but the rig has none (jaw: true)");
      if (!spec.inner)
        throw sinew::ConfigError(spec_path, spec.rig->field + ".jaw",
                                 "the jaw is cut from the skull: give the spec an `inner` surface");
      TriangleMesh skull = load_mesh_source(*spec.inner);
      clean_mesh(skull, spec.weld_tolerance);
      write_jaw_picture(jaw_png, skin, skull, landmarks);
      std::printf("drew the jaw to %s\n", jaw_png.c_str());
    }
    // The muscles' picture comes before the check of how much of each lies in the tissue: it is
    // how a muscle past an open mesh's edge is seen.
    const CheckedRig built = build_spec_rig(spec);
    if (!built.message.empty()) {
      if (!muscles_png.empty()) {
        std::vector<PictureMuscle> drawn;
        for (const auto& m : built.muscles) drawn.push_back({m.name, &m.mesh});
        write_rig_picture(muscles_png, skin, landmarks, drawn, false);
        std::printf("drew the muscles to %s (the check below failed)\n", muscles_png.c_str());
      }
      throw sinew::GeometryError(spec.file.string(), spec.rig->field, built.message);
    }
    const std::size_t own = spec.muscles.size();
    append_rig_muscles(spec, built);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw sinew::IoError(dir, "", "cannot create the folder: " + ec.message());
    std::vector<PictureMuscle> pm;
    for (std::size_t i = own; i < spec.muscles.size(); ++i) {
      const auto& m = spec.muscles[i];
      TriangleMesh mm = *m.mesh.generated;
      for (auto& v : mm.vertices) v = 1e3 * v;
      const auto path = std::filesystem::path(dir) / (m.name + ".obj");
      sinew::write_text_atomically(
          path.string(), obj_text(mm, {"sinew-rig: " + m.name + " (docs/faces.md)",
                                       "units: mm; the spec's axes; closed, outward oriented"}));
      const auto d = describe_mesh(mm);
      const char* fibres = m.fibres.kind == FibreSpec::Kind::harmonic ? "harmonic origin->insertion"
                                                                      : "circumferential";
      std::printf("%-32s %8.0f mm^3  %6zu triangles  fibres %s  -> %s\n", m.name.c_str(),
                  d.enclosed_volume, mm.triangles.size(), fibres, path.string().c_str());
      pm.push_back({m.name, m.mesh.generated.get()});
    }
    if (!muscles_png.empty()) write_rig_picture(muscles_png, skin, landmarks, pm, false);
    return sinew::tool::kExitOk;
  });
}
