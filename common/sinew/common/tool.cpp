#include "sinew/common/tool.hpp"

#include <exception>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"

namespace sinew::tool {

void report_error(const std::string& tool, const std::string& message) {
  log::error("{}: {}", tool, message);
  // The process is about to exit: make sure the message is out even if stderr is redirected.
  log::logger().flush();
}

int run(const std::string& tool, ExitCodes codes, const std::function<int()>& body) {
  // A tool ended by a signal removes the files it was writing (atomic_file.hpp).
  remove_temporaries_on_signal();
  // One catch per exit status; the message is the same form for all of them.
  try {
    return body();
  } catch (const ConfigError& e) {
    report_error(tool, std::string("error: ") + e.what());
    return codes.config;
  } catch (const InstabilityError& e) {
    report_error(tool, std::string("error: ") + e.what());
    return codes.instability;
  } catch (const std::exception& e) {
    report_error(tool, std::string("error: ") + e.what());
    return kExitError;
  }
}

int run(const std::string& tool, const std::function<int()>& body) {
  return run(tool, ExitCodes{}, body);
}

}  // namespace sinew::tool
