#include "sinew/common/threads.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <string>

#include <fmt/format.h>

namespace sinew::threads {

namespace {

// Set in the environment of the second start, so that the policy is known to be sinew's choice,
// not the user's.
constexpr const char* kMarker = "SINEW_OMP_WAIT_POLICY_SET";

}  // namespace

void prefer_passive_wait(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;  // the user's, or the second start
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
  ::setenv(kMarker, "1", 1);
  ::execv("/proc/self/exe", argv);
  // Not started again (no /proc, say): go on with OpenMP's own policy, as before.
  ::unsetenv("OMP_WAIT_POLICY");
  ::unsetenv(kMarker);
}

std::string wait_policy_text() {
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  if (policy == nullptr) return "OpenMP's default wait";
  std::string p = policy;
  std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return std::tolower(c); });
  return std::getenv(kMarker) != nullptr ? p + " wait" : p + " wait (OMP_WAIT_POLICY)";
}

std::string explain(int threads, bool from_command_line) {
  const char* count = std::getenv("OMP_NUM_THREADS");
  const std::string why = from_command_line ? "--threads"
                          : count != nullptr && *count != '\0'
                              ? fmt::format("OMP_NUM_THREADS={}", count)
                              : "OpenMP's default: every core";
  return fmt::format("threads: {} ({}; {})", threads, why, wait_policy_text());
}

}  // namespace sinew::threads
