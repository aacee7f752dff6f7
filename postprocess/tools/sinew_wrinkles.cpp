// sinew-wrinkles: measures the wrinkles of a results file's visual surface along vertical profiles
// (fold count, wavelength, depth, strain of the smooth motion) and prints a table; CSV/JSON files
// on request. docs/wrinkles.md.
//
//   sinew-wrinkles RESULTS [--surface NAME] [--frame N | --time T | --peak] [--up z] [--across x]
//                  [--profiles 9] [--region XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX] [--detrend-width 4]
//                  [--min-depth 0.02] [--spacing MM] [--min-facing 0.5] [--csv OUT.csv]
//                  [--json OUT.json] [--trace OUT.csv]
//
// Lengths on the command line and in the outputs are in mm. Exit status: 0 done, 1 bad input or
// I/O error, 2 bad command line (including a frame out of range).
#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "results_options.hpp"
#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/postprocess/wrinkles.hpp"

namespace {

using namespace sinew;
using namespace sinew::postprocess;

constexpr double kMm = 1e3;

// "a,b,c,d,e,f" (mm) → a box in m.
std::array<double, 6> parse_region(const std::string& text) {
  std::array<double, 6> r{};
  double v[6];
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &v[4],
                  &v[5], &tail) != 6) {
    throw ConfigError("", "--region",
                      fmt::format("\"{}\" is not XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX (mm)", text));
  }
  for (int i = 0; i < 6; ++i) r[i] = v[i] / kMm;
  return r;
}

// The voxel lattice: the size from the first element's first edge (node 0 → node 1, hex8/VTK
// order), m, and that element's node 0 as origin; size NaN when the file has no volume mesh.
struct Lattice {
  double h = std::nan("");
  std::array<double, 3> origin{0, 0, 0};
};
Lattice voxel_lattice(const std::string& path) {
  namespace h5 = sinew::formats::hdf5;
  auto file = h5::open_file(path, false);
  Lattice l;
  if (!h5::exists(file, "mesh") || !h5::exists(file, "/mesh/connectivity") ||
      !h5::exists(file, "/mesh/rest_positions")) {
    return l;
  }
  const auto conn = h5::read<std::int32_t>(file, "/mesh/connectivity", path);
  const auto x = h5::read<double>(file, "/mesh/rest_positions", path);
  if (conn.size() < 8) return l;
  const auto a = static_cast<std::size_t>(conn[0]), b = static_cast<std::size_t>(conn[1]);
  if (conn[0] < 0 || conn[1] < 0 || 3 * a + 2 >= x.size() || 3 * b + 2 >= x.size()) {
    throw FormatError(path, "/mesh/connectivity", "node id out of range").at(0);
  }
  l.h = std::sqrt(std::pow(x[3 * a] - x[3 * b], 2) + std::pow(x[3 * a + 1] - x[3 * b + 1], 2) +
                  std::pow(x[3 * a + 2] - x[3 * b + 2], 2));
  l.origin = {x[3 * a], x[3 * a + 1], x[3 * a + 2]};
  return l;
}

// RMS displacement of the surface in frame f.
double rms_displacement(const SurfaceAnimation& a, std::size_t f) {
  double q = 0;
  for (std::size_t i = 0; i < a.rest.size(); ++i) {
    const double d = static_cast<double>(a.frames[f][i]) - a.rest[i];
    q += d * d;
  }
  return std::sqrt(q / static_cast<double>(a.vertex_count()));
}

