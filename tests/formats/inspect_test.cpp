// The tools as a user runs them: sinew-generate writes a box, sinew-inspect accepts it (text and
// JSON) and rejects a broken file with exit status 1 and the reader's message.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "sinew/formats/model_file.hpp"
#include "test_models.hpp"

namespace {

struct Result {
  int status = -1;
  std::string out, err;
};

Result run(const std::string& args) {
  const std::string out = sinew::formats::testing::temp_path("stdout.txt");
  const std::string err = sinew::formats::testing::temp_path("stderr.txt");
  const std::string command = args + " >" + out + " 2>" + err;
  const int raw = std::system(command.c_str());
  Result r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = sinew::formats::testing::file_bytes(out);
  r.err = sinew::formats::testing::file_bytes(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

TEST(Tools, GenerateThenInspect) {
  const std::string model = sinew::formats::testing::temp_path("box.h5");
  const Result gen =
      run(std::string(SINEW_GENERATE_EXE) +
          " box --dims 8 8 8 --voxel-size 0.001 --material soft:3000:0.49:1000"
          " --material firm:30000:0.45:1100 --layer-boundary 0.0045"
          " --muscle m:firm --muscle-box 0 0 4 8 8 8 --fibre 0 1 0 --rigid-face z_min"
          " -o " +
          model);
  ASSERT_EQ(gen.status, 0) << gen.err;
  const Result text = run(std::string(SINEW_INSPECT_EXE) + " " + model);
  EXPECT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("(valid)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("nodes: 729, elements: 512"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("tool 'sinew-generate box'"), std::string::npos) << text.out;

  const Result json = run(std::string(SINEW_INSPECT_EXE) + " --json " + model);
  ASSERT_EQ(json.status, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  EXPECT_EQ(j["elements"], 512);
  // soft: 4.5 mm of 8 mm, firm the rest; cross-section 64 mm².
  EXPECT_NEAR(j["materials"][0]["volume"].get<double>(), 64e-6 * 4.5e-3, 1e-15);
  EXPECT_NEAR(j["materials"][1]["volume"].get<double>(), 64e-6 * 3.5e-3, 1e-15);
  EXPECT_NEAR(j["muscles"][0]["volume"].get<double>(), 256e-9, 1e-15);
  EXPECT_EQ(j["rigid_nodes"], 81);
  EXPECT_EQ(j["provenance"]["parameters"]["layer_boundaries"][0], 0.0045);

  // One element and one node (describe_test.cpp checks the text): element 0 is soft and rigid at
  // its bottom corners; an id past the end exits 1 naming the file and the option.
  const Result one = run(std::string(SINEW_INSPECT_EXE) + " " + model + " --element 0 --node 0");
  ASSERT_EQ(one.status, 0) << one.err;
  EXPECT_NE(one.out.find("element 0 of 512"), std::string::npos) << one.out;
  EXPECT_NE(one.out.find("soft                 fraction 1.0000"), std::string::npos) << one.out;
  EXPECT_NE(one.out.find("node 0 of 729"), std::string::npos) << one.out;
  EXPECT_NE(one.out.find("constraint   rigid"), std::string::npos) << one.out;
  const Result past = run(std::string(SINEW_INSPECT_EXE) + " " + model + " --element 512");
  EXPECT_EQ(past.status, 1);
  EXPECT_NE(past.err.find(model + ": --element: element 512 out of range [0, 512)"),
            std::string::npos)
      << past.err;
  std::filesystem::remove(model);
}

TEST(Tools, GenerateIsReproducibleAcrossProcesses) {
  // Two processes, the same options and creation time: byte-identical files.
  const std::string a = sinew::formats::testing::temp_path("a.h5");
  const std::string b = sinew::formats::testing::temp_path("b.h5");
  const std::string args =
      " box --dims 3 4 5 --voxel-size 0.002 --material gel:5000:0.45:1000"
      " --muscle m:gel --fibre 1 2 2 --created 2026-11-21T07:00:00Z -q -o ";
  ASSERT_EQ(run(std::string(SINEW_GENERATE_EXE) + args + a).status, 0);
  ASSERT_EQ(run(std::string(SINEW_GENERATE_EXE) + args + b).status, 0);
  const std::string bytes = sinew::formats::testing::file_bytes(a);
  EXPECT_GT(bytes.size(), 1000u);
  EXPECT_TRUE(bytes == sinew::formats::testing::file_bytes(b));
  std::filesystem::remove(a);
  std::filesystem::remove(b);
}

TEST(Tools, InspectRejectsABrokenFile) {
  const std::string model = sinew::formats::testing::temp_path("broken.h5");
  {
    std::ofstream out(model);
    out << "this is not a model\n";
  }
  const Result r = run(std::string(SINEW_INSPECT_EXE) + " " + model);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(model + ": not an HDF5 file"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
  std::filesystem::remove(model);
}

TEST(Tools, InspectRejectsAnInvalidModel) {
  // A valid HDF5 file whose content breaks a check: a negative fraction.
  sinew::formats::Model m = sinew::formats::testing::every_feature_model();
  const std::string model = sinew::formats::testing::temp_path("invalid.h5");
  sinew::formats::write_model(m, model);
  {
    const hid_t f = H5Fopen(model.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(f, "/muscles/fractions", H5P_DEFAULT);
    std::vector<double> v(24);
    H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    v[3] = -0.5;
    H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Dclose(ds);
    H5Fclose(f);
  }
  const Result r = run(std::string(SINEW_INSPECT_EXE) + " " + model);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(
      r.err.find("/muscles/fractions[3]: muscle 'frontalis_left': fraction -0.5 outside [0, 1]"),
      std::string::npos)
      << r.err;
  std::filesystem::remove(model);
}

TEST(Tools, GenerateRejectsABadMaterial) {
  const Result r = run(std::string(SINEW_GENERATE_EXE) + " box --material soft:3000:0.49 -o " +
                       sinew::formats::testing::temp_path("x.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--material: 'soft:3000:0.49' is not NAME:E:nu:rho"), std::string::npos)
      << r.err;
}

TEST(Tools, H5pyReadsTheFile) {
  // Any HDF5 reader must understand the file; h5py is the one users reach for.
  const std::string python = SINEW_PYTHON;
  if (python.empty() || run(python + " -c 'import h5py'").status != 0) {
    GTEST_SKIP() << "'" << python << "' has no h5py (scripts/install-deps installs python3-h5py)";
  }
  const std::string model = sinew::formats::testing::temp_path("model.h5");
  const std::string script = sinew::formats::testing::temp_path("read.py");
  sinew::formats::write_model(sinew::formats::testing::every_feature_model(), model);
  {
    std::ofstream py(script);
    py << R"(import sys, h5py
f = h5py.File(sys.argv[1], "r")
assert f.attrs["format"] == "sinew-model", f.attrs["format"]
assert int(f.attrs["format_version"]) == 3
assert f["jaw/nodes"].shape == (12,) and f["jaw/axis"].shape == (3,)
assert list(f["materials/name"].asstr()[:]) == ["fat", "muscle_tissue"]
assert list(f["surfaces/role"].asstr()[:]) == ["sliding", "visual"]
assert f["elements/nodes"].shape == (36, 8) and str(f["elements/nodes"].dtype) == "int32"
assert f["element_materials/offsets"].dtype == "int64" and f["element_materials/offsets"].shape == (37,)
assert abs(float(f["grid/voxel_size"][()]) - 0.001) < 1e-18
assert f["provenance/tool"].asstr()[()] == "formats test"
assert sorted(f["node_sets"].keys()) == sorted(["x_min", "x_max", "y_min", "y_max", "z_min", "z_max", "skull_contact"])
assert f["muscles/fibres"].shape == (24, 3)
print("ok")
)";
  }
  const Result r = run(python + " " + script + " " + model);
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_EQ(r.out, "ok\n");
  std::filesystem::remove(model);
  std::filesystem::remove(script);
}

}  // namespace
