// sinew-head -o DIR [--segments-around N] [--segments-up N]
// Writes the sample head (docs/faces.md): skin.obj and skull.obj (closed, mm) and landmarks.yaml
// (the 20 landmarks of docs/landmarks.md, mm) into DIR, and prints the landmarks' positions.
// Any error: a message on stderr, exit code 1 (2 for command-line errors).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/voxelizer/head.hpp"

int main(int argc, char** argv) {
  CLI::App app{"sinew-head: the procedural sample head (skin, skull, landmarks; mm)"};
  std::string dir;
  sinew::voxelizer::HeadParams p;
  app.add_option("-o,--output", dir, "folder to write into (created if needed)")->required();
  app.add_option("--segments-around", p.segments_around, "mesh segments around (even, >= 16)");
  app.add_option("--segments-up", p.segments_up, "mesh segments from pole to pole (even, >= 16)");
  CLI11_PARSE(app, argc, argv);
  return sinew::tool::run("sinew-head", [&] {
    const auto written = sinew::voxelizer::write_head(p, dir);
    for (const auto& w : written) std::printf("wrote %s\n", w.string().c_str());
    const auto l = sinew::voxelizer::head_landmarks(p);
    for (const auto& n : sinew::voxelizer::landmark_names()) {
      const auto& q = l.at(n);
      std::printf("  %-20s [%8.2f, %8.2f, %8.2f] mm\n", n.c_str(), 1e3 * q.x, 1e3 * q.y, 1e3 * q.z);
    }
    return sinew::tool::kExitOk;
  });
}
