#pragma once
// Progress reporting for long loops (voxelizer stages, simulation steps).
//
// On a terminal (stderr is a TTY) it draws one live bar with the rate and the ETA, redrawn at most
// ten times a second. Otherwise it writes a plain line through the logger every `plain_interval`
// seconds (default 10 s) so logs of CI and batch jobs stay readable. Silent when quiet. The caller
// reports absolute progress; the reporter never blocks the loop for more than a clock read.
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace sinew {

struct ProgressOptions {
  bool quiet = false;
  // Force the mode; by default it follows isatty(stderr).
  enum class Mode { automatic, bar, plain } mode = Mode::automatic;
  double plain_interval_s = 10.0;
  // Unit shown in the rate, e.g. "steps" -> "1234 steps/s".
  std::string unit = "items";
};

class ProgressReporter {
 public:
  using Clock = std::chrono::steady_clock;

  ProgressReporter(std::string label, std::int64_t total, ProgressOptions options = {});
  ~ProgressReporter();
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;

  // Report that `done` of `total` items are complete. `detail` is shown after the bar (e.g.
  // "t = 0.120 s"); it is only evaluated when a line is actually drawn.
  void update(std::int64_t done, const std::function<std::string()>& detail = {});
  // Draw the final state once and end the line.
  void finish();

  // The text of one line for the given state, without terminal control codes (exposed for tests).
  static std::string format_line(const std::string& label, std::int64_t done, std::int64_t total,
                                 double elapsed_s, const std::string& unit,
                                 const std::string& detail, int bar_width);

  bool uses_bar() const { return bar_; }

 private:
  void draw(std::int64_t done, const std::string& detail, bool final_line);

  std::string label_;
  std::int64_t total_;
  ProgressOptions options_;
  bool bar_ = false;
  bool finished_ = false;
  std::int64_t last_done_ = 0;
  Clock::time_point start_, last_draw_;
};

}  // namespace sinew
