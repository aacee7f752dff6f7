#include "sinew/voxelizer/voxelize.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/progress.hpp"
#include "sinew/common/version.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/sha256.hpp"
#include "sinew/voxelizer/constraint_checks.hpp"
#include "sinew/voxelizer/constraints.hpp"
#include "sinew/voxelizer/crop.hpp"
#include "sinew/voxelizer/embedding.hpp"
#include "sinew/voxelizer/fibres.hpp"
#include "sinew/voxelizer/fractions.hpp"
#include "sinew/voxelizer/jaw.hpp"
#include "sinew/voxelizer/mesh_bounds.hpp"
#include "sinew/voxelizer/mesh_source.hpp"
#include "sinew/voxelizer/muscle_ends.hpp"
#include "sinew/voxelizer/offset.hpp"
#include "sinew/voxelizer/primitives.hpp"
#include "sinew/voxelizer/rig.hpp"
#include "sinew/voxelizer/self_intersection.hpp"

namespace sinew::voxelizer {

double available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  double value = 0;
  std::string unit;
  while (in >> key >> value >> unit) {
    if (key == "MemAvailable:") return value * 1024.0;
  }
  return 0;
}

double peak_rss_bytes() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream is(line.substr(6));
      double kb = 0;
      is >> kb;
      return kb * 1024.0;
    }
  }
  return 0;
}

namespace {

using Clock = std::chrono::steady_clock;

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

class StageTimer {
 public:
  explicit StageTimer(Summary& s) : s_(s), start_(Clock::now()), cpu_(process_cpu_seconds()) {}
  void end(const std::string& name) {
    const auto now = Clock::now();
    const double cpu = process_cpu_seconds();
    s_.stages.push_back(
        {name, std::chrono::duration<double>(now - start_).count(), cpu - cpu_, peak_rss_bytes()});
    log::debug("stage {}: {:.3f} s", name, s_.stages.back().seconds);
    start_ = now;
    cpu_ = cpu;
  }

 private:
  Summary& s_;
  Clock::time_point start_;
  double cpu_;
};

struct LoadedMesh {
  TriangleMesh mesh;
  MeshDiagnostics diagnostics;
  std::unique_ptr<SignedField> field;
};

formats::Point to_point(const Vec3d& v) {
  return {v.x, v.y, v.z};
}

class Pipeline {
 public:
  Pipeline(const Spec& spec, const VoxelizeOptions& options) : spec_(spec), options_(options) {}

  VoxelizeResult run() {
    StageTimer timer(result_.summary);
    auto& summary = result_.summary;
    summary.threads = omp_get_max_threads();
    summary.output = spec_.output.string();

    load_all();
    timer.end("load");
    choose_resolution();
    index_all();
    timer.end("index");
    check_inner_inside_outer();
    timer.end("checks");
    estimate_memory();
    timer.end("estimate");
    compute();
    timer.end("fractions");
    build_model();
    timer.end("model");
    fibres();
    timer.end("fibres");
    constraints();
    for (const auto& f : free_muscle_ends(result_.model, muscle_ends_, outer_.mesh, 2 * h_))
      warn(free_muscle_end_warning(f));
    timer.end("constraints");
    surfaces();
    timer.end("embedding");
    provenance();
    return std::move(result_);
  }

 private:
  const Spec& spec_;
  const VoxelizeOptions& options_;
  VoxelizeResult result_;
  double h_ = 0;
  std::optional<JawGeometry> jaw_;  // rig.jaw
  // The lattice coordinates of the voxels the jaw's cut removed (for the lips' contact pairs).
  std::vector<std::array<std::int32_t, 3>> jaw_cut_;
  // Each harmonic muscle's origin and insertion voxels (fibres()), for free_muscle_ends.
  std::vector<MuscleEnd> muscle_ends_;

  LoadedMesh outer_;
  std::optional<LoadedMesh> inner_;
  std::optional<LoadedMesh> glide_;  // spec.glide_depth: the surface below the inner one
  std::vector<LoadedMesh> muscles_, tendons_;
  std::vector<std::optional<LoadedMesh>> regions_;
  std::map<std::string, LoadedMesh> extra_;  // meshes referenced by field path
  std::deque<TriangleMesh> cropped_;         // visual surfaces cut to the crop region
  std::vector<std::string> input_files_;

  FractionProblem problem_;
  VoxelFractions fractions_;
  std::vector<int> label_material_;  // label -> index into model.materials (-1 for 0)
  std::vector<int> label_muscle_;    // label -> index into spec.muscles or -1
  std::vector<std::string> used_materials_;

  void warn(const std::string& w) {
    log::warn("{}", w);
    result_.summary.warnings.push_back(w);
  }

  // A bound of mesh_bounds.hpp: an error naming the mesh, or with --force a warning.
  void bound(const std::string& file, const std::string& field, const std::string& what,
             const std::optional<std::string>& problem) {
    if (!problem) return;
    if (!options_.force) throw GeometryError(file, field, *problem);
    warn(what + ": " + *problem + "; going on (--force)");
  }

