// Message composition of the typed exceptions in common/error.hpp.
#include "sinew/common/error.hpp"

#include <gtest/gtest.h>

namespace {

TEST(Error, ComposesFileFieldIndexProblem) {
  const auto e =
      sinew::FormatError("model.h5", "/elements/nodes", "node id 1234 out of range [0, 1000)")
          .at(17);
  EXPECT_STREQ(e.what(), "model.h5: /elements/nodes[17]: node id 1234 out of range [0, 1000)");
  EXPECT_EQ(e.file(), "model.h5");
  EXPECT_EQ(e.field(), "/elements/nodes");
  EXPECT_EQ(e.problem(), "node id 1234 out of range [0, 1000)");
  ASSERT_TRUE(e.index().has_value());
  EXPECT_EQ(*e.index(), 17);
}

TEST(Error, OmitsMissingParts) {
  EXPECT_STREQ(sinew::IoError("a.h5", "", "cannot open").what(), "a.h5: cannot open");
  EXPECT_STREQ(sinew::ConfigError("", "solver.dt", "must be positive").what(),
               "solver.dt: must be positive");
  EXPECT_STREQ(sinew::GeometryError("", "", "empty mesh").what(), "empty mesh");
  EXPECT_STREQ(sinew::InstabilityError("", "", "NaN in node forces").at(3).what(),
               "[3]: NaN in node forces");
  EXPECT_FALSE(sinew::ResourceError("", "", "no GPU").index().has_value());
}

TEST(Error, KeepsItsTypeThroughAt) {
  try {
    throw sinew::ConfigError("scene.yaml", "materials.skin.E", "must be positive").at(2);
  } catch (const sinew::ConfigError& e) {
    EXPECT_STREQ(e.what(), "scene.yaml: materials.skin.E[2]: must be positive");
    return;
  } catch (...) {
  }
  FAIL() << "ConfigError was not caught as ConfigError";
}

TEST(Error, IsCaughtAsBaseAndRuntimeError) {
  try {
    throw sinew::IoError("x", "y", "z");
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "x: y: z");
  }
}

}  // namespace
