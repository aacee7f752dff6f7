#pragma once
// The one logger. Library code reports through these functions and never prints directly; the
// tools decide the level (--quiet, --verbose) and where it goes (stderr).
#include <spdlog/spdlog.h>

#include <string>
#include <utility>

namespace sinew::log {

enum class Level { debug, info, warn, error, off };

// Puts "<name>: " before every message the calling thread logs while it lives (sinew-sweep names
// the run each thread runs: "[warning] run_0003: hourglass energy is ..."). Restores the previous
// context when it ends.
class ScopedContext {
 public:
  explicit ScopedContext(const std::string& name);
  ~ScopedContext();
  ScopedContext(const ScopedContext&) = delete;
  ScopedContext& operator=(const ScopedContext&) = delete;

 private:
  std::string previous_;
};

// The process-wide logger ("sinew"), created on first use, writing to stderr.
spdlog::logger& logger();
void set_level(Level level);
Level level();
// Parses "debug", "info", "warn", "error", "off"; throws ConfigError otherwise.
Level parse_level(const std::string& name);

template <typename... Args>
void debug(spdlog::format_string_t<Args...> fmt, Args&&... args) {
  logger().debug(fmt, std::forward<Args>(args)...);
}
template <typename... Args>
void info(spdlog::format_string_t<Args...> fmt, Args&&... args) {
  logger().info(fmt, std::forward<Args>(args)...);
}
template <typename... Args>
void warn(spdlog::format_string_t<Args...> fmt, Args&&... args) {
  logger().warn(fmt, std::forward<Args>(args)...);
}
template <typename... Args>
void error(spdlog::format_string_t<Args...> fmt, Args&&... args) {
  logger().error(fmt, std::forward<Args>(args)...);
}

}  // namespace sinew::log