  // body: the mesh bounds tissue (outer, inner, muscles, tendons, regions), so it must enclose a
  // positive volume; selector and visual surfaces may be open sheets.
  LoadedMesh load(const MeshSource& src, const std::string& role, bool body = true) {
    LoadedMesh lm;
    lm.mesh = load_mesh_source(src);
    if (src.kind == MeshSource::Kind::file) input_files_.push_back(src.path.string());
    const std::string what = role + " (" + src.describe() + ")";
    bound(src.describe(), src.field, what, extent_problem(lm.mesh, spec_.units));
    for (std::size_t v = 0; v < lm.mesh.vertices.size(); ++v) {
      const auto& p = lm.mesh.vertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        throw GeometryError(src.describe(), src.field,
                            "vertex coordinates are not finite (NaN or "
                            "infinite)")
            .at(static_cast<std::int64_t>(v));
      }
    }
    if (lm.mesh.triangles.empty())
      throw GeometryError(src.describe(), src.field, "the mesh is empty");
    lm.diagnostics = clean_mesh(lm.mesh, spec_.weld_tolerance);
    if (lm.mesh.triangles.empty()) {
      throw GeometryError(src.describe(), src.field,
                          "the mesh has no triangles left after removing degenerate ones");
    }
    if (lm.diagnostics.closed && lm.diagnostics.inconsistently_oriented_edges == 0 &&
        lm.diagnostics.enclosed_volume < 0) {
      // A closed mesh oriented inward: the winding number would be -1 inside it.
      flip_orientation(lm.mesh);
      lm.diagnostics.enclosed_volume = -lm.diagnostics.enclosed_volume;
      warn(role + " (" + src.describe() + "): oriented inward; triangles flipped");
    }
    if (body) bound(src.describe(), src.field, what, volume_problem(lm.diagnostics, spec_.units));
    result_.summary.meshes.push_back({role, src.describe(), lm.diagnostics});
    const auto& d = lm.diagnostics;
    if (!d.closed) {
      warn(role + " (" + src.describe() + "): not closed (" + std::to_string(d.boundary_edges) +
           " boundary edges, " + std::to_string(d.non_manifold_edges) +
           " non-manifold edges); inside/outside from the winding number");
    }
    if (d.inconsistently_oriented_edges > 0) {
      warn(role + ": " + std::to_string(d.inconsistently_oriented_edges) +
           " inconsistently oriented edges");
    }
    return lm;
  }

  void load_all() {
    outer_ = load(spec_.outer, "outer");
    if (spec_.inner) inner_ = load(*spec_.inner, "inner");
    for (std::size_t i = 0; i < spec_.muscles.size(); ++i) {
      muscles_.push_back(load(spec_.muscles[i].mesh,
                              "muscles[" + std::to_string(i) + "] " + spec_.muscles[i].name));
    }
    for (std::size_t i = 0; i < spec_.tendons.size(); ++i) {
      tendons_.push_back(load(*spec_.tendons[i].mesh,
                              "tendons[" + std::to_string(i) + "] " + spec_.tendons[i].name));
    }
    for (std::size_t i = 0; i < spec_.regions.size(); ++i) {
      if (spec_.regions[i].mesh) {
        regions_.push_back(load(*spec_.regions[i].mesh,
                                "regions[" + std::to_string(i) + "] " + spec_.regions[i].name));
      } else {
        regions_.emplace_back();
      }
    }
    auto extra = [&](const SurfaceRef& r) {
      if (r.mesh && !extra_.count(r.field)) extra_.emplace(r.field, load(*r.mesh, r.field, false));
    };
    for (const auto& m : spec_.muscles) {
      if (m.fibres.origin.surface) extra(*m.fibres.origin.surface);
      if (m.fibres.insertion.surface) extra(*m.fibres.insertion.surface);
    }
    for (const auto& b : spec_.boundary)
      if (b.has_surface) extra(b.surface);
    for (const auto& s : spec_.node_sets)
      if (s.select.surface) extra(*s.select.surface);
    for (const auto& v : spec_.visual) extra(v.surface);
  }

  double volume_of(const LoadedMesh& m) const { return std::abs(m.diagnostics.enclosed_volume); }

  // Outer minus inner enclosed volume, at most skin area × tissue_thickness (m³).
  double tissue_volume_estimate() const {
    double v = volume_of(outer_) - (inner_ ? volume_of(*inner_) : 0.0);
    if (spec_.tissue_thickness) v = std::min(v, outer_.diagnostics.area * *spec_.tissue_thickness);
    return v;
  }

