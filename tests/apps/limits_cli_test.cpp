// `delta` refuses what it cannot do with one clear line: a size beyond its limit (with the
// memory it would need), an empty or malformed option value; and caps what it can (threads).
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <string_view>

#include "delta/core/memory.h"
#include "delta/core/parallel.h"

#include "apps/cli_run.h"
#include "sanitized.h"

namespace delta::test {
namespace {

/// Whether this machine lacks `bytes`: a test of a refusal runs only where it must be refused
/// (elsewhere the command would really allocate them).
bool beyondThisMachine(double bytes) {
  return bytes > static_cast<double>(memoryLimitBytes());
}

TEST(DeltaCliLimits, BuiltinParametersBeyondTheirLimitsAreRefused) {
  // 2·n + 2 wrapped in uint32 and overflowed the heap.
  expectOneLineError(runDelta("info builtin:cylinder:2147483647"),
                     "mesh 'builtin:cylinder:2147483647': segments 2147483647 is above the "
                     "limit 1073741823; it would need about 206 GB of memory");
  expectOneLineError(runDelta("info builtin:cylinder:99999999999999999999"),
                     "segments 99999999999999999999 is above the limit 1073741823");
  expectOneLineError(runDelta("info builtin:icosphere:9"),
                     "subdivision level 9 is above the limit 8");
  expectOneLineError(runDelta("info builtin:icosphere:-1"), "is not a non-negative integer");
  expectOneLineError(runDelta("info builtin:cylinder:2"), "segments 2 must be at least 3");
  if (beyondThisMachine(103e9))
    expectOneLineError(runDelta("info builtin:cylinder:1073741823"),
                       "segments 1073741823 would need about 103 GB of memory, more than the");
}

TEST(DeltaCliLimits, RunningOutOfMemoryAnywayIsOneLine) {
#if defined(DELTA_TESTS_SANITIZED)
  GTEST_SKIP() << "the sanitizers' shadow memory cannot be mapped under ulimit -v";
#endif
  // Within the estimates, but more than the process may have (here: 500 MB of address space).
  const CliRun run = runDeltaUnder("ulimit -v 500000;", "info builtin:cylinder:10000000");
  expectOneLineError(run, "out of memory: the input or the options ask for more than is free");
  EXPECT_EQ(run.exitCode, 1);
}

TEST(DeltaCliLimits, PointCountsBeyondTheMemoryAreRefused) {
  // Ended in std::bad_alloc.
  if (beyondThisMachine(103e9))
    expectOneLineError(runDelta("distance builtin:box --points builtin:uniform:4294967296"),
                       "points 'builtin:uniform:4294967296': 4294967296 points would need about "
                       "103 GB of memory, more than the");
  expectOneLineError(runDelta("distance builtin:box --points builtin:uniform:4294967297"),
                     "N must be between 1 and 2^32");
}

TEST(DeltaCliLimits, GridsThatCannotFitAreRefusedBeforeTheyAreMade) {
  // Exhausted the memory. Refused from the first levels' counts, in milliseconds.
  if (beyondThisMachine(35e9)) {
    const auto start = std::chrono::steady_clock::now();
    const CliRun run = runDelta("ib builtin:granulate:1 --levels 12");
    expectOneLineError(run, "AdaptiveGrid: levels 12: about ");
    EXPECT_NE(run.err.find("of memory, more than the"), std::string::npos) << run.err;
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
  }
  // More cells in a level than 32-bit indices hold, on any machine.
  expectOneLineError(runDelta("ib builtin:granulate:1 --levels 16"),
                     "a level's 32-bit indices hold");
}

TEST(DeltaCliLimits, AHugeThreadCountIsCapped) {
  // Named for threads, so the ThreadSanitizer build (which has no delta tool) selects it too.
  if (std::string_view(DELTA_CLI).empty()) GTEST_SKIP() << "this build has no delta tool";
  // OMP_NUM_THREADS=100000 segfaulted; --threads has always been checked.
  const CliRun distance =
      runDeltaUnder("OMP_NUM_THREADS=100000",
                    "distance builtin:icosphere:3 --points builtin:uniform:20000 "
                    "--json");
  ASSERT_EQ(distance.exitCode, 0) << distance.err;
  const CliRun ib = runDeltaUnder("OMP_NUM_THREADS=100000", "ib builtin:icosphere:1 --json");
  ASSERT_EQ(ib.exitCode, 0) << ib.err;
  EXPECT_EQ(jsonNumber(ib.out, "threads"), kMaxThreads);
  expectOneLineError(runDelta("--threads 100000 info builtin:box"), "--threads");
  const CliRun most =
      runDelta("--threads " + std::to_string(kMaxThreads) + " ib builtin:box --levels 4 --json");
  ASSERT_EQ(most.exitCode, 0) << most.err;
  EXPECT_EQ(jsonNumber(most.out, "threads"), kMaxThreads);
}

TEST(DeltaCliLimits, EmptyOrMalformedOptionValuesAreErrors) {
  for (const std::string arguments : {
           "contact builtin:box builtin:box --eps ''",
           "contact builtin:box builtin:box --eps=",
           "contact builtin:box builtin:box --rotate-b ''",
           "contact builtin:box builtin:box --translate-b ''",
           "contact builtin:box builtin:box --eps 0.1 --method ''",
           "contact builtin:box builtin:box --eps 0.1 --filter ''",
           "contact builtin:box builtin:box --eps 0.1 --out ''",
           "contact builtin:box builtin:box --eps abc",
           "contact builtin:box builtin:box --eps 0.1,2",
           "contact builtin:box builtin:box --rotate-b 1,0,0,",
           "contact builtin:box builtin:box --translate-b 1,,0",
           "distance builtin:box --points ''",
           "distance builtin:box --points builtin:uniform:10 --eps ''",
           "ib builtin:box --levels ''",
           "ib builtin:box --levels 3.5",
           "ib builtin:box --padding ''",
           "ib builtin:box --exact-band ''",
           "ib builtin:box --steps ''",
           "ib builtin:box --steps 1 --rotate ''",
           "ib builtin:box --steps 1 --translate ''",
           "ib builtin:box --out ''",
           "dem two-particles --steps ''",
           "dem two-particles --restitution ''",
           "dem two-particles --out ''",
           "--threads '' info builtin:box",
           "info ''",
       }) {
    const CliRun run = runDelta(arguments);
    expectOneLineError(run, "");
    EXPECT_LT(run.exitCode, 3) << arguments << ": " << run.err;
  }
  expectOneLineError(runDelta("contact builtin:box builtin:box --eps ''"),
                     "--eps: an empty value is not allowed");
  expectOneLineError(runDelta("contact builtin:box builtin:box --rotate-b ''"),
                     "--rotate-b: an empty value is not allowed");
}

TEST(DeltaCliLimits, IbAndDemStepsShareOneRangeCheck) {
  const std::string range = "must be a whole number from ";
  expectOneLineError(runDelta("ib builtin:box --steps -1"),
                     "--steps '-1' " + range + "0 to 1000000000000");
  expectOneLineError(runDelta("ib builtin:box --steps 1e3"),
                     "--steps '1e3' " + range + "0 to 1000000000000");
  expectOneLineError(runDelta("ib builtin:box --steps 1000000000001"),
                     "--steps '1000000000001' " + range + "0 to 1000000000000");
  expectOneLineError(runDelta("dem two-particles --steps 0"),
                     "--steps '0' " + range + "1 to 1000000000000");
  expectOneLineError(runDelta("dem two-particles --steps -1"),
                     "--steps '-1' " + range + "1 to 1000000000000");
  expectOneLineError(runDelta("dem two-particles --steps 99999999999999999999"),
                     "--steps '99999999999999999999' " + range + "1 to 1000000000000");
  const CliRun ib = runDelta("ib builtin:box --levels 4 --steps 2 --translate 0.01,0,0 --json");
  ASSERT_EQ(ib.exitCode, 0) << ib.err;
  EXPECT_EQ(jsonNumber(ib.out, "steps"), 2);
}

}  // namespace
}  // namespace delta::test
