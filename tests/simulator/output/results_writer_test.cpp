// The writers of a run: results.h5 read back with the HDF5 C API, the XDMF index checked as XML
// against the datasets it names, frames kept by an interrupted process, resuming, probe CSVs, the
// JSON run summary (checkpoints: engine/checkpoint_test.cpp).
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdint>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/output/probes.hpp"
#include "sinew/simulator/output/results_writer.hpp"
#include "sinew/simulator/run/run_summary.hpp"

namespace sinew::simulator {
namespace {

using testing::read_file;
using testing::small_box;
using testing::TempDir;
using testing::write_file;

// ---- raw HDF5 reading (independent of the writer's helpers) ----

std::vector<hsize_t> dims_of(hid_t file, const std::string& name) {
  const hid_t ds = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  EXPECT_GE(ds, 0) << name;
  if (ds < 0) return {};
  const hid_t space = H5Dget_space(ds);
  std::vector<hsize_t> d(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
  H5Sget_simple_extent_dims(space, d.data(), nullptr);
  H5Sclose(space);
  H5Dclose(ds);
  return d;
}

template <typename T>
std::vector<T> read_all(hid_t file, const std::string& name, hid_t type) {
  hsize_t n = 1;
  for (auto d : dims_of(file, name)) n *= d;
  std::vector<T> v(n);
  const hid_t ds = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (n > 0) {
    EXPECT_GE(H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0) << name;
  }
  H5Dclose(ds);
  return v;
}

// A linear displacement field u = G X (+ c): trilinear interpolation reproduces it exactly.
std::vector<double> linear_field(const formats::Model& m, double scale) {
  std::vector<double> u(m.node_count() * 3);
  for (std::size_t i = 0; i < m.node_count(); ++i) {
    const auto x = m.node_position(formats::Index(i));
    u[3 * i] = scale * (0.1 * x[0] + 0.2 * x[2]) + 1e-4;
    u[3 * i + 1] = scale * (-0.05 * x[1]);
    u[3 * i + 2] = scale * (0.3 * x[0] - 0.1 * x[2]) - 2e-4;
  }
  return u;
}

ElementFields fields_for(const formats::Model& m, double f) {
  ElementFields e;
  for (std::size_t i = 0; i < m.element_count(); ++i) {
    e.von_mises.push_back(100.0 * f + double(i));
    e.jacobian.push_back(1.0 - 0.01 * f);
    e.energy_density.push_back(0.5 * f * double(i));
  }
  return e;
}

ResultsOptions all_fields() {
  ResultsOptions o;
  o.stress = o.jacobian = o.energy_density = o.surfaces = true;
  o.model_file = "box.h5";
  o.scene_file = "box.yaml";
  return o;
}

// ---- a minimal XML reader: checks well-formedness and collects elements ----

struct XmlElement {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;
  std::vector<int> children;
  int parent = -1;
};

// Parses the subset of XML the index uses (declaration, DOCTYPE, elements, attributes, text).
// Returns false on any malformation (unbalanced tags, bad attribute syntax, text after the root).
bool parse_xml(const std::string& s, std::vector<XmlElement>& out, std::string& why) {
  std::size_t i = 0;
  std::vector<int> stack;
  bool root_done = false;
  const auto skip_ws = [&] {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  };
  while (i < s.size()) {
    if (s[i] != '<') {
      const auto end = s.find('<', i);
      const auto text = s.substr(i, end == std::string::npos ? std::string::npos : end - i);
      if (stack.empty()) {
        if (text.find_first_not_of(" \t\r\n") != std::string::npos)
          return why = "text outside the root", false;
      } else {
        out[std::size_t(stack.back())].text += text;
      }
      if (end == std::string::npos) break;
      i = end;
      continue;
    }
    if (s.compare(i, 2, "<?") == 0) {
      const auto end = s.find("?>", i);
      if (end == std::string::npos) return why = "unterminated declaration", false;
      i = end + 2;
      continue;
    }
    if (s.compare(i, 2, "<!") == 0) {
      const auto end = s.find('>', i);
      if (end == std::string::npos) return why = "unterminated DOCTYPE", false;
      i = end + 1;
      continue;
    }
    if (s.compare(i, 2, "</") == 0) {
      const auto end = s.find('>', i);
      if (end == std::string::npos) return why = "unterminated end tag", false;
      const auto name = s.substr(i + 2, end - i - 2);
      if (stack.empty() || out[std::size_t(stack.back())].name != name)
        return why = "mismatched </" + name + ">", false;
      stack.pop_back();
      if (stack.empty()) root_done = true;
      i = end + 1;
      continue;
    }
    if (root_done) return why = "a second root element", false;
    ++i;
    XmlElement e;
    while (i < s.size() &&
           (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_' || s[i] == ':'))
      e.name += s[i++];
    if (e.name.empty()) return why = "empty tag name", false;
    bool self_closing = false;
    while (true) {
      skip_ws();
      if (i >= s.size()) return why = "unterminated tag", false;
      if (s[i] == '>') {
        ++i;
        break;
      }
      if (s.compare(i, 2, "/>") == 0) {
        i += 2;
        self_closing = true;
        break;
      }
      std::string key;
      while (i < s.size() &&
             (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_' || s[i] == ':'))
        key += s[i++];
      if (key.empty() || i >= s.size() || s[i] != '=')
        return why = "bad attribute in <" + e.name + ">", false;
      ++i;
      if (i >= s.size() || s[i] != '"') return why = "unquoted attribute " + key, false;
      const auto close = s.find('"', i + 1);
      if (close == std::string::npos) return why = "unterminated attribute " + key, false;
      const auto value = s.substr(i + 1, close - i - 1);
      if (value.find('<') != std::string::npos) return why = "'<' in attribute " + key, false;
      if (!e.attributes.emplace(key, value).second)
        return why = "duplicate attribute " + key, false;
      i = close + 1;
    }
    e.parent = stack.empty() ? -1 : stack.back();
    out.push_back(e);
    const int id = int(out.size()) - 1;
    if (e.parent >= 0) out[std::size_t(e.parent)].children.push_back(id);
    if (!self_closing) {
      stack.push_back(id);
    } else if (stack.empty()) {
      root_done = true;
    }
  }
  if (!stack.empty()) return why = "unclosed <" + out[std::size_t(stack.back())].name + ">", false;
  if (!root_done) return why = "no root element", false;
  return true;
}

std::vector<hsize_t> parse_dims(const std::string& s) {
  std::istringstream in(s);
  std::vector<hsize_t> d;
  hsize_t v;
  while (in >> v) d.push_back(v);
  return d;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  const auto b = s.find_last_not_of(" \t\r\n");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

// Every HDF DataItem names an existing dataset of the stated shape; every hyperslab selects one
// frame inside it with the stated result shape. Returns the number of temporal grids per
// collection name.
std::map<std::string, int> check_xdmf(const std::string& xdmf_path, const std::string& h5_path) {
  std::vector<XmlElement> xml;
  std::string why;
  EXPECT_TRUE(parse_xml(read_file(xdmf_path), xml, why)) << why;
  std::map<std::string, int> grids;
  if (xml.empty()) return grids;
  EXPECT_EQ(xml[0].name, "Xdmf");
  const hid_t f = H5Fopen(h5_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0);
  for (const auto& e : xml) {
    if (e.name == "Grid" && e.attributes.count("CollectionType") &&
        e.attributes.at("CollectionType") == "Temporal") {
      int n = 0;
      for (int c : e.children) {
        const auto& g = xml[std::size_t(c)];
        if (g.name != "Grid") continue;
        ++n;
        bool has_time = false, has_topology = false, has_geometry = false;
        for (int k : g.children) {
          has_time |= xml[std::size_t(k)].name == "Time";
          has_topology |= xml[std::size_t(k)].name == "Topology";
          has_geometry |= xml[std::size_t(k)].name == "Geometry";
        }
        EXPECT_TRUE(has_time && has_topology && has_geometry) << g.attributes.at("Name");
      }
      grids[e.attributes.at("Name")] = n;
    }
    if (e.name != "DataItem") continue;
    if (e.attributes.count("Format") && e.attributes.at("Format") == "HDF") {
      const auto ref = trim(e.text);
      const auto colon = ref.find(':');
      EXPECT_EQ(ref.substr(0, colon), "results.h5");
      const auto dataset = ref.substr(colon + 1);
      EXPECT_EQ(dims_of(f, dataset), parse_dims(e.attributes.at("Dimensions"))) << dataset;
    }
    if (e.attributes.count("ItemType") && e.attributes.at("ItemType") == "HyperSlab") {
      EXPECT_EQ(e.children.size(), 2u);
      if (e.children.size() != 2) continue;
      const auto& sel = xml[std::size_t(e.children[0])];
      const auto& data = xml[std::size_t(e.children[1])];
      const auto full = parse_dims(data.attributes.at("Dimensions"));
      const auto rows = parse_dims(trim(sel.text));
      const auto rank = full.size();
      EXPECT_EQ(parse_dims(sel.attributes.at("Dimensions")), (std::vector<hsize_t>{3, rank}));
      EXPECT_EQ(rows.size(), 3 * rank);
      if (rows.size() != 3 * rank) continue;
      std::vector<hsize_t> count(rows.begin() + std::ptrdiff_t(2 * rank), rows.end());
      EXPECT_EQ(parse_dims(e.attributes.at("Dimensions")), count);
      for (std::size_t k = 0; k < rank; ++k)
        EXPECT_LE(rows[k] + count[k], full[k]) << "slab outside the dataset";
    }
  }
  H5Fclose(f);
  return grids;
}

TEST(ResultsWriter, WritesFramesThatReadBack) {
  TempDir dir("results");
  const auto model = small_box(false, true);
  const auto n = model.node_count(), e = model.element_count();
  {
    ResultsWriter w(dir.str(), model, all_fields());
    for (int f = 0; f < 3; ++f)
      w.append_frame(0.1 * f, 10 * f, linear_field(model, f), fields_for(model, f));
    EXPECT_EQ(w.frame_count(), 3);
  }
  const hid_t file = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  EXPECT_EQ(dims_of(file, "/mesh/rest_positions"), (std::vector<hsize_t>{n, 3}));
  EXPECT_EQ(dims_of(file, "/mesh/connectivity"), (std::vector<hsize_t>{e, 8}));
  EXPECT_EQ(dims_of(file, "/mesh/material"), (std::vector<hsize_t>{e}));
  EXPECT_EQ(dims_of(file, "/frames/displacement"), (std::vector<hsize_t>{3, n, 3}));
  EXPECT_EQ(dims_of(file, "/frames/von_mises"), (std::vector<hsize_t>{3, e}));
  EXPECT_EQ(dims_of(file, "/frames/J"), (std::vector<hsize_t>{3, e}));
  EXPECT_EQ(dims_of(file, "/frames/energy_density"), (std::vector<hsize_t>{3, e}));
  EXPECT_EQ(dims_of(file, "/surfaces/skin/positions"), (std::vector<hsize_t>{3, 4, 3}));
  EXPECT_EQ(dims_of(file, "/surfaces/skin/triangles"), (std::vector<hsize_t>{2, 3}));

  const auto time = read_all<double>(file, "/frames/time", H5T_NATIVE_DOUBLE);
  EXPECT_EQ(time, (std::vector<double>{0.0, 0.1, 0.2}));
  const auto step = read_all<std::int64_t>(file, "/frames/step", H5T_NATIVE_INT64);
  EXPECT_EQ(step, (std::vector<std::int64_t>{0, 10, 20}));
  const auto u = read_all<double>(file, "/frames/displacement", H5T_NATIVE_DOUBLE);
  const auto u2 = linear_field(model, 2);
  for (std::size_t k = 0; k < u2.size(); ++k) ASSERT_EQ(u[2 * n * 3 + k], u2[k]);
  const auto x = read_all<double>(file, "/mesh/rest_positions", H5T_NATIVE_DOUBLE);
  EXPECT_DOUBLE_EQ(x[3 * (n - 1)], 0.04);
  const auto conn = read_all<std::int32_t>(file, "/mesh/connectivity", H5T_NATIVE_INT32);
  for (std::size_t a = 0; a < 8; ++a) EXPECT_EQ(conn[8 * 5 + a], model.element_nodes[5][a]);
  const auto mat = read_all<std::int32_t>(file, "/mesh/material", H5T_NATIVE_INT32);
  EXPECT_EQ(mat, std::vector<std::int32_t>(e, 0));
  const auto vm = read_all<double>(file, "/frames/von_mises", H5T_NATIVE_DOUBLE);
  EXPECT_DOUBLE_EQ(vm[e + 7], 107.0);

  // Surface vertices: X + u(X) for the linear field, exactly up to round-off.
  const auto pos = read_all<double>(file, "/surfaces/skin/positions", H5T_NATIVE_DOUBLE);
  const auto& skin = model.surfaces[0];
  for (std::size_t v = 0; v < 4; ++v) {
    const auto& X = skin.vertices[v];
    const double expect[3] = {X[0] + 2 * (0.1 * X[0] + 0.2 * X[2]) + 1e-4,
                              X[1] + 2 * (-0.05 * X[1]),
                              X[2] + 2 * (0.3 * X[0] - 0.1 * X[2]) - 2e-4};
    for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(pos[2 * 12 + 3 * v + k], expect[k], 1e-15);
  }
  H5Fclose(file);

  const auto grids = check_xdmf(dir / "results.xdmf", dir / "results.h5");
  EXPECT_EQ(grids.at("volume"), 3);
  EXPECT_EQ(grids.at("surface_skin"), 3);
}

TEST(ResultsWriter, SurfaceInterpolationUsesTrilinearShapeFunctions) {
  // A vertex inside an element: x = X + Σ Na(ξ) ua; with u nonzero at one node only, the
  // displacement is that node's shape function value.
  const auto model = small_box(false, false, 1, 1, 1, 0.01);
  formats::Surface s;
  s.role = formats::SurfaceRole::visual;
  s.vertices = {{0.0025, 0.005, 0.0075}};
  s.triangles = {};
  s.embedding_element = {0};
  s.embedding_local = {{-0.5, 0.0, 0.5}};
  std::vector<double> u(model.node_count() * 3, 0.0);
  const auto node6 = std::size_t(model.element_nodes[0][6]);  // corner (1, 1, 1)
  u[3 * node6 + 2] = 1.0;
  const auto x = surface_positions(model, s, u);
  // N6 = (1 + ξ)(1 + η)(1 + ζ) / 8 = 0.5 · 1 · 1.5 / 8.
  EXPECT_DOUBLE_EQ(x[2] - 0.0075, 0.5 * 1.0 * 1.5 / 8);
  EXPECT_DOUBLE_EQ(x[0], 0.0025);
}

TEST(ResultsWriter, OnlyRequestedFieldsAreWritten) {
  TempDir dir("results_min");
  const auto model = small_box();
  ResultsOptions o;
  {
    ResultsWriter w(dir.str(), model, o);
    w.append_frame(0, 0, std::vector<double>(model.node_count() * 3, 0.0), {});
  }
  const hid_t file = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GT(H5Lexists(file, "/frames/displacement", H5P_DEFAULT), 0);
  EXPECT_EQ(H5Lexists(file, "/frames/von_mises", H5P_DEFAULT), 0);
  EXPECT_EQ(H5Lexists(file, "/surfaces", H5P_DEFAULT), 0);
  H5Fclose(file);
  const auto grids = check_xdmf(dir / "results.xdmf", dir / "results.h5");
  EXPECT_EQ(grids.size(), 1u);
  EXPECT_EQ(read_file(dir / "results.xdmf").find("von_mises"), std::string::npos);
}

TEST(ResultsWriter, WrongSizesAreRefused) {
  TempDir dir("results_bad");
  const auto model = small_box();
  ResultsOptions o;
  o.stress = true;
  ResultsWriter w(dir.str(), model, o);
  EXPECT_THROW(w.append_frame(0, 0, std::vector<double>(5, 0.0), {}), IoError);
  EXPECT_THROW(w.append_frame(0, 0, std::vector<double>(model.node_count() * 3, 0.0), {}), IoError);
}

TEST(ResultsWriter, AKilledProcessKeepsEveryFrameItFlushed) {
  TempDir dir("results_kill");
  const auto model = small_box(false, true);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The child writes two frames and dies without closing anything (no destructors run).
    auto* w = new ResultsWriter(dir.str(), model, all_fields());
    for (int f = 0; f < 2; ++f)
      w->append_frame(0.5 * f, f, linear_field(model, f), fields_for(model, f));
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  const hid_t file = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0) << "the file of a killed writer must open";
  EXPECT_EQ(dims_of(file, "/frames/displacement")[0], 2u);
  const auto u = read_all<double>(file, "/frames/displacement", H5T_NATIVE_DOUBLE);
  const auto u1 = linear_field(model, 1);
  for (std::size_t k = 0; k < u1.size(); ++k) ASSERT_EQ(u[u1.size() + k], u1[k]);
  H5Fclose(file);
  const auto grids = check_xdmf(dir / "results.xdmf", dir / "results.h5");
  EXPECT_EQ(grids.at("volume"), 2);
}

// A write that fails part way (a full disk; here a file-size limit, which fails HDF5's writes as
// ENOSPC does) never leaves results.h5 under its name: a full disk left one that failed to open
// ("addr overflow": issue 33). With no complete frame it is removed, else moved to
// results.h5.partial; the XDMF indexes naming it go, and the error says so.
TEST(ResultsWriter, AFailedWriteLeavesNoResultsUnderTheirName) {
  const auto model = small_box(false, true);
  for (const rlim_t limit : {rlim_t{4096}, rlim_t{96 * 1024}}) {
    TempDir dir("results_full_" + std::to_string(limit));
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      std::signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails with EFBIG instead
      const rlimit r{limit, limit};
      setrlimit(RLIMIT_FSIZE, &r);
      int frames = 0;
      try {
        ResultsWriter w(dir.str(), model, all_fields());
        for (; frames < 1000; ++frames)
          w.append_frame(0.5 * frames, frames, linear_field(model, frames),
                         fields_for(model, frames));
      } catch (const IoError& e) {
        const std::string m = e.what();
        const bool said =
            m.find(frames == 0 ? "was removed" : "results.h5.partial") != std::string::npos;
        _exit(said ? (frames == 0 ? 10 : 11) : 2);
      }
      _exit(1);  // 1000 frames under the limit: the limit did not bite
    }
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << limit;
    const int code = WEXITSTATUS(status);
    ASSERT_TRUE(code == 10 || code == 11) << "limit " << limit << ": child status " << code;
    EXPECT_FALSE(std::filesystem::exists(dir / "results.h5")) << limit;
    EXPECT_FALSE(std::filesystem::exists(dir / "results.xdmf")) << limit;
    EXPECT_FALSE(std::filesystem::exists(dir / "results_surface_skin.xdmf")) << limit;
    EXPECT_EQ(std::filesystem::exists(dir / "results.h5.partial"), code == 11) << limit;
    for (const auto& entry : std::filesystem::directory_iterator(dir.str()))
      EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << entry.path();
  }
}

TEST(ResultsWriter, ResumeDropsFramesAfterTheCheckpoint) {
  TempDir dir("results_resume");
  const auto model = small_box(false, true);
  {
    ResultsWriter w(dir.str(), model, all_fields());
    for (int f = 0; f < 4; ++f)
      w.append_frame(0.1 * f, 10 * f, linear_field(model, f), fields_for(model, f));
  }
  {
    auto w = ResultsWriter::resume(dir.str(), model, all_fields(), 15);
    EXPECT_EQ(w->frame_count(), 2);
    w->append_frame(0.17, 17, linear_field(model, 7), fields_for(model, 7));
  }
  const hid_t file = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_EQ(read_all<std::int64_t>(file, "/frames/step", H5T_NATIVE_INT64),
            (std::vector<std::int64_t>{0, 10, 17}));
  EXPECT_EQ(dims_of(file, "/frames/J")[0], 3u);
  EXPECT_EQ(dims_of(file, "/surfaces/skin/positions")[0], 3u);
  H5Fclose(file);
  check_xdmf(dir / "results.xdmf", dir / "results.h5");
  // Another model, or other fields, are refused.
  EXPECT_THROW(ResultsWriter::resume(dir.str(), small_box(false, true, 2, 2, 2), all_fields(), 15),
               FormatError);
  ResultsOptions fewer = all_fields();
  fewer.stress = false;
  EXPECT_THROW(ResultsWriter::resume(dir.str(), model, fewer, 15), FormatError);
}

// A chunk address damaged to point into another series' chunk (one flipped byte in a fuzz case):
// resuming would free it, and HDF5 1.10 crashed closing the file. The resume checks the series'
// chunks read-only first and refuses the file, which stays as it was.
TEST(ResultsWriter, ResumeRefusesOverlappingChunks) {
  TempDir dir("results_resume_overlap");
  const auto model = small_box(false, true);
  {
    ResultsWriter w(dir.str(), model, all_fields());
    for (int f = 0; f < 3; ++f)
      w.append_frame(0.1 * f, 10 * f, linear_field(model, f), fields_for(model, f));
  }
  const std::string path = dir / "results.h5";
  const auto chunk_address = [&](const char* name, hsize_t index) {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    const hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    const hid_t space = H5Dget_space(ds);
    haddr_t addr = 0;
    hsize_t size = 0;
    EXPECT_GE(H5Dget_chunk_info(ds, space, index, nullptr, nullptr, &addr, &size), 0);
    H5Sclose(space);
    H5Dclose(ds);
    H5Fclose(f);
    return addr;
  };
  const haddr_t j = chunk_address("/frames/J", 2), v = chunk_address("/frames/von_mises", 2);
  std::string bytes = read_file(path);
  const auto le = [](haddr_t a) {
    std::string out(8, '\0');
    for (int k = 0; k < 8; ++k) out[std::size_t(k)] = char((a >> (8 * k)) & 0xff);
    return out;
  };
  const auto at = bytes.find(le(j));
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, 8, le(v + 8));  // J's last chunk now starts inside von Mises' last one
  write_file(path, bytes);
  try {
    ResultsWriter::resume(dir.str(), model, all_fields(), 15);
    ADD_FAILURE() << "resumed a file with overlapping chunks";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("overlaps one of"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_file(path), bytes);  // not opened for writing
}

TEST(ResultsWriter, FrameViewsShowOneFrameEachAndFollowAResume) {
  // /frame_views/<f>/... are virtual datasets of frame f (what the XDMF files name, for meshio);
  // after a resume they show the new frames written at the dropped frames' indices.
  TempDir dir("results_views");
  const auto model = small_box(false, true);
  const auto& skin = model.surfaces[0];
  {
    ResultsWriter w(dir.str(), model, all_fields());
    for (int f = 0; f < 3; ++f)
      w.append_frame(0.1 * f, 10 * f, linear_field(model, f), fields_for(model, f));
    const auto docs = w.xdmf_documents();
    ASSERT_EQ(docs.size(), 2u);
    EXPECT_EQ(docs[0].first, w.xdmf_path());
    EXPECT_EQ(docs[1].first, dir / "results_surface_skin.xdmf");
    EXPECT_NE(docs[1].second.find("/frame_views/2/surfaces/skin/displacement"), std::string::npos);
    EXPECT_EQ(docs[1].second.find("volume"), std::string::npos);
    // meshio reads the last temporal collection of results.xdmf: the volume's.
    EXPECT_GT(docs[0].second.rfind("Name=\"volume\""), docs[0].second.rfind("surface_skin"));
  }
  {
    auto w = ResultsWriter::resume(dir.str(), model, all_fields(), 15);
    w->append_frame(0.17, 17, linear_field(model, 7), fields_for(model, 7));
  }
  const hid_t file = H5Fopen((dir / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  EXPECT_EQ(read_all<double>(file, "/frame_views/1/displacement", H5T_NATIVE_DOUBLE),
            linear_field(model, 1));
  EXPECT_EQ(read_all<double>(file, "/frame_views/2/displacement", H5T_NATIVE_DOUBLE),
            linear_field(model, 7));
  EXPECT_EQ(read_all<double>(file, "/frame_views/2/von_mises", H5T_NATIVE_DOUBLE),
            fields_for(model, 7).von_mises);
  // Frame 3 was dropped and not written again: its view is left, and no index names it.
  EXPECT_EQ(read_file(dir / "results.xdmf").find("/frame_views/3/"), std::string::npos);
  const auto positions = read_all<double>(file, "/surfaces/skin/positions", H5T_NATIVE_DOUBLE);
  const auto shown =
      read_all<double>(file, "/frame_views/2/surfaces/skin/positions", H5T_NATIVE_DOUBLE);
  const auto moved =
      read_all<double>(file, "/frame_views/2/surfaces/skin/displacement", H5T_NATIVE_DOUBLE);
  ASSERT_EQ(shown.size(), 12u);
  ASSERT_EQ(moved.size(), 12u);
  for (std::size_t v = 0; v < 4; ++v) {
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(shown[3 * v + k], positions[2 * 12 + 3 * v + k]);
      EXPECT_DOUBLE_EQ(moved[3 * v + k], shown[3 * v + k] - skin.vertices[v][k]);
    }
  }
  H5Fclose(file);
  const auto grids = check_xdmf(dir / "results_surface_skin.xdmf", dir / "results.h5");
  EXPECT_EQ(grids.at("surface_skin"), 3);
}

// ---- probes ----

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string l;
  while (std::getline(in, l)) out.push_back(l);
  return out;
}

TEST(ProbeWriter, WritesOneCsvPerProbeThatReadsBackExactly) {
  TempDir dir("probes");
  std::vector<ResolvedProbe> probes(2);
  probes[0].kind = SceneProbe::Kind::displacement;
  probes[0].name = "tip";
  probes[0].nodes = {1};
  probes[1].kind = SceneProbe::Kind::reaction;
  probes[1].name = "base";
  probes[1].nodes = {0, 1};
  const std::vector<double> u{0, 0, 0, 0.1, 1.0 / 3.0, -2e-7};
  int calls = 0;
  {
    ProbeWriter w(dir.str(), probes);
    for (int s = 0; s < 3; ++s) {
      w.record(0.25 * s, s, u, [&](const std::vector<Index>& nodes) {
        ++calls;
        EXPECT_EQ(nodes.size(), 2u);
        return std::array<double, 3>{double(s), -1.5, 1e300};
      });
    }
    // Rows are on disk before the writer closes.
    EXPECT_EQ(lines_of(read_file(dir / "probe_tip.csv")).size(), 4u);
  }
  EXPECT_EQ(calls, 3);
  const auto tip = lines_of(read_file(dir / "probe_tip.csv"));
  ASSERT_EQ(tip.size(), 4u);
  EXPECT_EQ(tip[0], "time,step,ux,uy,uz");
  double t, ux, uy, uz;
  long long step;
  ASSERT_EQ(std::sscanf(tip[3].c_str(), "%lf,%lld,%lf,%lf,%lf", &t, &step, &ux, &uy, &uz), 5);
  EXPECT_EQ(t, 0.5);
  EXPECT_EQ(step, 2);
  EXPECT_EQ(uy, 1.0 / 3.0);  // 17 significant digits round-trip
  EXPECT_EQ(uz, -2e-7);
  const auto base = lines_of(read_file(dir / "probe_base.csv"));
  EXPECT_EQ(base[0], "time,step,fx,fy,fz");
  EXPECT_EQ(base[2], "0.25,1,1,-1.5,1.0000000000000001e+300");
}

TEST(ProbeWriter, ResumeKeepsRowsUpToTheCheckpoint) {
  TempDir dir("probes_resume");
  std::vector<ResolvedProbe> probes(1);
  probes[0].name = "tip";
  probes[0].nodes = {0};
  const std::vector<double> u{1, 2, 3};
  const ProbeWriter::Reaction none;
  {
    ProbeWriter w(dir.str(), probes);
    for (int s = 0; s < 5; ++s) w.record(s, s, u, none);
  }
  // A row cut short by a crash is dropped too.
  testing::write_file(dir / "probe_tip.csv", read_file(dir / "probe_tip.csv") + "5,5,1,2");
  {
    auto w = ProbeWriter::resume(dir.str(), probes, 2);
    w->record(3.5, 3, u, none);
  }
  const auto rows = lines_of(read_file(dir / "probe_tip.csv"));
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[3], "2,2,1,2,3");
  EXPECT_EQ(rows[4], "3.5,3,1,2,3");
  probes[0].kind = SceneProbe::Kind::reaction;
  EXPECT_THROW(ProbeWriter::resume(dir.str(), probes, 2), FormatError);
  probes[0].name = "gone";
  EXPECT_THROW(ProbeWriter::resume(dir.str(), probes, 2), FormatError);
}

// ---- run summary ----

TEST(RunSummary, WritesJsonWithEveryKey) {
  TempDir dir("summary");
  RunSummary s;
  s.status = "completed";
  s.device = "cpu (OpenMP, 2 threads)";
  s.precision = "double";
  s.effects = {"elasticity", "damping"};
  s.dt = 1e-5;
  s.dt_reason = "automatic";
  s.steps_done = 100;
  s.warnings = {"mass scaling 4"};
  Energies e;
  e.step = 50;
  e.time = 5e-4;
  e.kinetic = 1.5;
  e.strain = std::numeric_limits<double>::quiet_NaN();
  s.energies = {e};
  write_run_summary(dir / "run_summary.json", s);
  const auto j = nlohmann::json::parse(read_file(dir / "run_summary.json"));
  for (const char* key : {"status",         "message",         "scene_file",    "model_file",
                          "device",         "precision",       "threads",       "effects",
                          "duration_s",     "time_scaling",    "mass_scaling",  "dt_s",
                          "dt_critical_s",  "dt_reason",       "steps_planned", "steps_done",
                          "steps_this_run", "restart_step",    "restart_file",  "simulated_time_s",
                          "wall_time_s",    "time_per_step_s", "frames",        "energies",
                          "warnings"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["status"], "completed");
  EXPECT_EQ(j["steps_done"], 100);
  EXPECT_EQ(j["effects"][1], "damping");
  EXPECT_EQ(j["energies"][0]["kinetic_J"], 1.5);
  EXPECT_TRUE(j["energies"][0]["strain_J"].is_null());  // NaN is not JSON
  const auto history = read_energy_history(dir / "run_summary.json");
  ASSERT_EQ(history.size(), 1u);
  EXPECT_EQ(history[0].step, 50);
  EXPECT_EQ(history[0].kinetic, 1.5);
  EXPECT_TRUE(read_energy_history(dir / "missing.json").empty());
}

}  // namespace
}  // namespace sinew::simulator