std::string mm(double v, int digits = 3) {
  return std::isfinite(v) ? fmt::format("{:.{}f}", v * kMm, digits) : std::string("-");
}
std::string csv_mm(double v) {
  return std::isfinite(v) ? fmt::format("{:.6g}", v * kMm) : "";
}
std::string csv_num(double v) {
  return std::isfinite(v) ? fmt::format("{:.6g}", v) : "";
}
nlohmann::ordered_json json_mm(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v * kMm) : nlohmann::ordered_json(nullptr);
}
nlohmann::ordered_json json_num(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

// Appends the figures a profile and the summary share (WrinkleProfile, WrinkleSummary: same
// names, same meaning), in the JSON's order: spectral wavelength, depths, RMS, strains.
template <class Figures>
void put_shared_figures(nlohmann::ordered_json& j, const Figures& f) {
  j["spectral_wavelength_mm"] = json_mm(f.spectral_wavelength);
  j["depth_mean_mm"] = json_mm(f.depth_mean);
  j["depth_max_mm"] = json_mm(f.depth_max);
  j["rms_mm"] = json_mm(f.rms);
  j["strain"] = json_num(f.strain);
  j["strain_min"] = json_num(f.strain_min);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "sinew-wrinkles: fold count, wavelength and depth of the wrinkles on a results "
      "file's skin surface, along vertical profiles"};
  std::string results, surface, up = "z", across = "x", region, csv, json_path, trace;
  int frame = -1, profiles = 9;
  double time = 0, width_mm = 4.0, depth_mm = 0.02, spacing_mm = 0, facing = 0.5;
  bool peak = false, quiet = false;
  add_results_options(app, results, surface);
  auto* frame_opt = app.add_option("--frame", frame, "Frame index (default: the last)")
                        ->check(CLI::NonNegativeNumber);
  auto* time_opt =
      app.add_option("--time", time, "Scene time, s: the nearest frame")->excludes(frame_opt);
  app.add_flag("--peak", peak, "The frame with the largest RMS surface displacement")
      ->excludes(frame_opt)
      ->excludes(time_opt);
  app.add_option("--up", up, "Axis of the skin's height (its outward direction)")
      ->check(CLI::IsMember({"x", "y", "z"}));
  app.add_option("--across", across, "Axis along which the profiles are spaced")
      ->check(CLI::IsMember({"x", "y", "z"}));
  app.add_option("--profiles", profiles, "Number of profiles")->check(CLI::Range(1, 100000));
  app.add_option("--region", region,
                 "Box on the rest positions, mm: XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX");
  app.add_option("--detrend-width", width_mm, "Width σ of the detrending fit, mm")
      ->check(CLI::PositiveNumber);
  app.add_option("--min-depth", depth_mm, "Fold threshold (peak to trough), mm")
      ->check(CLI::PositiveNumber);
  app.add_option("--spacing", spacing_mm, "Sample spacing along a profile, mm (default: automatic)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--min-facing", facing, "Use triangles whose rest normal has n·up ≥ this")
      ->check(CLI::Range(1e-6, 1.0));
  app.add_option("--csv", csv, "CSV: one row per profile and a row 'all'");
  app.add_option("--json", json_path, "JSON: options, summary, profiles with their folds");
  app.add_option("--trace", trace, "CSV of every profile sample (s, residual, strain)");
  app.add_flag("-q,--quiet", quiet, "Print only errors");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (quiet) log::set_level(log::Level::error);

  const tool::ExitCodes codes{.config = tool::kExitUsage};
  return tool::run("sinew-wrinkles", codes, [&] {
    WrinkleOptions o;
    o.up = parse_axis(up, "--up");
    o.across = parse_axis(across, "--across");
    if (o.up == o.across) throw ConfigError("", "--across", "must differ from --up");
    o.profiles = profiles;
    o.detrend_width = width_mm / kMm;
    o.min_depth = depth_mm / kMm;
    o.spacing = spacing_mm / kMm;
    o.min_facing = facing;
    if (!region.empty()) o.region = parse_region(region);

    const auto anim = read_surface(results, surface);
    const std::size_t frames = anim.frame_count();
    std::size_t f = frames - 1;
    if (frame >= 0) {
      if (static_cast<std::size_t>(frame) >= frames) {
        throw ConfigError(
            results, "--frame",
            fmt::format("frame {} out of range: the file has {} frames", frame, frames));
      }
      f = static_cast<std::size_t>(frame);
    } else if (time_opt->count() > 0) {
      if (!std::isfinite(time)) throw ConfigError("", "--time", "must be finite");
      for (std::size_t k = 0; k < frames; ++k) {
        if (std::abs(anim.times[k] - time) < std::abs(anim.times[f] - time)) f = k;
      }
    } else if (peak) {
      double best = -1;
      for (std::size_t k = 0; k < frames; ++k) {
        const double d = rms_displacement(anim, k);
        if (d > best) {
          best = d;
          f = k;
        }
      }
    }
    const auto lattice = voxel_lattice(results);
    const double h = lattice.h;
    if (std::isfinite(h) && h > 0) {
      o.voxel_size = h;
      o.lattice_origin = lattice.origin;
    }
    const auto rep = measure_wrinkles(anim, f, o);
    const auto& s = rep.summary;
    const char* ax = "xyz";
    const char along = ax[3 - o.up - o.across];

    if (!quiet) {
      std::printf(
          "%s: surface \"%s\", %zu vertices, frame %zu of %zu (t = %g s), RMS "
          "displacement %s mm\n",
          results.c_str(), anim.name.c_str(), anim.vertex_count(), f, frames, anim.times[f],
          mm(rms_displacement(anim, f)).c_str());
      std::printf("voxel size %s mm, surface mesh edge (median) %s mm\n", mm(h).c_str(),
                  mm(rep.edge_length).c_str());
      std::printf("profiles: %d lines %c = const along %c, height +%c; sample spacing %s mm\n",
                  o.profiles, ax[o.across], along, ax[o.up], mm(rep.options.spacing, 4).c_str());
      std::printf(
          "detrend: local quadratic, sigma %s mm (keeps >= 90%% of waves <= %s mm, 50%% at "
          "%s mm); folds: troughs deeper than %s mm\n\n",
          mm(o.detrend_width, 2).c_str(), mm(2.25 * o.detrend_width, 1).c_str(),
          mm(3.43 * o.detrend_width, 1).c_str(), mm(o.min_depth).c_str());
      std::printf("%7s %8s %9s %5s %9s %8s %9s %10s %9s %7s %8s %10s\n", "profile",
                  fmt::format("{} mm", ax[o.across]).c_str(), "length mm", "folds", "lambda mm",
                  "sd mm", "spec mm", "depth mm", "max mm", "rms mm", "strain%", "min strain%");
      for (std::size_t k = 0; k < rep.profiles.size(); ++k) {
        const auto& p = rep.profiles[k];
        if (p.samples == 0) {
          std::printf("%7zu %8s   (misses the surface)\n", k, mm(p.across, 2).c_str());
          continue;
        }
        std::printf("%7zu %8s %9s %5zu %9s %8s %9s %10s %9s %7s %8.2f %10.2f\n", k,
                    mm(p.across, 2).c_str(), mm(p.length_rest, 1).c_str(), p.folds.size(),
                    mm(p.wavelength_mean, 2).c_str(), mm(p.wavelength_std, 2).c_str(),
                    mm(p.spectral_wavelength, 2).c_str(), mm(p.depth_mean).c_str(),
                    mm(p.depth_max).c_str(), mm(p.rms).c_str(), 100 * p.strain, 100 * p.strain_min);
      }
      std::printf("%7s %8s %9s %5zu %9s %8s %9s %10s %9s %7s %8.2f %10.2f\n", "all", "", "",
                  s.folds, mm(s.wavelength_mean, 2).c_str(), mm(s.wavelength_std, 2).c_str(),
                  mm(s.spectral_wavelength, 2).c_str(), mm(s.depth_mean).c_str(),
                  mm(s.depth_max).c_str(), mm(s.rms).c_str(), 100 * s.strain, 100 * s.strain_min);
      std::printf("\n%zu folds on %zu profiles (%.2f per profile)", s.folds, s.profiles_used,
                  s.folds_mean);
      if (std::isfinite(s.retention)) {
        std::printf("; the detrending keeps %.0f%% of a wave of that length", 100 * s.retention);
      }
      std::printf("\n");
      if (std::isfinite(s.layer_locking)) {
        std::printf(
            "troughs within the voxel layers: phase locking R = %.2f over %zu folds "
            "spanning %.1f layers (random phases: about %.2f; near 1: a voxel-layer "
            "imprint, not wrinkles)\n",
            s.layer_locking, s.folds, s.layers_spanned,
            1 / std::sqrt(static_cast<double>(s.folds)));
        std::printf(
            "voxel-layer period at the troughs (h / rest slope, median): %s mm against "
            "the fold spacing %s mm\n",
            mm(s.layer_period, 2).c_str(), mm(s.wavelength_mean, 2).c_str());
      }
      const double lw = std::isfinite(s.wavelength_mean) ? s.wavelength_mean : std::nan("");
      if (std::isfinite(lw) && lw < 4 * rep.edge_length) {
        std::printf(
            "note: the wavelength is under 4 surface mesh edges: under-resolved by the "
            "visual mesh\n");
      }
      if (std::isfinite(lw) && std::isfinite(h) && lw < 3 * h) {
        std::printf(
            "note: the wavelength is under 3 voxels (2 voxels is the hourglass "
            "pattern's): suspect a discretisation mode, not a wrinkle\n");
      }
    }

    if (!csv.empty()) {
      std::ostringstream out;
      out << "profile,across_mm,samples,length_rest_mm,length_mm,folds,wavelength_mean_mm,"
             "wavelength_std_mm,spectral_wavelength_mm,depth_mean_mm,depth_max_mm,rms_mm,strain,"
             "strain_min\n";
      for (std::size_t k = 0; k < rep.profiles.size(); ++k) {
        const auto& p = rep.profiles[k];
        out << k << ',' << csv_mm(p.across) << ',' << p.samples << ',' << csv_mm(p.length_rest)
            << ',' << csv_mm(p.length) << ',' << p.folds.size() << ',' << csv_mm(p.wavelength_mean)
            << ',' << csv_mm(p.wavelength_std) << ',' << csv_mm(p.spectral_wavelength) << ','
            << csv_mm(p.depth_mean) << ',' << csv_mm(p.depth_max) << ',' << csv_mm(p.rms) << ','
            << csv_num(p.strain) << ',' << csv_num(p.strain_min) << '\n';
      }
      out << "all,," << std::to_string([&] {
        std::size_t n = 0;
        for (const auto& p : rep.profiles) n += p.samples;
        return n;
      }()) << ",,,"
          << s.folds << ',' << csv_mm(s.wavelength_mean) << ',' << csv_mm(s.wavelength_std) << ','
          << csv_mm(s.spectral_wavelength) << ',' << csv_mm(s.depth_mean) << ','
          << csv_mm(s.depth_max) << ',' << csv_mm(s.rms) << ',' << csv_num(s.strain) << ','
          << csv_num(s.strain_min) << '\n';
      write_text_atomically(csv, out.str());
      if (!quiet) std::printf("wrote %s\n", csv.c_str());
    }
    if (!json_path.empty()) {
      nlohmann::ordered_json j;
      j["results"] = results;
      j["surface"] = anim.name;
      j["frame"] = f;
      j["time_s"] = anim.times[f];
      j["voxel_size_mm"] = json_mm(h);
      j["edge_length_mm"] = json_mm(rep.edge_length);
      j["options"] = {{"up", std::string(1, ax[o.up])},
                      {"across", std::string(1, ax[o.across])},
                      {"along", std::string(1, along)},
                      {"profiles", o.profiles},
                      {"detrend_width_mm", o.detrend_width * kMm},
                      {"min_depth_mm", o.min_depth * kMm},
                      {"spacing_mm", rep.options.spacing * kMm},
                      {"min_facing", o.min_facing}};
      if (o.region) {
        std::vector<double> r;
        for (double v : *o.region) r.push_back(v * kMm);
        j["options"]["region_mm"] = r;
      }
      auto& summary = j["summary"] = {{"profiles_used", s.profiles_used},
                                      {"folds", s.folds},
                                      {"folds_mean", s.folds_mean},
                                      {"wavelength_mean_mm", json_mm(s.wavelength_mean)},
                                      {"wavelength_std_mm", json_mm(s.wavelength_std)},
                                      {"wavelength_count", s.wavelength_count}};
      put_shared_figures(summary, s);
      summary["detrend_retention"] = json_num(s.retention);
      summary["layer_locking"] = json_num(s.layer_locking);
      summary["layers_spanned"] = json_num(s.layers_spanned);
      summary["layer_period_mm"] = json_mm(s.layer_period);
      auto& arr = j["profiles"] = nlohmann::ordered_json::array();
      for (const auto& p : rep.profiles) {
        nlohmann::ordered_json folds = nlohmann::ordered_json::array();
        for (const auto& fo : p.folds) {
          folds.push_back({{"s_mm", fo.s * kMm},
                           {"arc_mm", fo.arc * kMm},
                           {"depth_mm", fo.depth * kMm},
                           {"height_mm", fo.height * kMm},
                           {"layer_phase", json_num(fo.layer_phase)},
                           {"layer_period_mm", json_mm(fo.layer_period)}});
        }
        nlohmann::ordered_json row = {{"across_mm", p.across * kMm},
                                      {"samples", p.samples},
                                      {"length_rest_mm", p.length_rest * kMm},
                                      {"length_mm", p.length * kMm},
                                      {"folds", p.folds.size()},
                                      {"wavelength_mean_mm", json_mm(p.wavelength_mean)},
                                      {"wavelength_std_mm", json_mm(p.wavelength_std)}};
        put_shared_figures(row, p);
        row["fold_list"] = std::move(folds);
        arr.push_back(std::move(row));
      }
      std::ostringstream out;
      out << j.dump(2) << '\n';
      write_text_atomically(json_path, out.str());
      if (!quiet) std::printf("wrote %s\n", json_path.c_str());
    }
    if (!trace.empty()) {
      std::ostringstream out;
      out << "profile,across_mm,s_mm,arc_mm,residual_mm,local_strain,x_mm,y_mm,z_mm\n";
      for (std::size_t k = 0; k < rep.profiles.size(); ++k) {
        const auto& p = rep.profiles[k];
        for (std::size_t i = 0; i < p.samples; ++i) {
          out << k << ',' << csv_mm(p.across) << ',' << csv_mm(p.s[i]) << ',' << csv_mm(p.arc[i])
              << ',' << csv_mm(p.residual[i]) << ',' << csv_num(p.local_strain[i]) << ','
              << csv_mm(p.rest[3 * i]) << ',' << csv_mm(p.rest[3 * i + 1]) << ','
              << csv_mm(p.rest[3 * i + 2]) << '\n';
        }
      }
      write_text_atomically(trace, out.str());
      if (!quiet) std::printf("wrote %s\n", trace.c_str());
    }
    return tool::kExitOk;
  });
}
