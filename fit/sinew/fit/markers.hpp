#pragma once
// Marker trajectories (docs/fit.md, "The marker file"): a CSV of named points over time in the
// model's coordinates, read and checked before anything is simulated.
//
//   # comments and blank lines are skipped
//   time,brow_centre_left.x,brow_centre_left.y,brow_centre_left.z,chin.x,chin.y,chin.z
//   0,25.624,31.777,87.566,0,-101.442,66.285
//   0.005,25.63,31.9,87.57,,,                 <- chin not seen in this frame
//
// time in s of scene time, ≥ 0 and strictly increasing; positions in the base scene's length unit
// (`units:`, m by default) unless the caller says otherwise. A marker is three columns NAME.x,
// NAME.y, NAME.z; a frame may leave all three empty (the marker was not seen), never one or two.
// Every error is a FormatError naming the file, the line and the value, e.g.
//   "markers.csv: line 7, column 'chin.y': not a finite number: 'nan'".
#include <array>
#include <string>
#include <vector>

namespace sinew::fit {

struct Markers {
  std::string file;                // as given, for messages
  std::vector<std::string> names;  // M, in column order
  int header_line = 0;             // the header's line (1-based)
  std::vector<double> times;       // F, s, strictly increasing
  std::vector<int> lines;          // F, the file line of each frame (1-based), for messages
  // F × M positions (in the unit they were written in); seen[f][m] false where the marker was
  // not seen in frame f (position then 0).
  std::vector<std::vector<std::array<double, 3>>> positions;
  std::vector<std::vector<bool>> seen;

  std::size_t frame_count() const { return times.size(); }
  std::size_t marker_count() const { return names.size(); }
  // The number of (frame, marker) pairs seen.
  std::size_t seen_count() const;
};

// Reads a marker CSV. Throws IoError (cannot be read) or FormatError (file, line, problem).
Markers read_markers(const std::string& path);
// The same from text; `file` names it in messages.
Markers parse_markers(const std::string& text, const std::string& file);

// Writes markers as CSV text in the same format (17 significant digits; an unseen marker as
// three empty cells).
std::string markers_csv(const Markers& markers);

}  // namespace sinew::fit
