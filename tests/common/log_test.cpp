// The logger's per-thread context (log::ScopedContext): each thread's messages carry its own name,
// and the previous context comes back when a scope ends.
#include <gtest/gtest.h>

#include <string>
#include <thread>

#include "sinew/common/log.hpp"

namespace sinew {
namespace {

TEST(Log, ScopedContextNamesTheMessagesOfItsThreadOnly) {
  testing::internal::CaptureStderr();
  {
    const log::ScopedContext outer("run_0001");
    log::warn("first");
    std::thread([] { log::warn("from another thread"); }).join();
    {
      const log::ScopedContext inner("run_0002");
      log::warn("second");
    }
    log::warn("third");
  }
  log::warn("fourth");
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("[warning] run_0001: first\n"), std::string::npos) << err;
  EXPECT_NE(err.find("[warning] from another thread\n"), std::string::npos) << err;
  EXPECT_NE(err.find("[warning] run_0002: second\n"), std::string::npos) << err;
  EXPECT_NE(err.find("[warning] run_0001: third\n"), std::string::npos) << err;
  EXPECT_NE(err.find("[warning] fourth\n"), std::string::npos) << err;
}

}  // namespace
}  // namespace sinew
