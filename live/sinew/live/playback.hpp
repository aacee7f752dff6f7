#pragma once
// Playback of a saved run (sinew-live --play RESULTS.h5; docs/live.md, "Playback and continue"):
// the frames of a results file, read one at a time for scrubbing, and the scene to continue it with.
//
// Continuing from frame k replays the scene from step 0 to the frame's step at full speed and goes
// on live from there. The engines are deterministic (any thread count, any step() call lengths
// give the same bits), so the replayed state is the run's own state at that step, velocities
// included; a results file holds u(n) only, which a restore (the checkpoint path) could not
// continue from exactly. Same backend and precision as the run that wrote the file.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace sinew::live {

class RecordedRun {
 public:
  // Opens a results file (docs/results-format.md). Throws FormatError / IoError.
  explicit RecordedRun(std::string path);
  const std::string& path() const { return path_; }
  std::size_t frame_count() const { return steps_.size(); }
  const std::vector<double>& times() const { return times_; }  // scene time, s
  const std::vector<std::int64_t>& steps() const { return steps_; }
  std::size_t nodes() const { return nodes_; }
  // u of frame k, N × 3, m. Throws FormatError for k out of range or an unreadable frame.
  std::vector<double> displacement(std::size_t k) const;
  // An element field the file stores per frame (docs/results-format.md: "/frames/von_mises", Pa,
  // and "/frames/J", written when the scene's output.fields has `stress` / `J`): its element
  // count (0 when the file has none), and frame k of it (E values). element_field throws
  // FormatError for k out of range, a missing dataset or an unreadable frame.
  std::size_t element_field_width(const std::string& dataset) const;
  std::vector<double> element_field(const std::string& dataset, std::size_t k) const;
  // The scene to continue with: scene.yaml next to the file when there is one (a live recording's
  // reproducing scene), else the file's scene_file attribute (relative paths: to the current
  // folder, as sinew-simulate was given it).
  std::string scene() const;

 private:
  std::string path_, scene_attribute_;
  std::vector<double> times_;
  std::vector<std::int64_t> steps_;
  std::size_t nodes_ = 0;
  // The element fields found at opening: dataset → element count.
  std::vector<std::pair<std::string, std::size_t>> element_fields_;
  // Row k of a frames × width (× 3 when vector) dataset of this file, as double.
  std::vector<double> read_frame(const std::string& dataset, std::size_t k,
                                 std::size_t values) const;
};

}  // namespace sinew::live
