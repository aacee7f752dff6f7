// sinew-render: draws a results file's visual surface into PNG images with a software rasteriser
// (no window, no GPU): one frame, every frame, a contact sheet, and an animated GIF or MP4 when
// ffmpeg or ImageMagick is installed. docs/visual-output.md.
//
//   sinew-render RESULTS [--surface NAME] [--frame N | --all] [--view front|side|top|three-quarter]
//                [--up y|z] [--color none|displacement] [--colormap viridis|blue-red]
//                [--size WxH] [-o OUT.png | --sequence DIR] [--contact-sheet OUT.png
//                [--columns 4] [--sheet-frames 8]] [--gif OUT.gif | --mp4 OUT.mp4] [--fps 12]
//
// Exit status: 0 done, 1 bad input, I/O error or a missing GIF/MP4 encoder, 2 bad command line
// (including a frame out of range).
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "results_options.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/postprocess/contact_sheet.hpp"
#include "sinew/postprocess/model_preview.hpp"
#include "sinew/postprocess/png_writer.hpp"
#include "sinew/postprocess/render_session.hpp"
#include "sinew/postprocess/results_reader.hpp"

namespace {

using namespace sinew;
using namespace sinew::postprocess;

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return false;
  std::string all = path;
  std::size_t start = 0;
  while (start <= all.size()) {
    const auto end = std::min(all.find(':', start), all.size());
    const auto dir = all.substr(start, end - start);
    if (!dir.empty()) {
      std::error_code ec;
      const auto p = std::filesystem::path(dir) / program;
      if (std::filesystem::is_regular_file(p, ec)) return true;
    }
    start = end + 1;
  }
  return false;
}

// `convert` must be ImageMagick's (its -version output starts with "Version: ImageMagick").
bool imagemagick_available() {
  if (!on_path("convert")) return false;
  std::FILE* p = popen("convert -version 2>/dev/null", "r");
  if (!p) return false;
  char line[256] = {};
  const bool ok = std::fgets(line, sizeof line, p) != nullptr;
  pclose(p);
  return ok && std::string(line).rfind("Version: ImageMagick", 0) == 0;
}

std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

void parse_size(const std::string& text, int& w, int& h) {
  if (std::sscanf(text.c_str(), "%dx%d", &w, &h) != 2 || w < 8 || h < 8 || w > 16384 || h > 16384) {
    throw ConfigError("", "--size", fmt::format("\"{}\" is not WxH with 8 ≤ W, H ≤ 16384", text));
  }
}

