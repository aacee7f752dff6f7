#include "sinew/simulator/output/results_writer.hpp"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"

namespace sinew::simulator {

namespace fs = std::filesystem;
namespace h5 = formats::hdf5;

std::vector<double> surface_positions(const formats::Model& model, const formats::Surface& surface,
                                      const std::vector<double>& u) {
  const std::size_t nv = surface.vertices.size();
  std::vector<double> x(nv * 3);
  for (std::size_t v = 0; v < nv; ++v) {
    const auto e = static_cast<std::size_t>(surface.embedding_element[v]);
    const auto& q = surface.embedding_local[v];
    const auto& nodes = model.element_nodes[e];
    double d[3] = {0, 0, 0};
    for (std::size_t a = 0; a < 8; ++a) {
      const auto& c = formats::kHexCorner[a];
      const double na = (1 + (2 * c[0] - 1) * q[0]) * (1 + (2 * c[1] - 1) * q[1]) *
                        (1 + (2 * c[2] - 1) * q[2]) / 8;
      const auto n = static_cast<std::size_t>(nodes[a]);
      for (std::size_t k = 0; k < 3; ++k) d[k] += na * u[3 * n + k];
    }
    for (std::size_t k = 0; k < 3; ++k) x[3 * v + k] = surface.vertices[v][k] + d[k];
  }
  return x;
}

struct ResultsWriter::Impl {
  h5::Handle file;
  h5::Handle time, step, displacement, von_mises, jacobian, energy_density;
  std::vector<h5::Handle> surfaces;               // positions per visual surface
  std::vector<h5::Handle> surface_displacements;  // displacement per visual surface

