#pragma once
// The one way the command-line tools end: run a tool's body, turn an escaping exception into one
// message through the logger (log.hpp, stderr) and a documented exit status. Every tool's main()
// is `return sinew::tool::run("sinew-x", [&] { ...; return sinew::tool::kExitOk; });`.
#include <functional>
#include <string>

namespace sinew::tool {

// Exit statuses of the sinew tools.
inline constexpr int kExitOk = 0;
inline constexpr int kExitError = 1;          // a failure: bad input, unreadable file, ...
inline constexpr int kExitUsage = 2;          // a bad command line (CLI11), or a ConfigError where
                                              // ExitCodes::config says so
inline constexpr int kExitUnstable = 3;       // sinew-simulate: the simulation became unstable
inline constexpr int kExitInterrupted = 130;  // stopped by SIGINT/SIGTERM (128 + SIGINT)

// Which typed errors get their own exit status (default: all kExitError).
struct ExitCodes {
  int config = kExitError;       // sinew::ConfigError
  int instability = kExitError;  // sinew::InstabilityError
};

// Logs "<tool>: <message>" at error level (shown unless the level is "off").
void report_error(const std::string& tool, const std::string& message);

// Runs body() and returns its exit status. First installs remove_temporaries_on_signal()
// (atomic_file.hpp): SIGINT, SIGTERM or SIGHUP removes the temporaries of the files being written
// and ends the process by that signal, unless the tool installs handlers of its own. An exception escaping it is reported once with
// report_error() as "error: <what>" (a sinew::Error, whose message names file, field and problem,
// or any other std::exception) and gives codes.config for ConfigError, codes.instability for
// InstabilityError, else kExitError.
int run(const std::string& tool, ExitCodes codes, const std::function<int()>& body);
// The same with the default ExitCodes.
int run(const std::string& tool, const std::function<int()>& body);

}  // namespace sinew::tool
