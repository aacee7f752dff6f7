// Writer and reader of the model file: round trip, determinism, atomic writes, and one test per
// broken-file case, each asserting its own message (dataset + problem). Broken files are made by
// writing a good file and then changing it with the HDF5 C API.
#include "sinew/formats/model_file.hpp"

#include <hdf5.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include "sinew/common/error.hpp"
#include "test_models.hpp"

namespace sinew::formats {
namespace {

using testing::every_feature_model;
using testing::file_bytes;
using testing::temp_path;

// ---- HDF5 surgery on written files ----

class H5File {
 public:
  explicit H5File(const std::string& path) : id_(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT)) {
    EXPECT_GE(id_, 0) << "cannot open " << path;
  }
  ~H5File() { H5Fclose(id_); }
  hid_t id() const { return id_; }

 private:
  hid_t id_;
};

template <typename T>
hid_t mem_type() {
  if constexpr (std::is_same_v<T, double>) return H5T_NATIVE_DOUBLE;
  if constexpr (std::is_same_v<T, std::int64_t>) return H5T_NATIVE_INT64;
  return H5T_NATIVE_INT32;
}

// Reads a whole numeric dataset, lets `edit` change the flat values, writes it back.
template <typename T, typename Edit>
void edit_dataset(const std::string& path, const std::string& dataset, Edit edit) {
  H5File f(path);
  const hid_t ds = H5Dopen2(f.id(), dataset.c_str(), H5P_DEFAULT);
  ASSERT_GE(ds, 0) << dataset;
  const hid_t space = H5Dget_space(ds);
  std::vector<T> values(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  ASSERT_GE(H5Dread(ds, mem_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  edit(values);
  ASSERT_GE(H5Dwrite(ds, mem_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  H5Sclose(space);
  H5Dclose(ds);
}

template <typename T>
void set_value(const std::string& path, const std::string& dataset, std::size_t flat_index,
               T value) {
  edit_dataset<T>(path, dataset, [&](std::vector<T>& v) {
    ASSERT_LT(flat_index, v.size());
    v[flat_index] = value;
  });
}

void delete_dataset(const std::string& path, const std::string& dataset) {
  H5File f(path);
  ASSERT_GE(H5Ldelete(f.id(), dataset.c_str(), H5P_DEFAULT), 0) << dataset;
}

// Replaces a dataset by a rows × cols (cols 0: 1-D) one of the given type, filled with zeros.
void replace_dataset(const std::string& path, const std::string& dataset, hsize_t rows,
                     hsize_t cols, hid_t type) {
  H5File f(path);
  ASSERT_GE(H5Ldelete(f.id(), dataset.c_str(), H5P_DEFAULT), 0) << dataset;
  const hsize_t dims[2] = {rows, cols};
  const hid_t space = H5Screate_simple(cols > 0 ? 2 : 1, dims, nullptr);
  const hid_t ds =
      H5Dcreate2(f.id(), dataset.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  std::vector<double> zeros(static_cast<std::size_t>(rows * std::max<hsize_t>(cols, 1)), 0.0);
  if (!zeros.empty()) H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data());
  H5Dclose(ds);
  H5Sclose(space);
}

void set_version_attribute(const std::string& path, std::int32_t version) {
  H5File f(path);
  const hid_t a = H5Aopen(f.id(), "format_version", H5P_DEFAULT);
  ASSERT_GE(a, 0);
  ASSERT_GE(H5Awrite(a, H5T_NATIVE_INT32, &version), 0);
  H5Aclose(a);
}

// The message of the FormatError that reading `path` throws ("" and a test failure if none).
std::string read_error(const std::string& path) {
  try {
    (void)read_model(path);
  } catch (const FormatError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected FormatError, got: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "reading " << path << " did not fail";
  return "";
}

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "message: " << (text)

class BrokenFile : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = every_feature_model();
    path_ = temp_path("model.h5");
    write_model(model_, path_);
  }
  void TearDown() override { std::filesystem::remove(path_); }
  Model model_;
  std::string path_;
};

// ---- round trip and determinism ----

TEST(ModelFile, EveryFeatureModelIsComplete) {
  const Model m = every_feature_model();
  EXPECT_EQ(m.materials.size(), 2u);
  EXPECT_EQ(m.muscles.size(), 2u);
  EXPECT_FALSE(m.rigid_nodes.empty());
  EXPECT_FALSE(m.sliding.empty());
  ASSERT_EQ(m.surfaces.size(), 2u);
  EXPECT_EQ(m.surfaces[0].role, SurfaceRole::sliding);
  EXPECT_EQ(m.surfaces[1].role, SurfaceRole::visual);
  EXPECT_FALSE(m.surfaces[1].embedding_element.empty());
  EXPECT_EQ(m.surfaces[1].uv_triangles.size(), m.surfaces[1].triangles.size());
  EXPECT_FALSE(m.provenance.inputs.empty());
  // Some element holds two materials, one is not full.
  bool two = false;
  for (std::size_t e = 0; e + 1 < m.material_offsets.size(); ++e) {
    two = two || m.material_offsets[e + 1] - m.material_offsets[e] == 2;
  }
  EXPECT_TRUE(two);
  EXPECT_DOUBLE_EQ(m.material_fractions[0], 0.5);
}

TEST(ModelFile, RoundTripKeepsEveryFeature) {
  const Model m = every_feature_model();
  const std::string path = temp_path("model.h5");
  write_model(m, path);
  const Model back = read_model(path);
  EXPECT_TRUE(back.grid == m.grid);
  EXPECT_EQ(back.node_lattice, m.node_lattice);
  EXPECT_EQ(back.element_nodes, m.element_nodes);
  EXPECT_TRUE(back.materials == m.materials);
  EXPECT_EQ(back.material_fractions, m.material_fractions);
  EXPECT_TRUE(back.muscles == m.muscles);
  EXPECT_TRUE(back.sliding == m.sliding);
  EXPECT_TRUE(back.surfaces == m.surfaces);
  EXPECT_TRUE(back.node_sets == m.node_sets);
  EXPECT_TRUE(back.element_sets == m.element_sets);
  EXPECT_TRUE(back.provenance == m.provenance);
  EXPECT_TRUE(back == m);
  std::filesystem::remove(path);
}

TEST(ModelFile, RewriteIsByteIdentical) {
  const Model m = every_feature_model();
  const std::string a = temp_path("a.h5"), b = temp_path("b.h5"), c = temp_path("c.h5");
  write_model(m, a);
  write_model(read_model(a), b);
  write_model(m, c);
  const std::string bytes_a = file_bytes(a);
  ASSERT_GT(bytes_a.size(), 1000u);
  EXPECT_TRUE(bytes_a == file_bytes(b)) << "write, read, write again differs";
  EXPECT_TRUE(bytes_a == file_bytes(c)) << "the same model written twice differs";
  for (const auto& p : {a, b, c}) std::filesystem::remove(p);
}

TEST(ModelFile, NamedSetsKeepTheirOrder) {
  Model m = every_feature_model();
  // Not in name order: the file keeps the model's order.
  std::swap(m.node_sets.front(), m.node_sets.back());
  const std::string path = temp_path("model.h5");
  write_model(m, path);
  EXPECT_TRUE(read_model(path).node_sets == m.node_sets);
  std::filesystem::remove(path);
}

TEST(ModelFile, WriteLeavesNoTemporaryAndReplacesAnOldFile) {
  const std::string path = temp_path("model.h5");
  {
    std::ofstream old(path);
    old << "old contents";
  }
  write_model(every_feature_model(), path);
  EXPECT_NO_THROW((void)read_model(path));
  const auto dir = std::filesystem::path(path).parent_path();
  const std::string tmp_name = std::filesystem::path(path).filename().string() + ".tmp-";
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_NE(entry.path().filename().string().rfind(tmp_name, 0), 0u) << entry.path();
  }
  std::filesystem::remove(path);
}

TEST(ModelFile, InvalidModelIsNotWritten) {
  Model m = every_feature_model();
  m.muscles[0].fibres[0] = {0.5, 0, 0};
  const std::string path = temp_path("model.h5");
  try {
    write_model(m, path);
    FAIL() << "an invalid model was written";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "/muscles/fibres");
    EXPECT_CONTAINS(e.what(), "not a unit vector");
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp-" + std::to_string(getpid())));
}

TEST(ModelFile, UnwritableDirectoryIsAnIoError) {
  EXPECT_THROW(write_model(every_feature_model(), "/nonexistent-dir-sinew/model.h5"), IoError);
  EXPECT_FALSE(
      std::filesystem::exists("/nonexistent-dir-sinew/model.h5.tmp-" + std::to_string(getpid())));
}

TEST(ModelFile, MissingFileIsAnIoError) {
  try {
    (void)read_model("/nonexistent-dir-sinew/model.h5");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_CONTAINS(e.what(), "/nonexistent-dir-sinew/model.h5: cannot open");
  }
}

// ---- broken files: one message each ----

TEST_F(BrokenFile, TruncatedFile) {
  const std::string bytes = file_bytes(path_);
  {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 2));
  }
  const std::string msg = read_error(path_);
  EXPECT_CONTAINS(msg, path_ + ": ");
  EXPECT_CONTAINS(msg, "truncated or corrupt");
}

TEST_F(BrokenFile, TruncatedAnywhereNeverCrashes) {
  // Cut the file at 40 lengths spread over its size: every one is a FormatError, none a crash.
  const std::string bytes = file_bytes(path_);
  const std::string cut = temp_path("cut.h5");
  for (std::size_t i = 0; i < 40; ++i) {
    const std::size_t n = bytes.size() * i / 40 + i;
    {
      std::ofstream out(cut, std::ios::binary | std::ios::trunc);
      out.write(bytes.data(), static_cast<std::streamsize>(n));
    }
    EXPECT_THROW((void)read_model(cut), FormatError) << "cut at " << n << " of " << bytes.size();
  }
  std::filesystem::remove(cut);
}

TEST_F(BrokenFile, EmptyFile) {
  { std::ofstream out(path_, std::ios::binary | std::ios::trunc); }
  EXPECT_CONTAINS(read_error(path_), "not an HDF5 file");
}

TEST_F(BrokenFile, NotHdf5) {
  {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out << "solid cube\nendsolid cube\n";
  }
  EXPECT_CONTAINS(read_error(path_), "not an HDF5 file");
}

TEST_F(BrokenFile, WrongVersion) {
  set_version_attribute(path_, 4);
  EXPECT_CONTAINS(read_error(path_),
                  "/format_version: unsupported format version 4 (this build reads versions 1 to "
                  "3)");
  set_version_attribute(path_, 0);
  EXPECT_CONTAINS(read_error(path_), "unsupported format version 0");
}

// A version 1 file (no texture coordinates) is still read: the same model without UVs.
TEST_F(BrokenFile, VersionOneFileReadsWithoutTextureCoordinates) {
  for (const char* d : {"/surfaces/uv_offsets", "/surfaces/uvs", "/surfaces/uv_triangle_offsets",
                        "/surfaces/uv_triangles"}) {
    delete_dataset(path_, d);
  }
  set_version_attribute(path_, 1);
  Model expected = every_feature_model();
  expected.jaw.reset();  // versions 1 and 2 have no jaw: a /jaw there is not read
  for (auto& s : expected.surfaces) {
    s.uvs.clear();
    s.uv_triangles.clear();
  }
  EXPECT_EQ(read_model(path_), expected);
  // A version 2 file must have them.
  set_version_attribute(path_, 2);
  EXPECT_CONTAINS(read_error(path_), "/surfaces/uv_offsets");
}

// A version 2 file (no jaw) is still read: the same model without a jaw.
TEST_F(BrokenFile, VersionTwoFileReadsWithoutAJaw) {
  delete_dataset(path_, "/jaw");
  set_version_attribute(path_, 2);
  Model expected = every_feature_model();
  expected.jaw.reset();
  EXPECT_EQ(read_model(path_), expected);
  // A version 3 file without /jaw is a model without a jaw too.
  set_version_attribute(path_, 3);
  EXPECT_EQ(read_model(path_), expected);
}

TEST_F(BrokenFile, JawNodeThatIsAlsoRigid) {
  set_value<std::int32_t>(path_, "/jaw/nodes", 0, 0);  // node 0: on the rigid bottom face
  EXPECT_CONTAINS(read_error(path_), "/jaw/nodes[0]: node 0 is both rigid and on the jaw");
}

TEST_F(BrokenFile, JawAxisNotAUnitVector) {
  set_value<double>(path_, "/jaw/axis", 1, 2.0);
  EXPECT_CONTAINS(read_error(path_), "/jaw/axis: not a unit vector: length 2");
}

TEST_F(BrokenFile, JawForwardAlongItsAxis) {
  set_value<double>(path_, "/jaw/forward", 0, 0.0);
  set_value<double>(path_, "/jaw/forward", 1, 1.0);
  EXPECT_CONTAINS(read_error(path_), "/jaw/forward: not normal to /jaw/axis: cosine 1");
}

TEST_F(BrokenFile, JawPivotWrongShape) {
  delete_dataset(path_, "/jaw/pivot");
  EXPECT_CONTAINS(read_error(path_), "/jaw/pivot: missing dataset");
}

TEST_F(BrokenFile, OutOfRangeTextureCorner) {
  set_value<std::int32_t>(path_, "/surfaces/uv_triangles", 4, 20);  // skin triangle 1, corner 1
  EXPECT_CONTAINS(read_error(path_),
                  "/surfaces/uv_triangles[1]: surface 'skin': texture coordinate id 20 out of "
                  "range [0, 20)");
}

TEST_F(BrokenFile, TextureOffsetsBeyondTheirRows) {
  set_value<std::int64_t>(path_, "/surfaces/uv_offsets", 2, 21);
  EXPECT_CONTAINS(read_error(path_),
                  "/surfaces/uv_offsets[2]: last offset 21 differs from the 20 "
                  "rows of /surfaces/uvs");
}

TEST_F(BrokenFile, NotASinewModel) {
  {
    H5File f(path_);
    ASSERT_GE(H5Adelete(f.id(), "format"), 0);
  }
  EXPECT_CONTAINS(read_error(path_), "/format: missing root attribute");
}

TEST_F(BrokenFile, MissingDataset) {
  delete_dataset(path_, "/materials/density");
  EXPECT_CONTAINS(read_error(path_), "/materials/density: missing dataset");
}

TEST_F(BrokenFile, MissingGroup) {
  delete_dataset(path_, "/constraints");
  EXPECT_CONTAINS(read_error(path_), "/constraints/rigid_nodes: missing dataset");
}

TEST_F(BrokenFile, WrongShape) {
  replace_dataset(path_, "/elements/nodes", model_.element_count(), 7, H5T_STD_I32LE);
  EXPECT_CONTAINS(read_error(path_), "/elements/nodes: wrong shape (36, 7), expected (n, 8)");
}

TEST_F(BrokenFile, WrongRowCount) {
  replace_dataset(path_, "/materials/density", 3, 0, H5T_IEEE_F64LE);
  EXPECT_CONTAINS(read_error(path_), "/materials/density: wrong shape (3), expected (2)");
}

TEST_F(BrokenFile, WrongDtype) {
  replace_dataset(path_, "/nodes/lattice", model_.node_count(), 3, H5T_IEEE_F64LE);
  EXPECT_CONTAINS(read_error(path_), "/nodes/lattice: wrong dtype, expected int32");
}

TEST_F(BrokenFile, OutOfRangeNodeIndex) {
  set_value<std::int32_t>(path_, "/elements/nodes", 3 * 8 + 2, 99999);
  EXPECT_CONTAINS(read_error(path_),
                  "/elements/nodes[3]: node id 99999 (corner 2) out of range [0, 80)");
}

TEST_F(BrokenFile, OutOfRangeMaterialIndex) {
  set_value<std::int32_t>(path_, "/element_materials/material", 4, 7);
  EXPECT_CONTAINS(read_error(path_),
                  "/element_materials/material[4]: element 4: material id 7 out of range [0, 2)");
}

TEST_F(BrokenFile, OutOfRangeSurfaceIndex) {
  set_value<std::int32_t>(path_, "/constraints/sliding_surface", 1, 5);
  EXPECT_CONTAINS(read_error(path_),
                  "/constraints/sliding_surface[1]: surface id 5 out of range [0, 2)");
}

TEST_F(BrokenFile, OutOfRangeTriangleIndex) {
  set_value<std::int32_t>(path_, "/constraints/sliding_rest_triangle", 0, 2);
  EXPECT_CONTAINS(read_error(path_),
                  "/constraints/sliding_rest_triangle[0]: triangle id 2 out of range [0, 2) of "
                  "surface 'skull'");
}

TEST_F(BrokenFile, OutOfRangeElementIndex) {
  set_value<std::int32_t>(path_, "/muscles/elements", 13, 36);
  EXPECT_CONTAINS(
      read_error(path_),
      "/muscles/elements[13]: muscle 'frontalis_right': element id 36 out of range [0, 36)");
}

TEST_F(BrokenFile, OutOfRangeSurfaceVertex) {
  set_value<std::int32_t>(path_, "/surfaces/triangles", 2 * 3 + 1, 20);  // skin triangle 0
  EXPECT_CONTAINS(read_error(path_),
                  "/surfaces/triangles[2]: surface 'skin': vertex id 20 out of range [0, 20)");
}

TEST_F(BrokenFile, OutOfRangeEmbeddingElement) {
  set_value<std::int32_t>(path_, "/surfaces/embedding_element", 3, -1);
  EXPECT_CONTAINS(
      read_error(path_),
      "/surfaces/embedding_element[3]: surface 'skin': vertex 3: element id -1 out of range");
}

TEST_F(BrokenFile, NaNVertex) {
  set_value<double>(path_, "/surfaces/vertices", 3 * 1 + 2,
                    std::numeric_limits<double>::quiet_NaN());
  EXPECT_CONTAINS(read_error(path_),
                  "/surfaces/vertices[1]: surface 'skull': vertex is not finite");
}

TEST_F(BrokenFile, NaNModulus) {
  set_value<double>(path_, "/materials/youngs_modulus", 1,
                    std::numeric_limits<double>::quiet_NaN());
  EXPECT_CONTAINS(read_error(path_),
                  "/materials/youngs_modulus[1]: material 'muscle_tissue': Young's modulus must be "
                  "positive and finite, got nan");
}

TEST_F(BrokenFile, NaNFraction) {
  set_value<double>(path_, "/element_materials/fraction", 2,
                    std::numeric_limits<double>::quiet_NaN());
  EXPECT_CONTAINS(read_error(path_),
                  "/element_materials/fraction[2]: element 2: fraction is not finite");
}

TEST_F(BrokenFile, NegativeFraction) {
  set_value<double>(path_, "/element_materials/fraction", 5, -0.1);
  EXPECT_CONTAINS(read_error(path_),
                  "/element_materials/fraction[5]: element 5: fraction -0.1 outside [0, 1]");
}

TEST_F(BrokenFile, NegativeMuscleFraction) {
  set_value<double>(path_, "/muscles/fractions", 0, -0.25);
  EXPECT_CONTAINS(read_error(path_),
                  "/muscles/fractions[0]: muscle 'frontalis_left': fraction -0.25 outside [0, 1]");
}

TEST_F(BrokenFile, FractionSumAboveOne) {
  // Elements of the k = 1 row hold both layers (0.5 + 0.5); make them 0.5 + 0.7.
  const std::size_t e = 12;  // first element of k = 1
  const auto first = static_cast<std::size_t>(model_.material_offsets[e]);
  ASSERT_EQ(model_.material_offsets[e + 1] - model_.material_offsets[e], 2);
  set_value<double>(path_, "/element_materials/fraction", first + 1, 0.7);
  EXPECT_CONTAINS(read_error(path_), "/element_materials/fraction[" + std::to_string(first) +
                                         "]: element 12: fraction sum 1.2 exceeds 1");
}

TEST_F(BrokenFile, ElementWithoutMaterial) {
  // Element 0 holds one entry (fat, 0.5): make it zero.
  set_value<double>(path_, "/element_materials/fraction", 0, 0.0);
  EXPECT_CONTAINS(read_error(path_), "/element_materials/offsets[0]: element 0 has no material");
}

TEST_F(BrokenFile, NonMonotoneOffsets) {
  set_value<std::int64_t>(path_, "/element_materials/offsets", 3, 100);
  EXPECT_CONTAINS(read_error(path_),
                  "/element_materials/offsets[4]: offsets decrease: 4 after 100");
}

TEST_F(BrokenFile, NonUnitFibre) {
  set_value<double>(path_, "/muscles/fibres", 2, 2.0);  // fibre 0 = (0, 0, 2)
  EXPECT_CONTAINS(read_error(path_),
                  "/muscles/fibres[0]: muscle 'frontalis_left': fibre direction is not a unit "
                  "vector (length 2)");
}

TEST_F(BrokenFile, EmbeddingOutsideElement) {
  set_value<double>(path_, "/surfaces/embedding_local", 4 * 3 + 0, 1.5);
  EXPECT_CONTAINS(read_error(path_),
                  "/surfaces/embedding_local[4]: surface 'skin': vertex 4: local coordinates (1.5, "
                  "-1, 1) outside the element");
}

TEST_F(BrokenFile, InconsistentModuli) {
  set_value<double>(path_, "/materials/shear_modulus", 0, 1000.0);
  EXPECT_CONTAINS(read_error(path_),
                  "/materials/shear_modulus[0]: material 'fat': shear modulus 1000 inconsistent "
                  "with E/(2(1+nu))");
}

TEST_F(BrokenFile, PoissonRatioAtIncompressibleLimit) {
  set_value<double>(path_, "/materials/poisson_ratio", 0, 0.5);
  EXPECT_CONTAINS(
      read_error(path_),
      "/materials/poisson_ratio[0]: material 'fat': Poisson ratio 0.5 outside (-1, 0.5)");
}

TEST_F(BrokenFile, UnsortedNodeLattice) {
  set_value<std::int32_t>(path_, "/nodes/lattice", 3 * 1 + 0, 0);  // node 1 becomes (0, 0, 0)
  EXPECT_CONTAINS(read_error(path_), "/nodes/lattice[1]: nodes not sorted by (k, j, i) and unique");
}

TEST_F(BrokenFile, ElementNodesInconsistentWithLattice) {
  // Swap corners 0 and 1 of element 0: ids in range, lattice wrong.
  edit_dataset<std::int32_t>(path_, "/elements/nodes",
                             [](std::vector<std::int32_t>& v) { std::swap(v[0], v[1]); });
  EXPECT_CONTAINS(read_error(path_),
                  "/elements/nodes[0]: corner 0 is node 1 at lattice (1, 0, 0), but base (0, 0, 0) "
                  "+ corner offset gives (0, 0, 0)");
}

TEST_F(BrokenFile, SlidingOnVisualSurface) {
  set_value<std::int32_t>(path_, "/constraints/sliding_surface", 0, 1);
  EXPECT_CONTAINS(
      read_error(path_),
      "/constraints/sliding_surface[0]: surface 1 ('skin') has role visual, expected sliding");
}

TEST_F(BrokenFile, UnsortedNamedSet) {
  edit_dataset<std::int32_t>(path_, "/element_sets/corner",
                             [](std::vector<std::int32_t>& v) { std::swap(v[1], v[2]); });
  EXPECT_CONTAINS(read_error(path_),
                  "/element_sets/corner[2]: element ids not sorted and unique: 5 follows 35");
}

TEST_F(BrokenFile, NamedSetOutOfRange) {
  set_value<std::int32_t>(path_, "/node_sets/x_max", 0, 80);
  EXPECT_CONTAINS(read_error(path_), "/node_sets/x_max[0]: node id 80 out of range [0, 80)");
}

// Replaces the model's two material names with a dataset of string type `t` written from `data`
// (dataset creation properties `dcpl`), as other tools may store them.
void replace_material_names(const std::string& path, hid_t t, const void* data,
                            hid_t dcpl = H5P_DEFAULT) {
  H5File f(path);
  ASSERT_GE(H5Ldelete(f.id(), "/materials/name", H5P_DEFAULT), 0);
  const hsize_t n = 2;
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t ds = H5Dcreate2(f.id(), "/materials/name", t, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  ASSERT_GE(H5Dwrite(ds, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), 0);
  H5Dclose(ds);
  H5Sclose(space);
}

TEST_F(BrokenFile, FixedLengthStringsAreReadToo) {
  // Other tools may write fixed-length strings; they read back the same.
  const hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, 16);
  char names[2][16] = {"fat", "muscle_tissue"};
  replace_material_names(path_, t, names);
  H5Tclose(t);
  EXPECT_TRUE(read_model(path_) == model_);
}

TEST_F(BrokenFile, FixedLengthUtf8AndSpacePaddedStringsAreReadToo) {
  // Fixed-length strings in UTF-8 (h5py's numpy bytes with cset UTF-8, MATLAB) and space-padded
  // (Fortran's convention) read back the same (issue 33: UTF-8 had no conversion path to ASCII).
  const hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, 16);
  H5Tset_cset(t, H5T_CSET_UTF8);
  H5Tset_strpad(t, H5T_STR_SPACEPAD);
  char names[2][16];
  std::memset(names, ' ', sizeof names);
  std::memcpy(names[0], "fat", 3);
  std::memcpy(names[1], "muscle_tissue", 13);
  replace_material_names(path_, t, names);
  H5Tclose(t);
  EXPECT_TRUE(read_model(path_) == model_);
}

TEST_F(BrokenFile, CompressedVariableLengthStringsAreRefusedWithTheLayoutToUse) {
  // gzip needs chunks; sinew checks a variable-length string's heap reference before HDF5 follows
  // it, which only the contiguous layout allows: the message says which layout to use.
  const hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  const hsize_t chunk = 2;
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dcpl, 1, &chunk);
  H5Pset_deflate(dcpl, 6);
  const char* names[2] = {"fat", "muscle_tissue"};
  replace_material_names(path_, t, names, dcpl);
  H5Pclose(dcpl);
  H5Tclose(t);
  EXPECT_CONTAINS(read_error(path_),
                  "/materials/name: variable-length strings must be stored contiguous");
  EXPECT_CONTAINS(read_error(path_), "h5repack -l /materials/name:CONTI");
}