  void choose_resolution() {
    auto& s = result_.summary;
    if (spec_.voxel_size) {
      h_ = *spec_.voxel_size;
    } else {
      const double v = tissue_volume_estimate();
      if (!(v > 0)) {
        throw GeometryError(
            spec_.file.string(), "resolution.target_elements",
            "cannot derive a voxel size: the tissue volume estimate is not positive "
            "(give voxel_size instead)");
      }
      h_ = std::cbrt(v / static_cast<double>(*spec_.target_elements));
    }
    s.voxel_size = h_;
  }

  void make_field(LoadedMesh& m) {
    const auto& d = m.diagnostics;
    bool watertight = d.closed && d.non_manifold_edges == 0 &&
                      d.inconsistently_oriented_edges == 0 && d.enclosed_volume > 0;
    // A mesh folded over itself passes the tests above, but the pseudonormal sign is wrong near
    // the fold (whole blocks of voxels can be filled): the winding number decides there. The rig's
    // sheets fold where the skin is more curved than their depth (the Lee Perry-Smith scan's
    // frontalis above the nose).
    if (watertight && self_intersects(m.mesh)) {
      watertight = false;
      warn("mesh " + m.mesh.source +
           " intersects itself: inside and outside by the generalized winding number");
    }
    m.field = std::make_unique<SignedField>(m.mesh, watertight, d.boundary_edges == 0);
  }

  void index_all() {
    make_field(outer_);
    if (spec_.tissue_thickness) {
      // The inner surface the artist did not model: an inward offset of the skin.
      const double t = *spec_.tissue_thickness;
      LoadedMesh lm;
      // Offset grid: the model's voxel size (the surface is then as accurate as the voxels that
      // resolve it), finer for thin tissue.
      lm.mesh = inward_offset_surface(outer_.mesh, t, std::min(h_, t / 3));
      lm.mesh.source = "offset of outer by " + std::to_string(t) + " m";
      lm.diagnostics = clean_mesh(lm.mesh, 0.0);
      result_.summary.meshes.push_back({"inner (derived)", lm.mesh.source, lm.diagnostics});
      inner_ = std::move(lm);
    }
    if (inner_) make_field(*inner_);
    if (spec_.glide_depth) {
      // The glide surface lies glide_depth below the inner surface: an inward offset of the skin by
      // tissue_thickness + glide_depth when the inner surface is derived (so it follows the skin
      // as the derived skull does), else of the inner mesh itself.
      const double d = *spec_.glide_depth;
      const bool derived = spec_.tissue_thickness.has_value();
      const double depth = derived ? *spec_.tissue_thickness + d : d;
      LoadedMesh lm;
      lm.mesh =
          inward_offset_surface(derived ? outer_.mesh : inner_->mesh, depth, std::min(h_, d / 3));
      lm.mesh.source = "offset of " + std::string(derived ? "outer" : "inner") + " by " +
                       std::to_string(depth) + " m";
      lm.diagnostics = clean_mesh(lm.mesh, 0.0);
      result_.summary.meshes.push_back({"glide (derived)", lm.mesh.source, lm.diagnostics});
      glide_ = std::move(lm);
      make_field(*glide_);
    }
    for (auto& m : muscles_) make_field(m);
    for (auto& m : tendons_) make_field(m);
    for (auto& m : regions_)
      if (m) make_field(*m);
    for (auto& [k, m] : extra_) make_field(m);
  }

  const SignedField* named_surface(const SurfaceRef& ref) {
    if (ref.mesh) return extra_.at(ref.field).field.get();
    if (ref.name == "outer") return outer_.field.get();
    if (ref.name == "inner") return inner_ ? inner_->field.get() : nullptr;
    if (ref.name == "glide") return glide_ ? glide_->field.get() : nullptr;
    for (std::size_t i = 0; i < spec_.muscles.size(); ++i)
      if (spec_.muscles[i].name == ref.name) return muscles_[i].field.get();
    for (std::size_t i = 0; i < spec_.tendons.size(); ++i)
      if (spec_.tendons[i].name == ref.name) return tendons_[i].field.get();
    for (std::size_t i = 0; i < spec_.regions.size(); ++i)
      if (spec_.regions[i].name == ref.name && regions_[i]) return regions_[i]->field.get();
    throw ConfigError(spec_.file.string(), ref.field, "unknown surface '" + ref.name + "'");
  }

  const TriangleMesh& named_mesh(const SurfaceRef& ref) {
    if (ref.mesh) return extra_.at(ref.field).mesh;
    if (ref.name == "outer") return outer_.mesh;
    if (ref.name == "inner") return inner_->mesh;
    if (ref.name == "glide") return glide_->mesh;
    return named_surface(ref)->mesh();
  }

  void check_inner_inside_outer() {
    if (!inner_ || spec_.tissue_thickness) return;
    std::vector<double> w;
    outer_.field->winding().evaluate(inner_->mesh.vertices, w);
    std::int64_t outside = 0;
    for (double x : w) outside += x < 0.5 ? 1 : 0;
    const double frac = static_cast<double>(outside) / static_cast<double>(w.size());
    if (frac > 0.1) {
      throw GeometryError(spec_.inner->describe(), "inner",
                          "the inner surface (skull) is not inside the outer surface (skin): " +
                              std::to_string(outside) + " of " + std::to_string(w.size()) +
                              " vertices lie outside it");
    }
    if (outside > 0) {
      warn("inner: " + std::to_string(outside) + " of " + std::to_string(w.size()) +
           " vertices lie outside the outer surface");
    }
  }