  // The datasets first: HDF5 closes a file only with its last open object.
  void close_datasets() {
    for (auto* h : {&time, &step, &displacement, &von_mises, &jacobian, &energy_density})
      h->reset();
    surfaces.clear();
    surface_displacements.clear();
  }
};

namespace {

std::string surface_group(const formats::Surface& s) {
  return "/surfaces/" + s.name;
}

// The group of frame f's views (virtual datasets, one frame of each series): the XDMF index and
// meshio name whole datasets only, so each frame's arrays need a name of their own.
std::string view_group(std::size_t f) {
  return "/frame_views/" + std::to_string(f);
}

// Surface names come from the model file; they must not break the index's XML.
std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::vector<std::int32_t> dominant_material(const formats::Model& model) {
  std::vector<std::int32_t> out(model.element_count(), -1);
  for (std::size_t e = 0; e < model.element_count(); ++e) {
    double best = 0;
    for (auto k = model.material_offsets[e]; k < model.material_offsets[e + 1]; ++k) {
      const auto i = static_cast<std::size_t>(k);
      if (model.material_fractions[i] > best) {
        best = model.material_fractions[i];
        out[e] = model.material_ids[i];
      }
    }
  }
  return out;
}

}  // namespace

ResultsWriter::ResultsWriter(const std::string& directory, const formats::Model& model,
                             ResultsOptions options)
    : ResultsWriter(Resume{}, directory, model, std::move(options)) {
  // What an earlier run in this folder left when its writing failed is not these results.
  std::error_code ec;
  fs::remove(h5_path_ + ".partial", ec);
  try {
    create();
  } catch (const Error& e) {
    abandon(e);
  }
}

void ResultsWriter::create() {
  const auto& model = model_;
  auto& f = impl_->file;
  f = h5::create_file(h5_path_);
  const auto& p = h5_path_;
  h5::set_attribute(f, "format", std::string(kResultsFormatName), p);
  h5::set_attribute(f, "format_version", std::int64_t{kResultsFormatVersion}, p);
  h5::set_attribute(f, "model_file", options_.model_file, p);
  h5::set_attribute(f, "scene_file", options_.scene_file, p);

  const auto n = static_cast<hsize_t>(model.node_count());
  const auto e = static_cast<hsize_t>(model.element_count());
  {
    auto mesh = h5::create_group(f, "/mesh", p);
    std::vector<double> x(model.node_count() * 3);
    for (std::size_t i = 0; i < model.node_count(); ++i) {
      const auto q = model.node_position(static_cast<formats::Index>(i));
      for (std::size_t k = 0; k < 3; ++k) x[3 * i + k] = q[k];
    }
    h5::write(f, "/mesh/rest_positions", {n, 3}, x.data(), p);
    std::vector<std::int32_t> conn(model.element_count() * 8);
    for (std::size_t i = 0; i < model.element_count(); ++i) {
      for (std::size_t a = 0; a < 8; ++a) conn[8 * i + a] = model.element_nodes[i][a];
    }
    h5::write(f, "/mesh/connectivity", {e, 8}, conn.data(), p);
    const auto mat = dominant_material(model);
    h5::write(f, "/mesh/material", {e}, mat.data(), p);
  }
  auto frames = h5::create_group(f, "/frames", p);
  impl_->time = h5::create_series<double>(f, "/frames/time", {}, p);
  impl_->step = h5::create_series<std::int64_t>(f, "/frames/step", {}, p);
  impl_->displacement = h5::create_series<double>(f, "/frames/displacement", {n, 3}, p);
  if (options_.stress) impl_->von_mises = h5::create_series<double>(f, "/frames/von_mises", {e}, p);
  if (options_.jacobian) impl_->jacobian = h5::create_series<double>(f, "/frames/J", {e}, p);
  if (options_.energy_density) {
    impl_->energy_density = h5::create_series<double>(f, "/frames/energy_density", {e}, p);
  }
  if (options_.surfaces && !visual_.empty()) {
    h5::create_group(f, "/surfaces", p);
    for (auto s : visual_) {
      const auto& surf = model.surfaces[s];
      const auto g = surface_group(surf);
      h5::create_group(f, g, p);
      std::vector<std::int32_t> tri(surf.triangles.size() * 3);
      for (std::size_t t = 0; t < surf.triangles.size(); ++t) {
        for (std::size_t k = 0; k < 3; ++k) tri[3 * t + k] = surf.triangles[t][k];
      }
      h5::write(f, g + "/triangles", {surf.triangles.size(), 3}, tri.data(), p);
      // Each vertex's element and natural coordinates, so that readers can interpolate element
      // fields (stress, J) to the surface (postprocess/element_fields.hpp).
      h5::write(f, g + "/embedding_element", {surf.embedding_element.size()},
                surf.embedding_element.data(), p);
      h5::write(f, g + "/embedding_local", {surf.embedding_local.size(), 3},
                reinterpret_cast<const double*>(surf.embedding_local.data()), p);
      if (!surf.uv_triangles.empty()) {
        // The artist's texture coordinates, for the exporters (model format: per triangle corner).
        static_assert(sizeof(formats::TexCoord) == 2 * sizeof(double));
        static_assert(sizeof(surf.uv_triangles[0]) == 3 * sizeof(std::int32_t));
        h5::write(f, g + "/uvs", {surf.uvs.size(), 2}, surf.uvs.front().data(), p);
        h5::write(f, g + "/uv_triangles", {surf.uv_triangles.size(), 3},
                  surf.uv_triangles.front().data(), p);
      }
      impl_->surfaces.push_back(
          h5::create_series<double>(f, g + "/positions", {surf.vertices.size(), 3}, p));
      impl_->surface_displacements.push_back(
          h5::create_series<double>(f, g + "/displacement", {surf.vertices.size(), 3}, p));
    }
  }
  h5::flush(f, p);
  write_index();
}

ResultsWriter::ResultsWriter(Resume, const std::string& directory, const formats::Model& model,
                             ResultsOptions options)
    : impl_(std::make_unique<Impl>()), model_(model), options_(std::move(options)) {
  h5_path_ = (fs::path(directory) / "results.h5").string();
  xdmf_path_ = (fs::path(directory) / "results.xdmf").string();
  if (options_.surfaces) {
    for (std::size_t s = 0; s < model.surfaces.size(); ++s) {
      if (model.surfaces[s].role == formats::SurfaceRole::visual) visual_.push_back(s);
    }
  }
}

std::unique_ptr<ResultsWriter> ResultsWriter::resume(const std::string& directory,
                                                     const formats::Model& model,
                                                     ResultsOptions options,
                                                     std::int64_t last_step) {
  std::unique_ptr<ResultsWriter> w(
      new ResultsWriter(Resume{}, directory, model, std::move(options)));
  const auto& p = w->h5_path_;
  auto& impl = *w->impl_;
  {
    // Read-only first: a damaged file must be refused before it is opened for writing. HDF5 1.10
    // can crash closing a writable file whose damaged metadata it acted on (freeing chunks at
    // damaged addresses: a fuzz case), never a read-only one.
    auto check = h5::open_file(p, false);
    std::vector<h5::ChunkExtent> chunks;
    const auto add = [&](const std::string& name) {
      if (!h5::exists(check, name)) return;
      auto extents = h5::chunk_extents(h5::open_dataset(check, name, p), p, name);
      chunks.insert(chunks.end(), extents.begin(), extents.end());
    };
    for (const auto* name : {"/frames/time", "/frames/step", "/frames/displacement",
                             "/frames/von_mises", "/frames/J", "/frames/energy_density"}) {
      add(name);
    }
    for (auto s : w->visual_) {
      add(surface_group(model.surfaces[s]) + "/positions");
      add(surface_group(model.surfaces[s]) + "/displacement");
    }
    h5::check_disjoint(std::move(chunks), p);
  }
  impl.file = h5::open_file(p, true);
  if (h5::string_attribute(impl.file, "format", p) != kResultsFormatName) {
    throw FormatError(p, "format", "not a sinew results file");
  }
  const auto shape = h5::shape(impl.file, "/mesh/rest_positions", p);
  if (shape.size() != 2 || shape[0] != model.node_count()) {
    throw FormatError(p, "/mesh/rest_positions",
                      "the results were written for another model (node count differs)");
  }
  const auto steps = h5::read<std::int64_t>(impl.file, "/frames/step", p);
  const auto times = h5::read<double>(impl.file, "/frames/time", p);
  std::size_t keep = 0;
  while (keep < steps.size() && steps[keep] <= last_step) ++keep;
  w->times_.assign(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(keep));
  const auto& o = w->options_;
  for (const auto& [wanted, name] :
       {std::pair{o.stress, "/frames/von_mises"}, std::pair{o.jacobian, "/frames/J"},
        std::pair{o.energy_density, "/frames/energy_density"}}) {
    if (wanted != h5::exists(impl.file, name)) {
      throw FormatError(
          p, name,
          wanted ? "the results to resume lack this field (the scene's output fields changed)"
                 : "the results to resume have a field the scene no longer asks for");
    }
  }
  // From here on the file is being changed: a failed write moves it away (abandon()). A
  // FormatError (results that do not fit the scene, above) leaves the user's file as it was.
  try {
    w->truncate_to(keep);
  } catch (const IoError& e) {
    w->abandon(e);
  }
  return w;
}

void ResultsWriter::truncate_to(std::size_t keep) {
  const auto& p = h5_path_;
  auto& impl = *impl_;
  const auto open = [&](const std::string& name) {
    auto ds = h5::open_dataset(impl.file, name, p);
    h5::set_frames(ds, keep, p, name);
    return ds;
  };
  impl.time = open("/frames/time");
  impl.step = open("/frames/step");
  impl.displacement = open("/frames/displacement");
  const auto field = [&](bool wanted, const std::string& name, h5::Handle& h) {
    if (wanted) h = open(name);
  };
  field(options_.stress, "/frames/von_mises", impl.von_mises);
  field(options_.jacobian, "/frames/J", impl.jacobian);
  field(options_.energy_density, "/frames/energy_density", impl.energy_density);
  for (auto s : visual_) {
    impl.surfaces.push_back(open(surface_group(model_.surfaces[s]) + "/positions"));
    impl.surface_displacements.push_back(open(surface_group(model_.surfaces[s]) + "/displacement"));
  }
  h5::flush(impl.file, p);
  write_index();
}

ResultsWriter::~ResultsWriter() = default;

void ResultsWriter::close() {
  if (closed_) return;
  try {
    impl_->close_datasets();
    h5::close_file(impl_->file, h5_path_);
  } catch (const Error& e) {
    abandon(e);
  }
  closed_ = true;
}

void ResultsWriter::abandon(const Error& e) {
  closed_ = true;
  impl_->close_datasets();
  impl_->file.reset();  // a close that fails too is part of the failure being reported
  std::error_code ec;
  std::string where;
  const auto partial = h5_path_ + ".partial";
  const auto frames = times_.size();
  if (frames > 0 && (fs::rename(h5_path_, partial, ec), !ec)) {
    where = fmt::format(
        "the results so far ({} complete frame{}) were moved to {}, which may not open (HDF5 had "
        "not finished writing it)",
        frames, frames == 1 ? "" : "s", partial);
  } else {
    fs::remove(h5_path_, ec);
    where = fmt::format("{} was removed{}", h5_path_,
                        frames == 0 ? " (it held no complete frame)" : "");
  }
  for (const auto& doc : xdmf_documents()) fs::remove(doc.first, ec);
  throw IoError(e.file(), e.field(),
                e.problem() + "; " + where + ", and the XDMF indexes naming it were removed");
}

void ResultsWriter::append_frame(double time, std::int64_t step, const std::vector<double>& u,
                                 const ElementFields& fields) {
  const auto& p = h5_path_;
  const auto n = model_.node_count();
  const auto e = model_.element_count();
  if (closed_) throw IoError(p, "", "the results file is closed: no more frames");
  if (u.size() != 3 * n)
    throw IoError(p, "/frames/displacement",
                  fmt::format("expected {} values, got {}", 3 * n, u.size()));
  const auto check = [&](bool on, const std::vector<double>& v, const char* name) {
    if (on && v.size() != e)
      throw IoError(p, name, fmt::format("expected {} element values, got {}", e, v.size()));
  };
  check(options_.stress, fields.von_mises, "/frames/von_mises");
  check(options_.jacobian, fields.jacobian, "/frames/J");
  check(options_.energy_density, fields.energy_density, "/frames/energy_density");
  try {
    write_frame(time, step, u, fields);
  } catch (const Error& err) {
    abandon(err);
  }
}

void ResultsWriter::write_frame(double time, std::int64_t step, const std::vector<double>& u,
                                const ElementFields& fields) {
  const auto& p = h5_path_;
  const auto f = static_cast<hsize_t>(times_.size());
  auto& impl = *impl_;
  h5::append(impl.displacement, f, u.data(), p, "/frames/displacement");
  if (options_.stress)
    h5::append(impl.von_mises, f, fields.von_mises.data(), p, "/frames/von_mises");
  if (options_.jacobian) h5::append(impl.jacobian, f, fields.jacobian.data(), p, "/frames/J");
  if (options_.energy_density) {
    h5::append(impl.energy_density, f, fields.energy_density.data(), p, "/frames/energy_density");
  }
  for (std::size_t i = 0; i < visual_.size(); ++i) {
    const auto& surf = model_.surfaces[visual_[i]];
    auto x = surface_positions(model_, surf, u);
    h5::append(impl.surfaces[i], f, x.data(), p, surface_group(surf) + "/positions");
    for (std::size_t v = 0; v < surf.vertices.size(); ++v) {
      for (std::size_t k = 0; k < 3; ++k) x[3 * v + k] -= surf.vertices[v][k];
    }
    h5::append(impl.surface_displacements[i], f, x.data(), p,
               surface_group(surf) + "/displacement");
  }
  const auto views = view_group(f);
  // A view names a frame index, not its data: after a resume the views of dropped frames (a killed
  // run may also have left some of a frame whose time it never wrote) show the new frame at their
  // index, so they stay. Deleting them would make HDF5 follow the global heap their mappings are
  // stored in, which no checksum covers (a damaged one hung H5Ldelete in the fuzz test).
  const auto view = [&](bool on, const std::string& series, const std::string& name) {
    if (on && !h5::exists(impl.file, views + "/" + name)) {
      h5::create_frame_view(impl.file, views + "/" + name, series, f, p);
    }
  };
  view(true, "/frames/displacement", "displacement");
  view(options_.stress, "/frames/von_mises", "von_mises");
  view(options_.jacobian, "/frames/J", "J");
  view(options_.energy_density, "/frames/energy_density", "energy_density");
  for (auto s : visual_) {
    const auto g = surface_group(model_.surfaces[s]);
    view(true, g + "/positions", g.substr(1) + "/positions");
    view(true, g + "/displacement", g.substr(1) + "/displacement");
  }
  // time and step last: a reader that sees the frame's time sees all of its data.
  h5::append(impl.step, f, &step, p, "/frames/step");
  h5::append(impl.time, f, &time, p, "/frames/time");
  h5::flush(impl.file, p);
  times_.push_back(time);
  write_index();
}

namespace {

// One temporal collection grid of an XDMF 3 document as meshio's TimeSeriesReader and ParaView's
// readers both take it: every DataItem names a whole dataset (meshio reads no hyperslabs), frame
// f's arrays being the views under /frame_views/f.
struct XdmfGrid {
  std::string name;
  std::string topology;  // the Topology element, with its DataItem
  // Per frame: the Geometry element and the attributes, the frame's group is substituted for {v}.
  std::string geometry;
  std::string attributes;
};

std::string data_item(const std::string& h5, const std::string& dataset, const std::string& dims,
                      const char* type, int precision) {
  return fmt::format(
      "<DataItem Dimensions=\"{}\" NumberType=\"{}\" Precision=\"{}\" "
      "Format=\"HDF\">{}:{}</DataItem>",
      dims, type, precision, h5, xml_escape(dataset));
}

std::string attribute(const char* name, const char* type, const char* center,
                      const std::string& item) {
  return fmt::format(
      "    <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"{}\">\n     {}\n"
      "    </Attribute>\n",
      name, type, center, item);
}

void write_grid(std::ostringstream& x, const XdmfGrid& g, const std::vector<double>& times) {
  x << fmt::format("  <Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
                   xml_escape(g.name));
  for (std::size_t f = 0; f < times.size(); ++f) {
    const auto views = view_group(f);
    const auto frame = [&](const std::string& text) {
      return fmt::format(fmt::runtime(text), fmt::arg("v", xml_escape(views)));
    };
    x << fmt::format("   <Grid Name=\"{}_{}\" GridType=\"Uniform\">\n", xml_escape(g.name), f)
      << fmt::format("    <Time Value=\"{:.17g}\"/>\n", times[f]) << g.topology << frame(g.geometry)
      << frame(g.attributes) << "   </Grid>\n";
  }
  x << "  </Grid>\n";
}

// Escapes fmt's braces in text that goes through write_grid's per-frame substitution.
std::string fmt_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    out += c;
    if (c == '{' || c == '}') out += c;
  }
  return out;
}

