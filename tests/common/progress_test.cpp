// The progress reporter: the line format and the plain (non-terminal) mode.
#include "sinew/common/progress.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

#include <sstream>

#include "sinew/common/log.hpp"

namespace {

TEST(Progress, FormatLineWithBar) {
  const std::string line =
      sinew::ProgressReporter::format_line("steps", 50, 200, 10.0, "steps", "t = 0.1 s", 10);
  // 25 % done, 5 steps/s, 150 left -> 30 s ETA.
  EXPECT_EQ(line,
            "steps [##........]  25.0% 50/200 | 5 steps/s | elapsed 00:10 | ETA 00:30 | t = 0.1 s");
}

TEST(Progress, FormatLineWithoutBarAndLongDurations) {
  const std::string line =
      sinew::ProgressReporter::format_line("voxelize", 1, 4, 3600.0, "slices", "", 0);
  EXPECT_EQ(line, "voxelize  25.0% 1/4 | 0.0002778 slices/s | elapsed 1:00:00 | ETA 3:00:00");
}

TEST(Progress, FormatLineBeforeAnyProgress) {
  const std::string line = sinew::ProgressReporter::format_line("x", 0, 10, 0.0, "items", "", 4);
  EXPECT_EQ(line, "x [....]   0.0% 0/10 | 0 items/s | elapsed 00:00 | ETA --:--");
}

// Captures the logger's output while alive.
class LogCapture {
 public:
  LogCapture() : sink_(std::make_shared<spdlog::sinks::ostream_sink_st>(out_)) {
    sink_->set_pattern("%v");
    sinew::log::logger().sinks().push_back(sink_);
  }
  ~LogCapture() {
    auto& sinks = sinew::log::logger().sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), sink_), sinks.end());
  }
  std::string text() const { return out_.str(); }

 private:
  std::ostringstream out_;
  std::shared_ptr<spdlog::sinks::ostream_sink_st> sink_;
};

TEST(Progress, PlainModeWritesLinesThroughTheLogger) {
  LogCapture capture;
  sinew::ProgressOptions options;
  options.mode = sinew::ProgressOptions::Mode::plain;
  options.plain_interval_s = 0.0;  // every update draws
  options.unit = "steps";
  sinew::ProgressReporter progress("simulate", 100, options);
  EXPECT_FALSE(progress.uses_bar());
  progress.update(40, [] { return std::string("t = 0.4 s"); });
  progress.finish();
  const std::string text = capture.text();
  EXPECT_NE(text.find("simulate  40.0% 40/100"), std::string::npos) << text;
  EXPECT_NE(text.find("| t = 0.4 s"), std::string::npos) << text;
  EXPECT_NE(text.find("40/100"), std::string::npos) << text;
  EXPECT_EQ(text.find('['), std::string::npos) << "plain lines carry no bar: " << text;
  EXPECT_EQ(text.find('\r'), std::string::npos) << text;
}

TEST(Progress, PlainModeRespectsTheInterval) {
  LogCapture capture;
  sinew::ProgressOptions options;
  options.mode = sinew::ProgressOptions::Mode::plain;
  options.plain_interval_s = 3600.0;
  sinew::ProgressReporter progress("slow", 10, options);
  for (int i = 1; i <= 10; ++i) progress.update(i);
  EXPECT_EQ(capture.text(), "") << "no line before the interval has passed";
  progress.finish();
  EXPECT_NE(capture.text().find("slow 100.0% 10/10"), std::string::npos) << capture.text();
}

TEST(Progress, QuietPrintsNothing) {
  LogCapture capture;
  sinew::ProgressOptions options;
  options.mode = sinew::ProgressOptions::Mode::plain;
  options.plain_interval_s = 0.0;
  options.quiet = true;
  sinew::ProgressReporter progress("quiet", 10, options);
  progress.update(5);
  progress.finish();
  EXPECT_EQ(capture.text(), "");
}

}  // namespace
