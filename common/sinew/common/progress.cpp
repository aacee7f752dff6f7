#include "sinew/common/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>

#include "sinew/common/log.hpp"

namespace sinew {

namespace {
std::string format_duration(double s) {
  if (!(s >= 0) || s > 1e7) return "--:--";
  const auto total = static_cast<long long>(s + 0.5);
  if (total >= 3600) return fmt::format("{}:{:02}:{:02}", total / 3600, (total / 60) % 60, total % 60);
  return fmt::format("{:02}:{:02}", total / 60, total % 60);
}
}  // namespace

ProgressReporter::ProgressReporter(std::string label, std::int64_t total, ProgressOptions options)
    : label_(std::move(label)), total_(std::max<std::int64_t>(total, 0)), options_(std::move(options)) {
  switch (options_.mode) {
    case ProgressOptions::Mode::bar: bar_ = true; break;
    case ProgressOptions::Mode::plain: bar_ = false; break;
    case ProgressOptions::Mode::automatic: bar_ = isatty(STDERR_FILENO) != 0; break;
  }
  start_ = last_draw_ = Clock::now();
}

ProgressReporter::~ProgressReporter() {
  // A reporter abandoned by an exception must not leave the terminal mid-line.
  if (!finished_ && bar_ && !options_.quiet) std::fputc('\n', stderr);
}

std::string ProgressReporter::format_line(const std::string& label, std::int64_t done,
                                          std::int64_t total, double elapsed_s,
                                          const std::string& unit, const std::string& detail,
                                          int bar_width) {
  const double fraction = total > 0 ? std::clamp(double(done) / double(total), 0.0, 1.0) : 1.0;
  const double rate = elapsed_s > 0 ? double(done) / elapsed_s : 0.0;
  const double eta = rate > 0 ? double(total - done) / rate : -1.0;
  std::string bar;
  if (bar_width > 0) {
    const int filled = static_cast<int>(fraction * bar_width);
    bar.reserve(static_cast<std::size_t>(bar_width) + 3);
    bar.push_back('[');
    bar.append(static_cast<std::size_t>(filled), '#');
    bar.append(static_cast<std::size_t>(bar_width - filled), '.');
    bar.append("] ");
  }
  std::string line = fmt::format("{} {}{:5.1f}% {}/{} | {:.4g} {}/s | elapsed {} | ETA {}", label, bar,
                                 100.0 * fraction, done, total, rate, unit,
                                 format_duration(elapsed_s), format_duration(eta));
  if (!detail.empty()) line += " | " + detail;
  return line;
}

void ProgressReporter::update(std::int64_t done, const std::function<std::string()>& detail) {
  last_done_ = done;
  if (options_.quiet || finished_) return;
  const auto now = Clock::now();
  const double since = std::chrono::duration<double>(now - last_draw_).count();
  const double interval = bar_ ? 0.1 : options_.plain_interval_s;
  if (since < interval) return;
  last_draw_ = now;
  draw(done, detail ? detail() : std::string(), false);
}

void ProgressReporter::finish() {
  if (finished_) return;
  if (!options_.quiet) draw(last_done_ < total_ ? last_done_ : total_, {}, true);
  finished_ = true;
}

void ProgressReporter::draw(std::int64_t done, const std::string& detail, bool final_line) {
  const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
  if (bar_) {
    const std::string line =
        format_line(label_, done, total_, elapsed, options_.unit, detail, 30);
    std::fprintf(stderr, "\r\033[2K%s%s", line.c_str(), final_line ? "\n" : "");
    std::fflush(stderr);
  } else {
    log::info("{}", format_line(label_, done, total_, elapsed, options_.unit, detail, 0));
  }
}

}  // namespace sinew