// Data in other files (issue 33: a damaged model crashed sinew-inspect named by a relative path
// from another folder and not by its absolute path: HDF5 follows links to other files and
// external storage relative to the working folder). A model holds its data itself: an external
// link, external raw storage and a virtual dataset mapping another file are refused by name,
// before HDF5 opens anything they point at (the other files here do not exist).
TEST_F(BrokenFile, DataInOtherFilesIsRefusedBeforeItIsOpened) {
  const hsize_t three = 3;
  auto recreate = [&](hid_t dcpl) {
    H5File f(path_);
    ASSERT_GE(H5Ldelete(f.id(), "/grid/origin", H5P_DEFAULT), 0);
    const hid_t space = H5Screate_simple(1, &three, nullptr);
    const hid_t ds = H5Dcreate2(f.id(), "/grid/origin", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl,
                                H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    H5Dclose(ds);
    H5Sclose(space);
  };
  const std::string path = path_;
  {
    SCOPED_TRACE("external link");
    {
      H5File f(path);
      ASSERT_GE(H5Ldelete(f.id(), "/grid/origin", H5P_DEFAULT), 0);
      ASSERT_GE(H5Lcreate_external("elsewhere.h5", "/origin", f.id(), "/grid/origin",
                                   H5P_DEFAULT, H5P_DEFAULT),
                0);
    }
    const std::string e = read_error(path);
    EXPECT_CONTAINS(e, "/grid/origin: a link to another file");
    EXPECT_CONTAINS(e, "h5copy -f ext");
  }
  write_model(model_, path_);
  {
    SCOPED_TRACE("external raw storage");
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    ASSERT_GE(H5Pset_external(dcpl, "origin.raw", 0, 3 * sizeof(double)), 0);
    recreate(dcpl);
    H5Pclose(dcpl);
    const std::string e = read_error(path);
    EXPECT_CONTAINS(e, "/grid/origin: stored in external raw files");
    EXPECT_CONTAINS(e, "h5repack -l /grid/origin:CONTI");
  }
  write_model(model_, path_);
  {
    SCOPED_TRACE("virtual dataset");
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    const hid_t space = H5Screate_simple(1, &three, nullptr);
    ASSERT_GE(H5Pset_virtual(dcpl, space, "elsewhere.h5", "/origin", space), 0);
    recreate(dcpl);
    H5Sclose(space);
    H5Pclose(dcpl);
    const std::string e = read_error(path);
    EXPECT_CONTAINS(e, "/grid/origin: a virtual dataset mapping values from other files");
    EXPECT_CONTAINS(e, "h5repack -l /grid/origin:CONTI");
  }
}

TEST_F(BrokenFile, UnknownSurfaceRole) {
  {
    H5File f(path_);
    ASSERT_GE(H5Ldelete(f.id(), "/surfaces/role", H5P_DEFAULT), 0);
    const hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    const hsize_t n = 2;
    const hid_t space = H5Screate_simple(1, &n, nullptr);
    const hid_t ds =
        H5Dcreate2(f.id(), "/surfaces/role", t, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const char* roles[2] = {"sliding", "decorative"};
    ASSERT_GE(H5Dwrite(ds, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, roles), 0);
    H5Dclose(ds);
    H5Sclose(space);
    H5Tclose(t);
  }
  EXPECT_CONTAINS(read_error(path_),
                  "/surfaces/role[1]: unknown surface role 'decorative' (known: sliding, visual)");
}

}  // namespace
}  // namespace sinew::formats