// Renders every frame into `dir` as frame_0000.png, ...; returns the printf pattern.
std::string write_sequence(const FrameRenderer& renderer, std::size_t frames,
                           const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir, "", "cannot create the directory: " + ec.message());
  for (std::size_t k = 0; k < frames; ++k) {
    write_png((std::filesystem::path(dir) / fmt::format("frame_{:04}.png", k)).string(),
              renderer.render(k));
  }
  return (std::filesystem::path(dir) / "frame_%04d.png").string();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sinew-render: software-rendered PNG images of a sinew results file's surface"};
  std::string results, surface, view = "three-quarter", up = "y", color = "none",
                                colormap = "viridis", size = "800x600", output, sequence, sheet,
                                gif, mp4;
  int frame = -1, columns = 4, sheet_frames = 8, fps = 12;
  std::vector<double> target;
  std::vector<int> crop_box;
  double zoom = 1.0, skin_opacity = 0.35;
  int seed_spacing = 3;
  bool no_fibres = false;
  bool all = false;
  add_results_options(app, results, surface);
  auto* frame_opt = app.add_option("--frame", frame, "Frame index to draw (default: the last)")
                        ->check(CLI::NonNegativeNumber);
  app.add_flag("--all", all, "Draw every frame (with --sequence)")->excludes(frame_opt);
  app.add_option("--view", view, "Camera: front, side, top or three-quarter")
      ->check(CLI::IsMember({"front", "side", "top", "three-quarter"}));
  app.add_option("--up", up, "The results' up axis: y or z")->check(CLI::IsMember({"y", "z"}));
  app.add_option("--color", color, "Colouring: none or displacement (|u| of the surface)")
      ->check(CLI::IsMember({"none", "displacement"}));
  app.add_option("--colormap", colormap, "Colour map: viridis or blue-red")
      ->check(CLI::IsMember({"viridis", "blue-red"}));
  app.add_option("--size", size, "Image size WxH in pixels");
  app.add_option("--target", target, "Point X,Y,Z (m) the camera looks at (default: the centre)")
      ->expected(3)
      ->delimiter(',');
  app.add_option("--zoom", zoom, "Move the camera this many times closer to its target (> 0)");
  app.add_option("--crop", crop_box, "Keep the X,Y,W,H pixels of the --size image")
      ->expected(4)
      ->delimiter(',');
  app.add_option("-o,--output", output, "PNG of one frame (of a model file: its preview)");
  app.add_option("--skin-opacity", skin_opacity,
                 "Model preview: the skin's opacity over the muscles, 0 to 1 (0.35)");
  app.add_option("--seed-spacing", seed_spacing,
                 "Model preview: a fibre streamline every N muscle elements along each axis (3)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--no-fibres", no_fibres, "Model preview: draw no fibre streamlines");
  app.add_option("--sequence", sequence, "Folder for one PNG per frame (frame_0000.png, ...)");
  app.add_option("--contact-sheet", sheet, "PNG with several frames tiled and labelled");
  app.add_option("--columns", columns, "Contact sheet columns")->check(CLI::PositiveNumber);
  app.add_option("--sheet-frames", sheet_frames, "Frames on the contact sheet, evenly spread")
      ->check(CLI::PositiveNumber);
  app.add_option("--gif", gif, "Animated GIF of all frames (needs ffmpeg or ImageMagick)");
  app.add_option("--mp4", mp4, "MP4 video of all frames (needs ffmpeg)");
  app.add_option("--fps", fps, "Frames per second of the GIF/MP4")->check(CLI::PositiveNumber);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help exits 0; every command-line mistake exits 2.
    return app.exit(e) == 0 ? 0 : 2;
  }

  const sinew::tool::ExitCodes codes{.config = sinew::tool::kExitUsage};
  return sinew::tool::run("sinew-render", codes, [&] {
    // The image options both kinds of file take.
    auto set_view = [&](ViewSettings& v) {
      parse_size(size, v.width, v.height);
      v.view = parse_view(view);
      v.up = parse_up_axis(up);
      if (!target.empty()) v.target = Point{target[0], target[1], target[2]};
      v.zoom = zoom;
      if (!crop_box.empty())
        v.crop = std::array<int, 4>{crop_box[0], crop_box[1], crop_box[2], crop_box[3]};
    };
    if (is_model_file(results)) {
      // A model before any run: its muscles and fibres under a translucent skin.
      if (output.empty() || !sequence.empty() || !sheet.empty() || !gif.empty() || !mp4.empty() ||
          frame >= 0 || all || color != "none") {
        throw ConfigError(results, "command line",
                          "this is a model file: it has no frames; draw its preview with -o "
                          "OUT.png (--view, --target, --zoom, --crop, --skin-opacity, "
                          "--no-fibres, --seed-spacing)");
      }
      PreviewSettings ps;
      set_view(ps);
      ps.skin_opacity = skin_opacity;
      ps.fibres = !no_fibres;
      const auto model = formats::read_model(results);
      const auto preview = make_model_preview(model, surface, seed_spacing);
      write_png(output, render_model_preview(preview, ps));
      std::printf("%s: model preview: skin \"%s\", %zu muscles, %zu fibre streamlines; wrote %s\n",
                  results.c_str(), preview.skin.name.c_str(), preview.muscles.size(),
                  preview.streamlines.size(), output.c_str());
      return sinew::tool::kExitOk;
    }
    if (output.empty() && sequence.empty() && sheet.empty() && gif.empty() && mp4.empty()) {
      throw ConfigError("", "command line",
                        "nothing to draw: give -o, --sequence, --contact-sheet, --gif or --mp4");
    }
    if (all && sequence.empty()) {
      throw ConfigError("", "--all", "--all draws every frame into --sequence DIR");
    }
    // Check the GIF/MP4 tools before the work.
    const bool have_ffmpeg = on_path("ffmpeg");
    if (!mp4.empty() && !have_ffmpeg) {
      throw ResourceError("", "--mp4",
                          "unavailable: ffmpeg is not on PATH (write --sequence DIR "
                          "and encode the PNGs elsewhere)");
    }
    const bool have_magick = !gif.empty() && !have_ffmpeg && imagemagick_available();
    if (!gif.empty() && !have_ffmpeg && !have_magick) {
      throw ResourceError("", "--gif",
                          std::string("unavailable: ffmpeg is not on PATH and ") +
                              (on_path("convert")
                                   ? "the `convert` on PATH is not ImageMagick's (its -version "
                                     "does not begin with \"Version: ImageMagick\")"
                                   : "neither is ImageMagick's convert") +
                              " (write --sequence DIR and encode the PNGs elsewhere)");
    }
    FrameRenderSettings s;
    set_view(s);
    s.color_displacement = color == "displacement";
    s.map = parse_color_map(colormap);
    const auto anim = read_surface(results, surface);
    const std::size_t frames = anim.frame_count();
    if (frame >= 0 && static_cast<std::size_t>(frame) >= frames) {
      throw ConfigError(
          results, "--frame",
          fmt::format("frame {} out of range: the file has {} frames", frame, frames));
    }
    const std::size_t chosen = frame >= 0 ? static_cast<std::size_t>(frame) : frames - 1;
    const FrameRenderer renderer(anim, s);
    std::printf("%s: surface \"%s\", %zu vertices, %zu triangles, %zu frames (t = %g .. %g s)\n",
                results.c_str(), anim.name.c_str(), anim.vertex_count(), anim.triangle_count(),
                frames, anim.times.front(), anim.times.back());
    if (s.color_displacement) {
      std::printf("colour: displacement 0 .. %.4g mm\n", 1000.0 * renderer.max_displacement());
    }
    if (!output.empty()) {
      write_png(output, renderer.render(chosen));
      std::printf("wrote %s (frame %zu)\n", output.c_str(), chosen);
    }
    if (!sequence.empty()) {
      if (all || frame < 0) {
        write_sequence(renderer, frames, sequence);
        std::printf("wrote %zu frames into %s\n", frames, sequence.c_str());
      } else {
        std::filesystem::create_directories(sequence);
        const auto p = (std::filesystem::path(sequence) / fmt::format("frame_{:04}.png", chosen));
        write_png(p.string(), renderer.render(chosen));
        std::printf("wrote %s\n", p.string().c_str());
      }
    }
    if (!sheet.empty()) {
      std::vector<Image> tiles;
      std::vector<std::string> labels;
      FrameRenderSettings tile_settings = s;
      tile_settings.caption = false;
      const FrameRenderer tile_renderer(anim, tile_settings);
      for (auto k : spread_frames(frames, static_cast<std::size_t>(sheet_frames))) {
        tiles.push_back(tile_renderer.render(k));
        labels.push_back(frame_label(anim, k));
      }
      ContactSheetOptions co;
      co.columns = columns;
      co.font_scale = std::max(1, s.height / 200);
      write_png(sheet, contact_sheet(tiles, labels, co));
      std::printf("wrote %s (%zu frames)\n", sheet.c_str(), tiles.size());
    }
    for (const auto* target : {&gif, &mp4}) {
      if (target->empty()) continue;
      const auto tmp = std::filesystem::temp_directory_path() /
                       fmt::format("sinew-render-{}-{}", static_cast<long>(getpid()),
                                   target == &gif ? "gif" : "mp4");
      const auto pattern = write_sequence(renderer, frames, tmp.string());
      std::string cmd;
      if (have_ffmpeg) {
        cmd = fmt::format("ffmpeg -loglevel error -y -framerate {} -i {} ", fps, quote(pattern));
        cmd += target == &gif
                   ? quote(gif)
                   : "-pix_fmt yuv420p -vf 'scale=trunc(iw/2)*2:trunc(ih/2)*2' " + quote(mp4);
      } else {
        cmd = fmt::format("convert -delay {} -loop 0 {}/frame_*.png {}", std::max(1, 100 / fps),
                          quote(tmp.string()), quote(gif));
      }
      const int rc = std::system(cmd.c_str());
      std::error_code ec;
      std::filesystem::remove_all(tmp, ec);
      if (rc != 0) throw IoError(*target, "", "the encoder failed: " + cmd);
      std::printf("wrote %s\n", target->c_str());
    }
    return sinew::tool::kExitOk;
  });
}