  std::array<std::int32_t, 3> dims_;
  Vec3d origin_;

  void estimate_memory() {
    auto& s = result_.summary;
    const BoundingBox b =
        spec_.crop ? crop_bounds(*spec_.crop, outer_.field->bounds(), spec_.file.string())
                   : outer_.field->bounds();
    double nvox = 1;
    for (int d = 0; d < 3; ++d) {
      const double n = std::ceil((b.hi[d] - b.lo[d]) / h_) + 1;
      nvox *= n;
      if (n > 2e9) {
        throw ResourceError(spec_.file.string(), "resolution",
                            "voxel size " + std::to_string(h_) + " m gives " + std::to_string(n) +
                                " voxels along one axis (limit 2e9)");
      }
      dims_[static_cast<std::size_t>(d)] = static_cast<std::int32_t>(n);
      origin_[d] = 0.5 * (b.lo[d] + b.hi[d]) - 0.5 * n * h_;
    }
    // Elements: the tissue volume plus a shell of boundary voxels, at most the whole grid.
    double tissue = std::max(volume_of(outer_), 0.0);
    const double shell = 2.0 * outer_.diagnostics.area / (h_ * h_);
    double elements = std::min(nvox, tissue / (h_ * h_ * h_) + shell);
    if (!std::isfinite(elements)) elements = nvox;
    std::int64_t triangles = 0;
    for (const auto& m : s.meshes) triangles += m.diagnostics.triangles;
    // Bytes: ~400 per element (lattice, nodes, CSR fractions, topology sort buffers, results),
    // ~600 per triangle (mesh copies, CGAL tree, winding-number tree), 64 MiB base.
    const double estimate =
        400.0 * elements + 600.0 * static_cast<double>(triangles) + 64.0 * 1024 * 1024;
    const double available =
        options_.memory_limit_bytes ? *options_.memory_limit_bytes : available_memory_bytes();
    s.memory_estimate_bytes = estimate;
    s.memory_available_bytes = available;
    if (available > 0 && estimate > available) {
      throw ResourceError(spec_.file.string(), "resolution",
                          "memory estimate " + format_bytes(estimate) + " (about " +
                              std::to_string(static_cast<long long>(elements)) +
                              " elements at voxel size " + std::to_string(h_) +
                              " m) exceeds the available memory " + format_bytes(available) +
                              "; choose a larger voxel size or fewer target elements");
    }
    // After the memory check, whose message says more about an absurd count; of the tissue, not
    // the whole inside of the skin (a face's 8 mm of tissue on a bust is a fifth of it).
    const double expected =
        std::min(nvox, std::max(tissue_volume_estimate(), 0.0) / (h_ * h_ * h_) + shell);
    bound(spec_.file.string(), "resolution", "resolution",
          element_count_problem(expected, spec_.max_elements.value_or(kDefaultMaxElements), h_,
                                spec_.units));
    s.dims = dims_;
  }

  int material_index(const std::string& name) {
    const auto it = std::find(used_materials_.begin(), used_materials_.end(), name);
    return static_cast<int>(it - used_materials_.begin());
  }

