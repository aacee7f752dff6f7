#pragma once
// Simulation results: one HDF5 file (results.h5) that grows a frame at a time, and an XDMF 3 index
// (results.xdmf) that ParaView and meshio open as a temporal collection of hexahedral grids, plus
// one temporal collection of triangle grids per visual surface (also alone in
// results_surface_<name>.xdmf, for meshio, which reads one collection per file).
// docs/results-format.md documents every dataset.
//
// Layout (F frames, N nodes, E elements, V vertices / T triangles of a surface):
//   /mesh/rest_positions      F64 N × 3, m
//   /mesh/connectivity        I32 E × 8, hex8 (VTK) order
//   /mesh/material            I32 E, dominant material (largest fraction), −1 where none
//   /frames/time              F64 F, s of scene time
//   /frames/step              I64 F, engine step index
//   /frames/displacement      F64 F × N × 3, m
//   /frames/von_mises         F64 F × E, Pa           (field "stress")
//   /frames/J                 F64 F × E               (field "J")
//   /frames/energy_density    F64 F × E, J/m³         (field "energy_density")
//   /surfaces/<name>/triangles  I32 T × 3
//   /surfaces/<name>/positions  F64 F × V × 3, m      (field "surfaces")
//   /surfaces/<name>/displacement  F64 F × V × 3, m   (positions − rest vertex positions)
//   /frame_views/<f>/...      virtual datasets (HDF5 VDS), frame f of each series above:
//                             displacement, von_mises, J, energy_density,
//                             surfaces/<name>/positions, surfaces/<name>/displacement
// Frame datasets are extendible along their first axis. After each frame the file is flushed
// (H5Fflush) and the XDMF files rewritten atomically (temporary file + rename), so a run killed
// between frames leaves a file and indexes that agree on every frame written.
// A write that fails (a full disk: HDF5 may have written part of its metadata, and the file then
// fails to open with "addr overflow") never leaves results.h5 under its name: the writer closes it
// and renames it to results.h5.partial (removes it when no frame was complete), removes the XDMF
// indexes that name it, and throws an IoError that says so (abandon()).
//
// Surface vertices follow the volume through their embedding: x = X + Σa Na(ξ, η, ζ) ua with the
// trilinear hex8 shape functions Na = (1+ξaξ)(1+ηaη)(1+ζaζ)/8 (physics-notes §1) at the stored
// natural coordinates of the vertex in its element.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/formats/results_format.hpp"
#include "sinew/simulator/engine/backend.hpp"

namespace sinew::simulator {

struct ResultsOptions {
  bool stress = false;          // von Mises stress per element
  bool jacobian = false;        // J per element
  bool energy_density = false;  // strain energy density per element
  bool surfaces = false;        // visual surfaces' vertex positions
  std::string model_file;       // recorded as an attribute
  std::string scene_file;       // recorded as an attribute
};

using formats::kResultsFormatName;  // formats/results_format.hpp
using formats::kResultsFormatVersion;

// Vertex positions of a visual surface for nodal displacements u (N × 3), V × 3, m.
std::vector<double> surface_positions(const formats::Model& model, const formats::Surface& surface,
                                      const std::vector<double>& u);

class ResultsWriter {
 public:
  // Creates (truncates) <directory>/results.h5 and <directory>/results.xdmf. The model must
  // outlive the writer.
  ResultsWriter(const std::string& directory, const formats::Model& model, ResultsOptions options);
  // Reopens the results of an interrupted run to continue after a restart: keeps the frames whose
  // step is ≤ `last_step` and drops the rest. Throws FormatError when the file does not match the
  // model or the options.
  static std::unique_ptr<ResultsWriter> resume(const std::string& directory,
                                               const formats::Model& model, ResultsOptions options,
                                               std::int64_t last_step);
  ~ResultsWriter();
  ResultsWriter(const ResultsWriter&) = delete;
  ResultsWriter& operator=(const ResultsWriter&) = delete;

  // Appends one frame: u is N × 3 (m); `fields` must hold the requested element fields (E each).
  // Flushes the file and rewrites the index.
  void append_frame(double time, std::int64_t step, const std::vector<double>& u,
                    const ElementFields& fields);
  // Closes results.h5 now, so that a failure of its last write (HDF5 writes metadata on close) is
  // an error rather than a damaged file; then no more frames. The destructor closes it otherwise.
  void close();

  std::int64_t frame_count() const { return static_cast<std::int64_t>(times_.size()); }
  const std::vector<double>& times() const { return times_; }
  const std::string& h5_path() const { return h5_path_; }
  const std::string& xdmf_path() const { return xdmf_path_; }
  // The XDMF document (results.xdmf) for the frames written so far.
  std::string xdmf_text() const;
  // Every XDMF document for the frames written so far, (path, text): results.xdmf first (the
  // surfaces' collections, then the volume's), then results_surface_<name>.xdmf per visual
  // surface (its collection alone, for readers that take one collection per file, like meshio).
  std::vector<std::pair<std::string, std::string>> xdmf_documents() const;

 private:
  struct Resume {};
  ResultsWriter(Resume, const std::string& directory, const formats::Model& model,
                ResultsOptions options);
  void create();                         // the new file: mesh, empty series, index
  void truncate_to(std::size_t frames);  // resume: keep `frames` frames, reopen the series
  void write_frame(double time, std::int64_t step, const std::vector<double>& u,
                   const ElementFields& fields);  // append_frame's writes
  void write_index() const;
  // After a failed write (`e`): closes the file, moves results.h5 out of its name, removes the
  // indexes and throws e as an IoError that says where the results went.
  [[noreturn]] void abandon(const Error& e);

  struct Impl;
  std::unique_ptr<Impl> impl_;
  const formats::Model& model_;
  ResultsOptions options_;
  std::string h5_path_, xdmf_path_;
  std::vector<double> times_;
  std::vector<std::size_t> visual_;  // indices of the model's visual surfaces
  bool closed_ = false;              // by close() or abandon(): no more frames
};

}  // namespace sinew::simulator
