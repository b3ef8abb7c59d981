#include "delta/core/memory.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <string>

#include "delta/core/error.h"

namespace delta {
namespace {

TEST(Memory, TheLimitIsAtMostThePhysicalMemory) {
  const double physical =
      static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
  EXPECT_GT(memoryLimitBytes(), std::size_t{1} << 26);
  EXPECT_LE(static_cast<double>(memoryLimitBytes()), physical);
}

TEST(Memory, BytesReadAsAPersonWritesThem) {
  EXPECT_EQ(describeBytes(812), "812 bytes");
  EXPECT_EQ(describeBytes(1.5e6), "1.5 MB");
  EXPECT_EQ(describeBytes(88.4e9), "88.4 GB");
  EXPECT_EQ(describeBytes(2.06e11), "206 GB");
  EXPECT_EQ(describeBytes(5.86e14), "586 TB");
  EXPECT_EQ(describeBytes(INFINITY), "an unbounded amount");
}

TEST(Memory, RequireMemoryRefusesWhatCannotFitAndSaysWhy) {
  EXPECT_NO_THROW(requireMemory(1e6, "a small request"));
  const double beyond = 2.0 * static_cast<double>(memoryLimitBytes());
  try {
    requireMemory(beyond, "a grid of 12 levels");
    ADD_FAILURE() << "no delta::Error";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("a grid of 12 levels would need about " + describeBytes(beyond), 0), 0u)
        << message;
    EXPECT_NE(
        message.find(describeBytes(static_cast<double>(memoryLimitBytes())) + " memory limit"),
        std::string::npos)
        << message;
  }
  EXPECT_THROW(requireMemory(NAN, "a count that overflowed"), Error);
  EXPECT_THROW(requireMemory(INFINITY, "a count that overflowed"), Error);
}

}  // namespace
}  // namespace delta