  void compute() {
    // Materials actually used, in the table's order.
    std::vector<std::string> wanted;
    for (const auto& l : spec_.layers) wanted.push_back(l.material);
    for (const auto& m : spec_.muscles) wanted.push_back(m.material);
    for (const auto& t : spec_.tendons) wanted.push_back(t.material);
    for (const auto& r : spec_.regions) wanted.push_back(r.material);
    for (const auto& m : spec_.materials) {
      if (std::find(wanted.begin(), wanted.end(), m.name) != wanted.end()) {
        used_materials_.push_back(m.name);
      }
    }

    auto& p = problem_;
    p.outer = outer_.field.get();
    p.inner = inner_ ? inner_->field.get() : nullptr;
    p.layer_count = static_cast<int>(spec_.layers.size());
    double depth = 0;
    label_material_ = {-1};
    label_muscle_ = {-1};
    for (std::size_t i = 0; i < spec_.layers.size(); ++i) {
      if (spec_.layers[i].thickness) {
        depth += *spec_.layers[i].thickness;
        p.layer_bottoms.push_back(depth);
      }
      label_material_.push_back(material_index(spec_.layers[i].material));
      label_muscle_.push_back(-1);
    }
    int label = p.layer_count + 1;
    for (std::size_t i = 0; i < spec_.regions.size(); ++i) {
      FractionProblem::Body b;
      if (regions_[i]) b.field = regions_[i]->field.get();
      b.box = spec_.regions[i].box;
      b.label = label++;
      p.bodies.push_back(b);
      label_material_.push_back(material_index(spec_.regions[i].material));
      label_muscle_.push_back(-1);
    }
    for (std::size_t i = 0; i < spec_.muscles.size(); ++i) {
      p.bodies.push_back({muscles_[i].field.get(), std::nullopt, label++});
      label_material_.push_back(material_index(spec_.muscles[i].material));
      label_muscle_.push_back(static_cast<int>(i));
    }
    for (std::size_t i = 0; i < spec_.tendons.size(); ++i) {
      p.bodies.push_back({tendons_[i].field.get(), std::nullopt, label++});
      label_material_.push_back(material_index(spec_.tendons[i].material));
      label_muscle_.push_back(-1);
    }
    p.label_count = label;
    p.grid.voxel_size = h_;
    p.grid.dims = dims_;
    p.grid.origin = to_point(origin_);
    p.max_subdivision = spec_.max_subdivision;
    p.min_tissue_fraction = spec_.min_fraction;

    ProgressOptions po;
    po.quiet = !options_.progress;
    po.unit = "blocks";
    std::int64_t blocks = 1;
    for (int d = 0; d < 3; ++d) blocks *= (dims_[static_cast<std::size_t>(d)] + 7) / 8;
    ProgressReporter bar("fractions", blocks, po);
    fractions_ = compute_fractions(p, [&](std::int64_t done, std::int64_t) { bar.update(done); });
    bar.finish();
    result_.summary.field_evaluations = fractions_.field_evaluations;
    if (spec_.crop)
      result_.summary.cropped_voxels = crop_fractions(fractions_, p.grid, *spec_.crop);
    if (spec_.rig && spec_.rig->jaw) cut_for_the_jaw(p.grid);
    if (fractions_.voxels.empty()) {
      throw GeometryError(spec_.outer.describe(), "outer",
                          "no tissue at this resolution (voxel size " + std::to_string(h_) +
                              " m): nothing lies inside the outer surface and outside the inner "
                              "one");
    }
  }

  void build_model() {
    auto& m = result_.model;
    auto& s = result_.summary;
    m.grid = problem_.grid;
    m.element_lattice = fractions_.voxels;
    formats::build_lattice_topology(m);
    for (const auto& name : used_materials_) {
      const MaterialSpec* ms = spec_.find_material(name);
      m.materials.push_back(formats::make_neo_hookean_material(ms->name, ms->youngs_modulus,
                                                               ms->poisson_ratio, ms->density));
    }
    const std::size_t ne = fractions_.voxels.size();
    const std::size_t nmat = m.materials.size();
    m.muscles.resize(spec_.muscles.size());
    for (std::size_t i = 0; i < spec_.muscles.size(); ++i) {
      const auto& ms = spec_.muscles[i];
      auto& mu = m.muscles[i];
      mu.name = ms.name;
      mu.material = material_index(ms.material);
      mu.reference_stress = ms.reference_stress;
      mu.optimal_stretch = ms.optimal_stretch;
      mu.passive_p1 = ms.passive_p1;
      mu.passive_p2 = ms.passive_p2;
      mu.passive_linear_stretch = ms.passive_linear_stretch;
    }
    std::vector<double> per_material(nmat), material_volume(nmat, 0.0);
    std::vector<double> muscle_volume(spec_.muscles.size(), 0.0);
    const double v0 = h_ * h_ * h_;
    m.material_offsets.reserve(ne + 1);
    m.material_offsets.push_back(0);
    for (std::size_t e = 0; e < ne; ++e) {
      std::fill(per_material.begin(), per_material.end(), 0.0);
      for (auto q = fractions_.offsets[e]; q < fractions_.offsets[e + 1]; ++q) {
        const auto lab = static_cast<std::size_t>(fractions_.labels[static_cast<std::size_t>(q)]);
        const double f = fractions_.fractions[static_cast<std::size_t>(q)];
        per_material[static_cast<std::size_t>(label_material_[lab])] += f;
        if (label_muscle_[lab] >= 0) {
          auto& mu = m.muscles[static_cast<std::size_t>(label_muscle_[lab])];
          mu.elements.push_back(static_cast<formats::Index>(e));
          mu.fractions.push_back(f);
          muscle_volume[static_cast<std::size_t>(label_muscle_[lab])] += f * v0;
        }
      }
      for (std::size_t k = 0; k < nmat; ++k) {
        if (per_material[k] > 0) {
          m.material_ids.push_back(static_cast<formats::Index>(k));
          m.material_fractions.push_back(std::min(per_material[k], 1.0));
          material_volume[k] += per_material[k] * v0;
          s.tissue_volume += per_material[k] * v0;
        }
      }
      m.material_offsets.push_back(static_cast<formats::Offset>(m.material_ids.size()));
    }
    for (std::size_t k = 0; k < nmat; ++k) {
      s.material_volumes.push_back({m.materials[k].name, material_volume[k]});
    }
    for (std::size_t i = 0; i < spec_.muscles.size(); ++i) {
      s.muscle_volumes.push_back({spec_.muscles[i].name, muscle_volume[i]});
      const double mesh_volume = volume_of(muscles_[i]);
      const double ratio = mesh_volume > 0 ? muscle_volume[i] / mesh_volume : 0.0;
      if (muscle_volume[i] <= 0 || ratio < 0.5) {
        throw GeometryError(spec_.muscles[i].mesh.describe(),
                            "muscles[" + std::to_string(i) + "] " + spec_.muscles[i].name,
                            "the muscle lies outside the tissue: only " +
                                std::to_string(100.0 * ratio) +
                                "% of its enclosed volume is inside the outer surface and "
                                "outside the inner one");
      }
      if (ratio < 0.95) {
        warn("muscle " + spec_.muscles[i].name + ": only " + std::to_string(100.0 * ratio) +
             "% of its volume lies in the tissue");
      }
    }
    s.elements = static_cast<std::int64_t>(ne);
    s.nodes = static_cast<std::int64_t>(m.node_count());
    // Release the fraction buffers we no longer need.
    fractions_.labels = {};
    fractions_.fractions = {};
    fractions_.offsets = {};
  }

