// The procedural forehead (voxelizer/sinew/voxelizer/forehead.hpp, docs/forehead.md): closed,
// outward meshes; the skin 5–7 mm over the skull; ~1 mm muscle sheets inside the tissue;
// determinism and the committed meshes; the 2 mm spec voxelizes with everything a scene needs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/forehead.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"
#include "sinew/voxelizer/winding_number.hpp"

namespace sinew::voxelizer {
namespace {

const std::filesystem::path kSource = SINEW_SOURCE_DIR;

const ForeheadMeshes& meshes() {
  static const ForeheadMeshes m = make_forehead(ForeheadParams{});
  return m;
}

TEST(Forehead, ClosedMeshesAreWatertightAndOutward) {
  const auto& m = meshes();
  for (const TriangleMesh* mesh : {&m.skull, &m.skull_glide, &m.skull_glide_coarse, &m.skin,
                                   &m.frontalis_left, &m.frontalis_right, &m.galea}) {
    SCOPED_TRACE(mesh->source);
    const MeshDiagnostics d = describe_mesh(*mesh);
    EXPECT_TRUE(d.closed);
    EXPECT_EQ(d.boundary_edges, 0);
    EXPECT_EQ(d.non_manifold_edges, 0);
    EXPECT_EQ(d.inconsistently_oriented_edges, 0);
    EXPECT_EQ(d.components, 1);
    EXPECT_EQ(d.degenerate_triangles_removed, 0);
    EXPECT_GT(d.enclosed_volume, 0);  // outward: positive signed volume
    // Outward, checked locally too: a point just outside each triangle's centroid along its
    // normal has winding number ~0, just inside ~1.
    const WindingNumber w(*mesh);
    for (std::size_t t = 0; t < mesh->triangles.size(); t += 97) {
      const auto& tri = mesh->triangles[t];
      const Vec3d a = mesh->vertices[tri[0]], b = mesh->vertices[tri[1]],
                  c = mesh->vertices[tri[2]];
      const Vec3d n = cross(b - a, c - a);
      const Vec3d g = (1.0 / 3.0) * (a + b + c), u = (1e-3 / norm(n)) * n;
      EXPECT_LT(w(g + u), 0.5) << "triangle " << t;
      EXPECT_GT(w(g - u), 0.5) << "triangle " << t;
    }
  }
  // The visual skin surface is open but consistently oriented, one piece.
  const MeshDiagnostics s = describe_mesh(m.skin_surface);
  EXPECT_FALSE(s.closed);
  EXPECT_EQ(s.non_manifold_edges, 0);
  EXPECT_EQ(s.inconsistently_oriented_edges, 0);
  EXPECT_EQ(s.components, 1);
}

TEST(Forehead, SkinIsFiveToSevenMillimetresAboveTheSkullWithAForeheadsShape) {
  const auto& m = meshes();
  const DistanceQuery skull(m.skull);
  const WindingNumber inside_skull(m.skull);
  double lo = 1e9, hi = 0;
  for (std::size_t i = 0; i < m.skin_surface.vertices.size(); i += 3) {
    const Vec3d& v = m.skin_surface.vertices[i];
    const double d = skull.distance(v);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
    ASSERT_LT(inside_skull(v), 0.5);
  }
  EXPECT_GE(lo, 5.0);
  EXPECT_LE(hi, 7.0);
  EXPECT_GT(hi - lo, 1.0);  // the thickness varies: thicker at the brow
  // Size and curvature: ~120 mm wide at the brow, 60–70 mm from the brow to the top; curved
  // left-right (the temples lie well behind the glabella) and bottom-top (the top leans back).
  const ForeheadParams p;
  const ForeheadLandmarks l = forehead_landmarks(p);
  EXPECT_NEAR(l.width, 120, 5);
  const double brow_to_top = l.hi.y - l.brow_centre.y;
  EXPECT_GE(brow_to_top, 60);
  EXPECT_LE(brow_to_top, 80);
  const auto skin_at = [&p](double th, double ph) {
    return forehead_skull_point(p, th, ph) +
           forehead_thickness(p, th, ph) * forehead_skull_normal(p, th, ph);
  };
  EXPECT_GT(skin_at(0, p.brow_deg).z - skin_at(p.patch_half_angle_deg, p.brow_deg).z, 20);
  EXPECT_GT(skin_at(0, p.brow_deg).z - skin_at(0, p.patch_top_deg).z, 15);
}

TEST(Forehead, MuscleSheetsAreAboutOneMillimetreThickInsideTheDeepTissue) {
  const auto& m = meshes();
  const DistanceQuery skull(m.skull);
  const WindingNumber in_skin(m.skin), in_skull(m.skull);
  const ForeheadParams p;
  for (const TriangleMesh* sheet : {&m.frontalis_left, &m.frontalis_right, &m.galea}) {
    SCOPED_TRACE(sheet->source);
    for (const Vec3d& v : sheet->vertices) {
      ASSERT_GT(in_skin(v), 0.5);
      ASSERT_LT(in_skull(v), 0.5);
      // 1.1–2.1 mm above the skull: the deep tissue (0.02 mm: the 2 mm facets of the meshes).
      const double d = skull.distance(v);
      ASSERT_GE(d, p.muscle_height - 0.5 * p.muscle_thickness - 0.02);
      ASSERT_LE(d, p.muscle_height + 0.5 * p.muscle_thickness + 0.02);
    }
    // A thin closed sheet of thickness t has V ≈ t · A / 2 (A counts both faces, plus the rim).
    const MeshDiagnostics d = describe_mesh(*sheet);
    const double thickness = 2 * d.enclosed_volume / d.area;
    EXPECT_GT(thickness, 0.9);
    EXPECT_LT(thickness, 1.05);
  }
  // Left and right: mirror images on either side of the midline, their fibres' span vertical.
  for (const Vec3d& v : m.frontalis_left.vertices) ASSERT_LT(v.x, -1.5);
  for (const Vec3d& v : m.frontalis_right.vertices) ASSERT_GT(v.x, 1.5);
  const BoundingBox r = bounding_box(m.frontalis_right), g = bounding_box(m.galea);
  EXPECT_GT(r.hi.y - r.lo.y, 45);  // brow to galea
  EXPECT_LT(r.lo.y, 0);            // reaches down into the brow
  EXPECT_LT(g.lo.y, r.hi.y);       // the galea overlaps the muscles' upper ends
  EXPECT_GT(g.hi.y, r.hi.y + 20);  // and runs on up
}

TEST(Forehead, GlideSurfacesLieParallelUnderTheSkullAndReachBeyondThePatch) {
  // The specs' sliding surfaces: glide_depth (for h <= 1 mm) and glide_depth_coarse (h = 2 mm)
  // under the skull surface, so that every corner of an element the skull surface cuts (at most
  // sqrt(3) h deep) lies above them, and wide enough that points near the patch's rim find a top.
  const auto& m = meshes();
  const ForeheadParams p;
  struct Case {
    const TriangleMesh* mesh;
    double depth, corner;  // mm: the surface's depth, the deepest element corner it must cover
  };
  for (const Case& c : {Case{&m.skull_glide, p.glide_depth, std::sqrt(3.0) * 1.0},
                        Case{&m.skull_glide_coarse, p.glide_depth_coarse, std::sqrt(3.0) * 2.0}}) {
    SCOPED_TRACE(c.mesh->source);
    const DistanceQuery glide(*c.mesh);
    const WindingNumber in_glide(*c.mesh);
    for (std::size_t i = 0; i < m.skin_surface.vertices.size(); i += 97) {
      ASSERT_LT(in_glide(m.skin_surface.vertices[i]), 0.5);
    }
    for (double th : {-p.patch_half_angle_deg, 0.0, p.patch_half_angle_deg}) {
      for (double ph : {p.patch_bottom_deg, p.brow_deg, p.patch_top_deg}) {
        const Vec3d s = forehead_skull_point(p, th, ph), n = forehead_skull_normal(p, th, ph);
        // 0.1 mm: the glide meshes' 5 mm facets.
        EXPECT_NEAR(glide.distance(s), c.depth, 0.1) << th << " " << ph;
        const Vec3d deep = s - c.corner * n;
        EXPECT_LT(in_glide(deep), 0.5) << th << " " << ph;
        EXPECT_NEAR(glide.distance(deep), c.depth - c.corner, 0.1) << th << " " << ph;
      }
    }
  }
}

TEST(Forehead, DeterministicAndTheCommittedMeshesAreWhatTheGeneratorWrites) {
  const ForeheadMeshes again = make_forehead(ForeheadParams{});
  EXPECT_EQ(obj_text(again.skin, {}), obj_text(meshes().skin, {}));
  EXPECT_EQ(obj_text(again.frontalis_left, {}), obj_text(meshes().frontalis_left, {}));

  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("sinew-forehead-" + std::to_string(::getpid()));
  const auto written = write_forehead(ForeheadParams{}, dir);
  ASSERT_EQ(written.size(), forehead_file_names().size());
  const auto slurp = [](const std::filesystem::path& f) {
    std::ifstream in(f, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  const auto by_name = [](const std::string& name) -> const TriangleMesh& {
    const auto& m = meshes();
    if (name == "skull.obj") return m.skull;
    if (name == "skull_glide.obj") return m.skull_glide;
    if (name == "skull_glide_coarse.obj") return m.skull_glide_coarse;
    if (name == "skin.obj") return m.skin;
    if (name == "skin_surface.obj") return m.skin_surface;
    if (name == "frontalis_left.obj") return m.frontalis_left;
    if (name == "frontalis_right.obj") return m.frontalis_right;
    return m.galea;
  };
  for (const auto& name : forehead_file_names()) {
    SCOPED_TRACE(name);
    const auto committed = kSource / "data" / "meshes" / "forehead" / name;
    ASSERT_TRUE(std::filesystem::exists(committed)) << committed;
    const std::string a = slurp(dir / name), b = slurp(committed);
    EXPECT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << "data/meshes/forehead/" << name
                        << " differs from what sinew-forehead writes: regenerate it with "
                           "`sinew-forehead -o data/meshes/forehead`";
    // The written OBJ reads back as the same mesh (to the 0.001 mm of the text).
    const TriangleMesh back = load_mesh(dir / name, {LengthUnit::mm, 1, {0, 0, 0}, {0, 0, 0}});
    EXPECT_EQ(back.triangles.size(), by_name(name).triangles.size());
  }
  std::filesystem::remove_all(dir);
}

TEST(Forehead, RejectsBadParameters) {
  ForeheadParams p;
  p.spacing = 0;
  EXPECT_THROW(make_forehead(p), ConfigError);
  p = {};
  p.muscle_height = 6;  // above the skin
  EXPECT_THROW(make_forehead(p), ConfigError);
  p = {};
  p.muscle_top_deg = 60;  // beyond the patch
  EXPECT_THROW(make_forehead(p), ConfigError);
  p = {};
  p.skull_cap_depth = 1;  // the skin's bottom would poke out of the skull cap
  EXPECT_THROW(make_forehead(p), ConfigError);
}

TEST(Forehead, TwoMillimetreSpecVoxelizesWithMusclesTendonSlidingAndRigidNodes) {
  const Spec spec = read_spec(kSource / "data" / "specs" / "forehead_2mm.yaml");
  const VoxelizeResult r = voxelize(spec);
  const formats::Model& model = r.model;
  EXPECT_GT(r.summary.elements, 9000);
  EXPECT_LT(r.summary.elements, 13000);
  ASSERT_EQ(model.muscles.size(), 2u);
  for (const auto& mu : model.muscles) {
    SCOPED_TRACE(mu.name);
    EXPECT_DOUBLE_EQ(mu.reference_stress, 5e6);
    EXPECT_DOUBLE_EQ(mu.optimal_stretch, 1.0);
    ASSERT_GT(mu.elements.size(), 100u);
    // Fibres run up the forehead (brow -> galea): mostly +y, tangent to the skull.
    double up = 0;
    for (const auto& f : mu.fibres) up += f[1];
    EXPECT_GT(up / static_cast<double>(mu.fibres.size()), 0.75);
  }
  EXPECT_EQ(model.muscles[0].name, "frontalis_left");
  EXPECT_EQ(model.muscles[1].name, "frontalis_right");
  bool has_tendon = false;
  for (const auto& v : r.summary.material_volumes) {
    if (v.name == "tendon") has_tendon = v.volume > 1e-6;  // m³: > 1000 mm³
  }
  EXPECT_TRUE(has_tendon);
  EXPECT_GT(r.summary.rigid_nodes, 1000);  // the held scalp
  EXPECT_GT(r.summary.sliding_nodes, 3000);
  // No element has a rigid corner outside the scalp strip: the deep layer can slide.
  std::vector<char> rigid(static_cast<std::size_t>(model.node_lattice.size()), 0);
  for (auto n : model.rigid_nodes) rigid[static_cast<std::size_t>(n)] = 1;
  const double h = r.summary.voxel_size;
  for (std::size_t e = 0; e < model.element_nodes.size(); ++e) {
    const double y = (model.element_lattice[e][1] + 0.5) * h + model.grid.origin[1];
    if (y > 0.066) continue;  // elements touching the held strip (y >= 68 mm)
    for (auto n : model.element_nodes[e]) ASSERT_EQ(rigid[static_cast<std::size_t>(n)], 0) << e;
  }
  for (const char* set : {"skin_surface", "brow", "strip_left", "strip_right", "scalp"}) {
    SCOPED_TRACE(set);
    const auto it = std::find_if(r.summary.node_sets.begin(), r.summary.node_sets.end(),
                                 [&](const auto& s) { return s.first == set; });
    ASSERT_NE(it, r.summary.node_sets.end());
    EXPECT_GT(it->second, 10);
  }
  ASSERT_EQ(model.surfaces.empty(), false);
  const auto skin = std::find_if(model.surfaces.begin(), model.surfaces.end(),
                                 [](const auto& s) { return s.name == "skin"; });
  ASSERT_NE(skin, model.surfaces.end());
  EXPECT_EQ(skin->vertices.size(), meshes().skin_surface.vertices.size());
  // min_fraction drops voxels less than 1 % full; skin vertices in such a sliver are bound to the
  // nearest kept element, which must lie within a tenth of a voxel (a sliver is that thin).
  EXPECT_LT(double(r.summary.embedding_outside), 0.02 * double(skin->vertices.size()));
  EXPECT_LT(r.summary.embedding_max_outside_distance, 0.12 * h);
}

TEST(Forehead, FinerSpecsReadTheSameMeshes) {
  for (const char* name : {"forehead_1mm.yaml", "forehead_0.5mm.yaml"}) {
    SCOPED_TRACE(name);
    const Spec spec = read_spec(kSource / "data" / "specs" / name);
    EXPECT_EQ(spec.muscles.size(), 2u);
    EXPECT_EQ(spec.tendons.size(), 1u);
  }
}

}  // namespace
}  // namespace sinew::voxelizer
