// sinew-live: simulates a scene in an engine thread and serves a page that draws the skin while it
// computes and steers it (muscle sliders, pause/resume/step/reset, click-drag forces, recording).
// docs/live.md.
//
//   sinew-live [SCENE] [--play RESULTS.h5] [--device auto|cpu|cuda] [--port P] [--host H] [--record DIR] [--explain]
//              [--precision float|double] [--threads N] [--paused] [--frame-rate F] [--speed S]
//              [--surface NAME] [--up z|y] [--token T] [--allow-host NAME]... [--web DIR]
//              [--three DIR] [-q] [-v]
//
// Exit status: 0 stopped (Ctrl-C), 1 bad input or I/O error, 2 bad command line.
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/threads.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/live/own_origin.hpp"
#include "sinew/live/playback.hpp"
#include "sinew/live/server.hpp"
#include "sinew/live/session.hpp"
#include "sinew/simulator/run/run_setup.hpp"

int main(int argc, char** argv) {
  using namespace sinew;
  threads::prefer_passive_wait(argv);
  CLI::App app{
      "sinew-live: simulate a scene and watch and steer it in a browser while it runs "
      "(docs/live.md)"};
  simulator::RunOptions opt;
  live::SessionOptions so;
  live::ServerOptions server;
  // The page and three.js beside the tool (the build copies them there: live/copy_page.cmake)
  // first, so a build used from elsewhere or copied away serves its page; else the source tree.
  std::error_code ec;
  const auto here = std::filesystem::read_symlink("/proc/self/exe", ec).parent_path();
  const auto beside = [&](const char* name, const char* file, const char* source) {
    return !ec && std::filesystem::is_regular_file(here / name / file) ? (here / name).string()
                                                                       : std::string(source);
  };
  std::string precision, web = beside("web", "index.html", SINEW_LIVE_WEB_DIR),
                         three = beside("three", "build/three.module.js", SINEW_LIVE_THREE_DIR);
  bool verbose = false;
  auto* scene_opt =
      app.add_option("scene", opt.scene_path, "Scene file (YAML, docs/scene-format.md)")
          ->check(CLI::ExistingFile);
  app.add_option("--play", so.play,
                 "Scrub through this results file first; 'continue' replays its scene to the "
                 "shown frame and goes on live (scene: SCENE, else scene.yaml beside the file, "
                 "else the file's scene_file)")
      ->check(CLI::ExistingFile);
  app.add_option("--device", opt.device, "Backend: cpu, cuda or auto")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  app.add_option("--precision", precision, "Override the scene's precision: float or double")
      ->check(CLI::IsMember({"float", "double"}));
  app.add_option("--threads", opt.threads,
                 "OpenMP threads of the CPU backend (default: every core, waiting passively)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--explain", opt.explain, "Print the plan first (as sinew-simulate --explain)");
  app.add_option("--host", server.host,
                 "Address to bind (default 127.0.0.1; any other needs the printed token)");
  app.add_option("--port", server.port, "Port (0: any free port)")->default_val(8080);
  // A weak token or a bad name is refused with the command line, before the model loads (and
  // before anything binds), whatever the host: the Server's own rules (server.hpp, own_origin.hpp).
  app.add_option("--token", server.token,
                 fmt::format("Access token to require, at least {} characters of letters, "
                             "digits, '-', '.', '_', '~' (default: a random one for non-loopback "
                             "binds)",
                             live::kMinTokenLength))
      ->check(CLI::Validator([](std::string& t) { return live::token_problem(t); }, "TOKEN"));
  app.add_option("--allow-host", server.allowed_hosts,
                 "A host name the server also answers to (the browser's address bar without the "
                 "port, e.g. gpu-server.lan), besides 127.0.0.1, localhost, [::1] and --host")
      ->check(CLI::Validator([](std::string& n) { return live::host_name_problem(n); }, "NAME"));
  app.add_option("--record", so.record_dir,
                 "Record from the start into this folder (results.h5, steering_log.json, "
                 "scene.yaml that reproduces the session)");
  app.add_flag("--paused", so.start_paused, "Start paused");
  app.add_option("--frame-rate", so.frame_rate, "Frames per second streamed (at most)")
      ->default_val(30)
      ->check(CLI::Range(1.0, 240.0));
  app.add_option("--speed", so.max_speed,
                 "At most this many simulated seconds per wall second (0: as fast as it goes)")
      ->default_val(0)
      ->check(CLI::NonNegativeNumber);
  app.add_option("--surface", so.surface, "Visual surface to show (default: the first)");
  app.add_option("--up", so.up,
                 "The model's up axis, for the page's camera: z, or y for the face and forehead "
                 "(the page's ?up= overrides it)")
      ->default_val("z")
      ->check(CLI::IsMember({"y", "z"}));
  app.add_option("--web", web, "Folder of the page")->default_val(web);
  app.add_option("--three", three, "three.js package folder (scripts/install-deps puts it there)")
      ->default_val(three);
  app.add_flag("-q,--quiet", opt.quiet, "Warnings and errors only");
  app.add_flag("-v,--verbose", verbose, "Debug messages");
  app.set_version_flag("--version", std::string(sinew::kVersion));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  log::set_level(verbose ? log::Level::debug : opt.quiet ? log::Level::warn : log::Level::info);
  if (!precision.empty()) {
    opt.precision =
        precision == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
  }

  return tool::run("sinew-live", [&] {
    if (!so.play.empty() && scene_opt->count() == 0)
      opt.scene_path = live::RecordedRun(so.play).scene();
    if (opt.scene_path.empty())
      throw ConfigError("", "scene", "give a scene (or --play RESULTS.h5)");
    if (!std::filesystem::is_regular_file(std::filesystem::path(web) / "index.html"))
      throw IoError(web, "", "the page's folder has no index.html (--web)");
    if (!std::filesystem::is_regular_file(std::filesystem::path(three) / "build/three.module.js"))
      throw IoError(three, "",
                    fmt::format("three.js is not there, nor beside the tool ({}/three): run "
                                "scripts/install-deps (it puts three.js into .cache/three) and "
                                "build again (it copies it beside sinew-live), or point --three at "
                                "a three.js package folder",
                                here.string()));
    // The live run plans as sinew-simulate does, with its steering (make_live_setup).
    auto run = simulator::load_run(
        opt, so.play.empty() ? live::make_live_setup : live::make_playback_setup);
    if (opt.explain) {
      simulator::RunOptions shown = opt;
      shown.output_dir = "(live)";
      std::fputs(simulator::explain_run(run, shown).c_str(), stdout);
    }
    if (!live::is_loopback_host(server.host) && server.token.empty())
      server.token = live::make_token();
    server.roots = {{"/vendor/three/", three}, {"/", web}};
    live::Session session(std::move(run), so);
    live::Server http(session, server);
    const std::string shown =
        server.host.find(':') != std::string::npos ? "[" + server.host + "]" : server.host;
    const std::string url = fmt::format("http://{}:{}/{}", shown, http.port(),
                                        server.token.empty() ? "" : "?token=" + server.token);
    std::printf("sinew-live: open %s  (Ctrl-C stops)\n", url.c_str());
    std::fflush(stdout);
    session.start();
    http.run(true);
    session.stop();
    log::info("sinew-live: stopped at step {}", session.step_index());
    return tool::kExitOk;
  });
}