  Vec3d element_centre(formats::Index e) const {
    const auto& l = result_.model.element_lattice[static_cast<std::size_t>(e)];
    return {origin_.x + h_ * (l[0] + 0.5), origin_.y + h_ * (l[1] + 0.5),
            origin_.z + h_ * (l[2] + 0.5)};
  }

  bool selects(const Selector& sel, const SignedField* surface, const Vec3d& p) const {
    if (sel.box && !sel.box->contains(p)) return false;
    if (surface && surface->distance().distance(p) > sel.distance) return false;
    return true;
  }

  void fibres() {
    auto& m = result_.model;
    for (std::size_t i = 0; i < spec_.muscles.size(); ++i) {
      const auto& ms = spec_.muscles[i];
      auto& mu = m.muscles[i];
      const std::size_t n = mu.elements.size();
      if (ms.fibres.kind == FibreSpec::Kind::constant) {
        mu.fibres.assign(n, to_point(ms.fibres.direction));
        continue;
      }
      if (ms.fibres.kind == FibreSpec::Kind::circumferential) {
        mu.fibres.resize(n);
        for (std::size_t j = 0; j < n; ++j) {
          const auto& f = ms.fibres;
          mu.fibres[j] =
              to_point(circumferential_fibre(element_centre(mu.elements[j]), f.centre, f.axis,
                                             f.major, f.radius_major, f.radius_minor));
        }
        continue;
      }
      const SignedField* so =
          ms.fibres.origin.surface ? named_surface(*ms.fibres.origin.surface) : nullptr;
      const SignedField* si =
          ms.fibres.insertion.surface ? named_surface(*ms.fibres.insertion.surface) : nullptr;
      std::vector<formats::Lattice> voxels(n);
      std::vector<DirichletTag> tags(n, DirichletTag::free);
#pragma omp parallel for schedule(dynamic, 256)
      for (std::int64_t j = 0; j < static_cast<std::int64_t>(n); ++j) {
        const auto e = mu.elements[static_cast<std::size_t>(j)];
        voxels[static_cast<std::size_t>(j)] = m.element_lattice[static_cast<std::size_t>(e)];
        const Vec3d c = element_centre(e);
        if (selects(ms.fibres.origin, so, c)) {
          tags[static_cast<std::size_t>(j)] = DirichletTag::origin;
        } else if (selects(ms.fibres.insertion, si, c)) {
          tags[static_cast<std::size_t>(j)] = DirichletTag::insertion;
        }
      }
      MuscleEnd origin{ms.name, "origin", {}}, insertion{ms.name, "insertion", {}};
      for (std::size_t j = 0; j < n; ++j) {
        if (tags[j] == DirichletTag::origin) origin.elements.push_back(mu.elements[j]);
        if (tags[j] == DirichletTag::insertion) insertion.elements.push_back(mu.elements[j]);
      }
      muscle_ends_.push_back(std::move(origin));
      muscle_ends_.push_back(std::move(insertion));
      const auto hf = harmonic_fibres(voxels, tags, "muscles[" + std::to_string(i) + "] " + ms.name,
                                      mu.fractions);
      mu.fibres.resize(n);
      for (std::size_t j = 0; j < n; ++j) mu.fibres[j] = to_point(hf.fibres[j]);
      if (hf.fallback > 0) {
        warn("muscle " + ms.name + ": " + std::to_string(hf.fallback) +
             " voxels without a harmonic gradient got the origin-to-insertion axis");
      }
    }
  }

  std::map<std::string, formats::Index> sliding_surface_index_;