std::string xdmf_document(const std::vector<XdmfGrid>& grids, const std::vector<double>& times) {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n";
  for (const auto& g : grids) write_grid(x, g, times);
  x << " </Domain>\n</Xdmf>\n";
  return x.str();
}

}  // namespace

std::vector<std::pair<std::string, std::string>> ResultsWriter::xdmf_documents() const {
  const auto h5 = fs::path(h5_path_).filename().string();  // "results.h5": no braces, no XML
  const auto n = model_.node_count();
  const auto e = model_.element_count();
  XdmfGrid volume{"volume", "", "", ""};
  volume.topology = fmt::format(
      "    <Topology TopologyType=\"Hexahedron\" NumberOfElements=\"{}\">\n     {}\n"
      "    </Topology>\n",
      e, data_item(h5, "/mesh/connectivity", fmt::format("{} 8", e), "Int", 4));
  volume.geometry = fmt_escape(
      fmt::format("    <Geometry GeometryType=\"XYZ\">\n     {}\n    </Geometry>\n",
                  data_item(h5, "/mesh/rest_positions", fmt::format("{} 3", n), "Float", 8)));
  volume.attributes =
      fmt_escape(attribute("material", "Scalar", "Cell",
                           data_item(h5, "/mesh/material", std::to_string(e), "Int", 4))) +
      attribute("displacement", "Vector", "Node",
                data_item(h5, "{v}/displacement", fmt::format("{} 3", n), "Float", 8));
  const auto cell = [&](bool on, const char* name) {
    if (on) {
      volume.attributes +=
          attribute(name, "Scalar", "Cell",
                    data_item(h5, fmt::format("{{v}}/{}", name), std::to_string(e), "Float", 8));
    }
  };
  cell(options_.stress, "von_mises");
  cell(options_.jacobian, "J");
  cell(options_.energy_density, "energy_density");

  std::vector<std::pair<std::string, std::string>> docs;
  std::vector<XdmfGrid> all;
  for (auto s : visual_) {
    const auto& surf = model_.surfaces[s];
    const auto g = fmt_escape(surface_group(surf).substr(1));
    const auto v = fmt::format("{} 3", surf.vertices.size());
    XdmfGrid grid{"surface_" + surf.name, "", "", ""};
    grid.topology = fmt::format(
        "    <Topology TopologyType=\"Triangle\" NumberOfElements=\"{}\">\n     {}\n"
        "    </Topology>\n",
        surf.triangles.size(),
        data_item(h5, surface_group(surf) + "/triangles",
                  fmt::format("{} 3", surf.triangles.size()), "Int", 4));
    grid.geometry = "    <Geometry GeometryType=\"XYZ\">\n     " +
                    data_item(h5, "{v}/" + g + "/positions", v, "Float", 8) + "\n    </Geometry>\n";
    grid.attributes = attribute("displacement", "Vector", "Node",
                                data_item(h5, "{v}/" + g + "/displacement", v, "Float", 8));
    docs.emplace_back(
        (fs::path(xdmf_path_).parent_path() / ("results_surface_" + surf.name + ".xdmf")).string(),
        xdmf_document({grid}, times_));
    all.push_back(std::move(grid));
  }
  // The volume last: meshio's TimeSeriesReader reads the last temporal collection of a document.
  all.push_back(std::move(volume));
  docs.emplace(docs.begin(), xdmf_path_, xdmf_document(all, times_));
  return docs;
}

std::string ResultsWriter::xdmf_text() const {
  return xdmf_documents().front().second;
}

void ResultsWriter::write_index() const {
  for (const auto& [path, text] : xdmf_documents()) write_text_atomically(path, text);
}

}  // namespace sinew::simulator
