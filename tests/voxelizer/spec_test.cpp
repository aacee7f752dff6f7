// The voxelizer spec: keys, units, presets and the errors for bad specs.
#include "sinew/voxelizer/spec.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <string>

#include "pipeline_test_util.hpp"
#include "sinew/common/error.hpp"

namespace sinew::voxelizer {
namespace {

const std::string kMinimal = R"(
units: mm
output: out.h5
resolution: {voxel_size: 0.5}
outer: {sphere: {radius: 10}}
)" + testing::kPaperLayers;

// Parses text and returns the ConfigError message ("" when it parsed).
std::string config_error(const std::string& text) {
  try {
    parse_spec(text, "/specs/test.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Spec, MinimalSpecConvertsLengthsToMetres) {
  const Spec s = parse_spec(kMinimal, "/specs/test.yaml");
  ASSERT_TRUE(s.voxel_size.has_value());
  EXPECT_DOUBLE_EQ(*s.voxel_size, 0.5e-3);
  ASSERT_EQ(s.layers.size(), 3u);
  EXPECT_DOUBLE_EQ(*s.layers[0].thickness, 0.02e-3);
  EXPECT_DOUBLE_EQ(*s.layers[1].thickness, 1.8e-3);
  EXPECT_FALSE(s.layers[2].thickness.has_value());
  EXPECT_EQ(s.outer.kind, MeshSource::Kind::sphere);
  EXPECT_EQ(s.outer.transform.unit, LengthUnit::mm);  // meshes default to the spec's units
  EXPECT_DOUBLE_EQ(s.outer.radii.x, 10.0);
  EXPECT_EQ(s.output, std::filesystem::path("/specs/out.h5"));  // relative to the spec's folder
  ASSERT_EQ(s.visual.size(), 1u);                               // default visual surface: the skin
  EXPECT_EQ(s.visual[0].surface.name, "outer");
}

TEST(Spec, Warburton2013PresetIsTable1) {
  const Spec s = parse_spec(kMinimal, "/specs/test.yaml");
  const auto* sc = s.find_material("stratum_corneum");
  const auto* d = s.find_material("dermis");
  const auto* hy = s.find_material("hypodermis");
  const auto* mu = s.find_material("muscle");
  const auto* te = s.find_material("tendon");
  ASSERT_TRUE(sc && d && hy && mu && te);
  EXPECT_DOUBLE_EQ(sc->youngs_modulus, 48e6);
  EXPECT_DOUBLE_EQ(d->youngs_modulus, 0.0814e6);
  EXPECT_DOUBLE_EQ(hy->youngs_modulus, 0.034e6);
  EXPECT_DOUBLE_EQ(mu->youngs_modulus, 0.5e6);
  EXPECT_DOUBLE_EQ(te->youngs_modulus, 24e6);
  for (const auto* m : {sc, d, hy, mu, te}) {
    EXPECT_DOUBLE_EQ(m->poisson_ratio, 0.49);
    EXPECT_DOUBLE_EQ(m->density, 11000);
  }
}

TEST(Spec, FullSpecReadsEverySection) {
  const std::string text = std::string(kMinimal) + R"(
inner: {path: skull.stl, unit: cm, scale: 2, rotate_deg: [0, 0, 90], translate: [1, 2, 3]}
muscles:
  - name: frontalis
    mesh: frontalis.obj
    material: muscle
    reference_stress: 4e6
    optimal_stretch: 1.1
    passive: {p1: 0.1, p2: 5, linear_stretch: 1.5}
    fibres:
      type: harmonic
      origin: {box: {min: [0, 0, 0], max: [1, 1, 1]}}
      insertion: {surface: inner, distance: 2}
tendons:
  - {name: galea, mesh: galea.obj, material: tendon}
regions:
  - {name: block, box: {min: [0, 0, 0], max: [1, 1, 1]}, material: dermis}
boundary:
  - {type: rigid, inside: true}
  - {type: sliding, within: 1.5, box: {min: [-5, -5, -5], max: [5, 5, 5]}}
node_sets:
  - {name: top, box: {min: [-1, -1, 9], max: [1, 1, 11]}}
  - {name: near_skin, surface: outer, distance: 0.5}
visual:
  - {name: skin, surface: outer}
  - {name: bone, surface: inner}
)";
  const Spec s = parse_spec(text, "/specs/test.yaml");
  ASSERT_TRUE(s.inner.has_value());
  EXPECT_EQ(s.inner->path, std::filesystem::path("/specs/skull.stl"));
  EXPECT_EQ(s.inner->transform.unit, LengthUnit::cm);
  EXPECT_DOUBLE_EQ(s.inner->transform.scale, 2.0);
  EXPECT_DOUBLE_EQ(s.inner->transform.translate.y, 0.02);  // in the mesh's unit (cm)
  ASSERT_EQ(s.muscles.size(), 1u);
  const auto& m = s.muscles[0];
  EXPECT_DOUBLE_EQ(m.reference_stress, 4e6);
  EXPECT_DOUBLE_EQ(m.optimal_stretch, 1.1);
  EXPECT_DOUBLE_EQ(m.passive_linear_stretch, 1.5);
  EXPECT_EQ(m.fibres.kind, FibreSpec::Kind::harmonic);
  ASSERT_TRUE(m.fibres.origin.box.has_value());
  EXPECT_DOUBLE_EQ(m.fibres.origin.box->hi.x, 1e-3);
  ASSERT_TRUE(m.fibres.insertion.surface.has_value());
  EXPECT_EQ(m.fibres.insertion.surface->name, "inner");
  EXPECT_DOUBLE_EQ(m.fibres.insertion.distance, 2e-3);
  ASSERT_EQ(s.boundary.size(), 2u);
  EXPECT_EQ(s.boundary[0].kind, BoundarySpec::Kind::rigid);
  EXPECT_TRUE(s.boundary[0].inside);
  EXPECT_EQ(s.boundary[1].kind, BoundarySpec::Kind::sliding);
  EXPECT_DOUBLE_EQ(*s.boundary[1].within, 1.5e-3);
  EXPECT_EQ(s.node_sets.size(), 2u);
  EXPECT_EQ(s.visual.size(), 2u);
  EXPECT_EQ(s.tendons.size(), 1u);
  EXPECT_EQ(s.regions.size(), 1u);
}

TEST(Spec, UnknownKeysNameFileAndKeyPath) {
  const std::string top = config_error(std::string(kMinimal) + "colour: red\n");
  EXPECT_NE(top.find("/specs/test.yaml"), std::string::npos) << top;
  EXPECT_NE(top.find("colour"), std::string::npos) << top;
  EXPECT_NE(top.find("unknown key"), std::string::npos) << top;

  const std::string nested = config_error(std::string(kMinimal) + R"(
muscles:
  - name: m
    mesh: m.obj
    material: muscle
    fibres: {type: constant, direction: [1, 0, 0], drection: [0, 1, 0]}
)");
  EXPECT_NE(nested.find("muscles[0].fibres.drection"), std::string::npos) << nested;
}

TEST(Spec, UnknownMaterialAndSurfaceNamesAreErrors) {
  std::string bad = kMinimal;
  bad.replace(bad.find("material: dermis"), 16, "material: derm");
  const std::string e1 = config_error(bad);
  EXPECT_NE(e1.find("layers[1].material"), std::string::npos) << e1;
  EXPECT_NE(e1.find("unknown material 'derm'"), std::string::npos) << e1;

  const std::string e2 = config_error(std::string(kMinimal) + R"(
muscles:
  - name: frontalis
    mesh: f.obj
    material: muscle
    fibres:
      type: harmonic
      origin: {surface: corrugator, distance: 1}
      insertion: {box: {min: [0, 0, 0], max: [1, 1, 1]}}
)");
  EXPECT_NE(e2.find("muscles[0].fibres.origin.surface"), std::string::npos) << e2;
  EXPECT_NE(e2.find("unknown surface or muscle name 'corrugator'"), std::string::npos) << e2;

  const std::string e3 =
      config_error(std::string(kMinimal) + "boundary:\n  - {type: rigid, inside: true}\n");
  EXPECT_NE(e3.find("'inner'"), std::string::npos) << e3;  // no inner surface declared
}

TEST(Spec, RangeAndTypeErrors) {
  EXPECT_NE(config_error(std::string(kMinimal) + "tissue_thickness: -1\n").find("must be > 0"),
            std::string::npos);
  std::string both = kMinimal;
  both.replace(both.find("{voxel_size: 0.5}"), 17, "{voxel_size: 0.5, target_elements: 1000}");
  EXPECT_NE(config_error(both).find("exactly one of voxel_size and target_elements"),
            std::string::npos);
  std::string nan = kMinimal;
  nan.replace(nan.find("0.5}"), 4, ".nan}");
  EXPECT_NE(config_error(nan).find("finite"), std::string::npos);
  std::string unit = kMinimal;
  unit.replace(unit.find("units: mm"), 9, "units: in");
  EXPECT_NE(config_error(unit).find("unknown unit 'in'"), std::string::npos);
  std::string layer = kMinimal;
  layer.replace(layer.find("{material: dermis, thickness: 1.8}"), 34, "{material: dermis}");
  EXPECT_NE(config_error(layer).find("only the last layer may omit it"), std::string::npos);
  EXPECT_NE(config_error("units: [").find("YAML syntax error"), std::string::npos);
}

// Issue 33's vague errors, each now named against its spec key: an overflowing fibre direction
// (its length overflowed to inf, and the zero direction it gave was reported against the output
// file) is a direction like any other; a duplicated visual name; a passive curve whose slope
// overflows, or a negative p1.
TEST(Spec, FibreOverflowVisualNamesAndPassiveCurveAreCheckedAtTheirKeys) {
  const std::string muscle = R"(
muscles:
  - name: m
    mesh: m.obj
    material: muscle
    PASSIVE
    fibres: {type: constant, direction: [1e308, 1e308, 0]}
)";
  auto with = [&](const std::string& passive, const std::string& extra = "") {
    std::string t = std::string(kMinimal) + muscle + extra;
    t.replace(t.find("PASSIVE"), 7, passive);
    return t;
  };
  const Spec spec = parse_spec(with("optimal_stretch: 1"), "/specs/test.yaml");
  ASSERT_EQ(spec.muscles.size(), 1u);
  EXPECT_NEAR(spec.muscles[0].fibres.direction[0], std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(spec.muscles[0].fibres.direction[1], std::sqrt(0.5), 1e-15);
  EXPECT_EQ(spec.muscles[0].fibres.direction[2], 0.0);

  const std::string overflow = config_error(with("passive: {p1: 1e300, p2: 1000}"));
  EXPECT_NE(overflow.find("muscles[0].passive"), std::string::npos) << overflow;
  EXPECT_NE(overflow.find("overflows: lower p1, p2 or linear_stretch"), std::string::npos)
      << overflow;
  const std::string negative = config_error(with("passive: {p1: -1}"));
  EXPECT_NE(negative.find("muscles[0].passive.p1"), std::string::npos) << negative;

  const std::string twice =
      config_error(std::string(kMinimal) +
                   "visual:\n  - {name: skin, surface: outer}\n  - {name: skin, surface: outer}\n");
  EXPECT_NE(twice.find("visual[1].name"), std::string::npos) << twice;
  EXPECT_NE(twice.find("duplicate visual name 'skin'"), std::string::npos) << twice;
}

TEST(Spec, MissingSpecFileIsAnIoError) {
  EXPECT_THROW(read_spec("/nonexistent/spec.yaml"), IoError);
}

TEST(Spec, JsonRecordsTheParameters) {
  const Spec s = parse_spec(kMinimal, "/specs/test.yaml");
  const std::string j = spec_to_json(s);
  EXPECT_NE(j.find("\"voxel_size\":0.0005"), std::string::npos) << j;
  EXPECT_NE(j.find("stratum_corneum"), std::string::npos);
}

}  // namespace
}  // namespace sinew::voxelizer