  formats::Index add_sliding_surface(const SurfaceRef& ref) {
    const std::string key = ref.mesh ? ref.field : ref.name;
    const auto it = sliding_surface_index_.find(key);
    if (it != sliding_surface_index_.end()) return it->second;
    const TriangleMesh& mesh = named_mesh(ref);
    formats::Surface s;
    s.name = ref.mesh ? "sliding_" + std::to_string(sliding_surface_index_.size()) : ref.name;
    s.role = formats::SurfaceRole::sliding;
    for (const auto& v : mesh.vertices) s.vertices.push_back(to_point(v));
    for (const auto& t : mesh.triangles) s.triangles.push_back({t[0], t[1], t[2]});
    result_.model.surfaces.push_back(std::move(s));
    const auto idx = static_cast<formats::Index>(result_.model.surfaces.size() - 1);
    sliding_surface_index_.emplace(key, idx);
    return idx;
  }

  void constraints() {
    auto& m = result_.model;
    auto& s = result_.summary;
    std::vector<BoundaryCondition> conds;
    for (const auto& b : spec_.boundary) {
      BoundaryCondition c;
      c.kind = b.kind;
      c.inside = b.inside;
      c.within = b.within;
      c.box = b.box;
      if (b.has_surface) {
        c.surface = named_surface(b.surface);
        if (!c.surface) {
          throw ConfigError(spec_.file.string(), b.field + ".surface",
                            "the inner surface is named but the spec has neither inner nor "
                            "tissue_thickness");
        }
        if (b.kind == BoundarySpec::Kind::sliding) c.surface_index = add_sliding_surface(b.surface);
      }
      conds.push_back(c);
    }
    if (!conds.empty()) {
      auto r = bind_constraints(m, conds);
      const ConstraintCheck check = check_constraints(m, conds, spec_.boundary, r);
      if (!check.error.empty()) throw ConfigError(spec_.file.string(), check.field, check.error);
      for (const auto& w : check.warnings) warn(w);
      m.rigid_nodes = std::move(r.rigid);
      m.sliding = std::move(r.sliding);
      for (std::size_t i = 0; i < conds.size(); ++i) {
        if (r.per_condition[i] == 0) warn(spec_.boundary[i].field + ": selects no node");
      }
    }
    if (jaw_) split_the_jaw();
    if (spec_.crop) hold_the_cut();
    if (m.jaw) {
      std::vector<formats::Index> held = m.rigid_nodes;
      held.insert(held.end(), m.jaw->nodes.begin(), m.jaw->nodes.end());
      std::sort(held.begin(), held.end());
      m.jaw->lip_pairs = lip_pairs(*jaw_, m, jaw_cut_, held);
      result_.summary.lip_pairs = static_cast<std::int64_t>(m.jaw->lip_pairs.size());
    }
    s.rigid_nodes = static_cast<std::int64_t>(m.rigid_nodes.size());
    s.jaw_nodes = m.jaw ? static_cast<std::int64_t>(m.jaw->nodes.size()) : 0;
    s.sliding_nodes = static_cast<std::int64_t>(m.sliding.size());
    for (const auto& ns : spec_.node_sets) {
      const SignedField* surf = ns.select.surface ? named_surface(*ns.select.surface) : nullptr;
      auto set = select_nodes(m, ns.name, ns.select.box, surf, ns.select.distance);
      if (set.ids.empty()) warn("node set " + ns.name + " is empty");
      s.node_sets.emplace_back(ns.name, static_cast<std::int64_t>(set.ids.size()));
      m.node_sets.push_back(std::move(set));
    }
  }

  // The jaw (rig.jaw, jaw.hpp): its geometry from the landmarks, and the voxels between the lips
  // and along the teeth removed so that the mouth can open.
  void cut_for_the_jaw(const formats::VoxelGrid& grid) {
    if (!inner_) {
      throw ConfigError(spec_.file.string(), spec_.rig->field + ".jaw",
                        "the jaw is cut from the skull: give the spec an `inner` surface (the "
                        "skull)");
    }
    jaw_ = jaw_geometry(read_landmarks(spec_.rig->landmarks));
    const SignedField& skull = *inner_->field;
    const SignedField& skin = *outer_.field;
    result_.summary.jaw_cut_voxels = drop_voxels(fractions_, grid, [&](const Vec3d& c) {
      const bool cut = near_occlusal_plane(*jaw_, c, h_) &&
                       in_jaw_cut(*jaw_, c, h_, skull(c).value, skin(c).value);
      if (cut) {
        std::array<std::int32_t, 3> v{};
        for (int k = 0; k < 3; ++k)
          v[k] = static_cast<std::int32_t>(std::floor((c[k] - grid.origin[k]) / grid.voxel_size));
        jaw_cut_.push_back(v);
      }
      return cut;
    });
  }

  // The mandible: the held nodes of the skull in its region (jaw.hpp) leave the rigid nodes.
  void split_the_jaw() {
    auto& m = result_.model;
    formats::Jaw jaw;
    std::vector<formats::Index> rigid;
    for (const auto nd : m.rigid_nodes) {
      const auto p = m.node_position(nd);
      (in_mandible(*jaw_, {p[0], p[1], p[2]}) ? jaw.nodes : rigid).push_back(nd);
    }
    if (jaw.nodes.empty()) {
      throw GeometryError(spec_.file.string(), spec_.rig->field + ".jaw",
                          "no held node of the skull lies in the mandible's region (below the "
                          "lips, in front of the tragi): check the landmarks and the skull, and "
                          "that a boundary condition holds the skull (rigid, inside: true)");
    }
    m.rigid_nodes = std::move(rigid);
    jaw.pivot = to_point(jaw_->pivot);
    jaw.axis = to_point(jaw_->axis);
    jaw.forward = to_point(jaw_->forward);
    jaw.incisal = to_point(jaw_->incisal);
    m.jaw = std::move(jaw);
  }

  // The nodes on the crop's cut are held rigid, whatever the boundary conditions bound them to.
  void hold_the_cut() {
    auto& m = result_.model;
    const auto cut = cut_nodes(m, *spec_.crop);
    result_.summary.cut_nodes = static_cast<std::int64_t>(cut.size());
    std::vector<formats::Index> rigid;
    std::set_union(m.rigid_nodes.begin(), m.rigid_nodes.end(), cut.begin(), cut.end(),
                   std::back_inserter(rigid));
    m.rigid_nodes = std::move(rigid);
    std::erase_if(m.sliding, [&](const formats::SlidingBinding& b) {
      return std::binary_search(cut.begin(), cut.end(), b.node);
    });
    if (m.jaw) {
      std::erase_if(m.jaw->nodes, [&](formats::Index nd) {
        return std::binary_search(cut.begin(), cut.end(), nd);
      });
      if (m.jaw->nodes.empty()) m.jaw.reset();
    }
  }

  void surfaces() {
    auto& m = result_.model;
    auto& s = result_.summary;
    for (const auto& v : spec_.visual) {
      const TriangleMesh& mesh =
          spec_.crop ? cropped_.emplace_back(crop_mesh(named_mesh(v.surface), *spec_.crop))
                     : named_mesh(v.surface);
      if (mesh.triangles.empty())
        throw GeometryError(spec_.file.string(), v.surface.field,
                            "visual surface " + v.name + " has no triangle inside the crop region");
      formats::Surface surf;
      surf.name = v.name;
      surf.role = formats::SurfaceRole::visual;
      for (const auto& p : mesh.vertices) surf.vertices.push_back(to_point(p));
      for (const auto& t : mesh.triangles) surf.triangles.push_back({t[0], t[1], t[2]});
      auto uvs = indexed_uvs(mesh);
      surf.uvs = std::move(uvs.uvs);
      surf.uv_triangles = std::move(uvs.triangles);
      auto emb = embed_points(m, surf.vertices);
      surf.embedding_element = std::move(emb.element);
      surf.embedding_local = std::move(emb.local);
      s.embedded_vertices += static_cast<std::int64_t>(surf.vertices.size());
      s.embedding_outside += emb.outside;
      s.embedding_max_outside_distance =
          std::max(s.embedding_max_outside_distance, emb.max_outside_distance);
      if (emb.outside > 0) {
        warn("visual surface " + v.name + ": " + std::to_string(emb.outside) +
             " vertices lie in no element; bound to the nearest one (up to " +
             std::to_string(emb.max_outside_distance) + " m away)");
      }
      m.surfaces.push_back(std::move(surf));
    }
  }

  void provenance() {
    auto& p = result_.model.provenance;
    p.tool = "sinew-voxelize";
    p.tool_version = sinew::kVersion;
    p.created = formats::current_utc_iso8601();
    std::vector<std::string> files;
    if (!spec_.file.empty() && std::filesystem::exists(spec_.file))
      files.push_back(spec_.file.string());
    for (const auto& f : input_files_)
      if (std::find(files.begin(), files.end(), f) == files.end()) files.push_back(f);
    for (const auto& f : files) p.inputs.push_back({f, formats::sha256_file(f)});
    p.parameters_json = spec_to_json(spec_);
  }
};

}  // namespace

VoxelizeResult voxelize(const Spec& spec, const VoxelizeOptions& options) {
  const int previous = omp_get_max_threads();
  if (options.threads > 0) omp_set_num_threads(options.threads);
  try {
    // The rig's muscles are built first (they need the skin) and join the spec's own.
    std::optional<Spec> rigged;
    if (spec.rig) {
      rigged = spec;
      add_rig_muscles(*rigged);
    }
    Pipeline pipeline(rigged ? *rigged : spec, options);
    auto r = pipeline.run();
    if (options.threads > 0) omp_set_num_threads(previous);
    return r;
  } catch (...) {
    if (options.threads > 0) omp_set_num_threads(previous);
    throw;
  }
}

}  // namespace sinew::voxelizer
