#include "delta/core/parallel.h"

#include <gtest/gtest.h>
#include <omp.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

// ThreadSanitizer: GCC says so with __SANITIZE_THREAD__, clang with __has_feature.
#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define DELTA_TEST_TSAN 1
#endif
#endif
#ifndef DELTA_TEST_TSAN
#define DELTA_TEST_TSAN 0
#endif

namespace delta {
namespace {

std::vector<int> coverage(std::size_t first, std::size_t last, std::size_t grain) {
  std::vector<int> hits(last + 1, 0);
  parallelFor(first, last, grain, [&](std::size_t begin, std::size_t end) {
    EXPECT_LT(begin, end);
    EXPECT_LE(end - begin, grain == 0 ? 1 : grain);
    for (std::size_t i = begin; i < end; ++i)
      ++hits[i];  // disjoint chunks: no race
  });
  return hits;
}

TEST(ParallelFor, CoversTheRangeExactlyOnce) {
  for (std::size_t grain : {1, 3, 64, 1000}) {
    const std::vector<int> hits = coverage(5, 777, grain);
    for (std::size_t i = 0; i < hits.size(); ++i)
      EXPECT_EQ(hits[i], i >= 5 && i < 777 ? 1 : 0);
  }
  EXPECT_EQ(coverage(4, 4, 8), std::vector<int>(5, 0));
}

TEST(ParallelFor, UsesSeveralThreadsWhenAllowed) {
  if (omp_get_num_procs() < 2) GTEST_SKIP() << "one processor";
  omp_set_num_threads(2);
  std::vector<int> owner(64, -1);
  parallelFor(0, owner.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      owner[i] = loopThreadIndex();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  EXPECT_NE(std::count(owner.begin(), owner.end(), 0), 64) << "everything ran on thread 0";
}

// Where the same loop ran on two threads (as above), under SerialLoops every chunk runs on the
// calling thread, nested scopes included, and the pool is back when the outermost one ends.
TEST(ParallelFor, SerialLoopsRunOnTheCallingThreadAlone) {
  if (omp_get_num_procs() < 2) GTEST_SKIP() << "one processor";
  omp_set_num_threads(2);
  const auto owners = [] {
    std::vector<int> owner(64, -1);
    parallelFor(0, owner.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        owner[i] = loopThreadIndex();
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      }
    });
    return static_cast<std::size_t>(std::count(owner.begin(), owner.end(), 0));
  };
  {
    const detail::SerialLoops alone;
    EXPECT_TRUE(detail::serialLoops());
    {
      const detail::SerialLoops nested;
      EXPECT_EQ(owners(), 64u);
    }
    EXPECT_TRUE(detail::serialLoops());
    EXPECT_EQ(owners(), 64u);
  }
  EXPECT_FALSE(detail::serialLoops());
  EXPECT_NE(owners(), 64u) << "everything ran on thread 0 after the scope";
}

TEST(ParallelFor, ThreadCpuTimeCountsWorkNotSleep) {
  const double start = detail::threadCpuSeconds();
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  const double slept = detail::threadCpuSeconds() - start;
  EXPECT_LT(slept, 0.01);
  // Busy until 20 ms of CPU time: reached (within 5 s, however busy the machine) only if the
  // clock counts the work.
  volatile double sink = 0.0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (detail::threadCpuSeconds() - start - slept < 0.02 &&
         std::chrono::steady_clock::now() < deadline)
    sink = sink + 1.0;
  EXPECT_GE(detail::threadCpuSeconds() - start - slept, 0.02);
}

// The pool's threads watch for a while before they sleep (parallel.cpp), and a World judges the
// load on its cores by the CPU time its thread worked: a caller waiting for a worker's chunk did
// not work, whether it slept or watched. (Counted as work, the watching made a caller waiting 60 µs
// look busy for most of it.)
TEST(ParallelFor, WaitingForAWorkerIsNotCountedAsWork) {
  if (threadCount() < 2) GTEST_SKIP() << "one thread";
  using Clock = std::chrono::steady_clock;
  const auto busy = [](std::chrono::microseconds time) {
    for (const auto until = Clock::now() + time; Clock::now() < until;) {
    }
  };
  // Over the loops in which a worker took one chunk: from the end of the caller's chunk (which
  // waits for the worker to start the other) to the end of the loop.
  double waited = 0.0, worked = 0.0;
  for (int loop = 0; loop < 2000 && waited < 0.02; ++loop) {
    std::atomic<bool> workerStarted{false};
    bool split = false;
    Clock::time_point callerDone;
    double workAtCallerDone = 0.0;
    parallelFor(0, 2, 1, [&](std::size_t, std::size_t) {
      if (loopThreadIndex() != 0) {
        workerStarted = true;
        busy(std::chrono::microseconds(60));
        return;
      }
      if (split) return;  // the caller took both chunks
      for (const auto until = Clock::now() + std::chrono::milliseconds(1);
           !workerStarted && Clock::now() < until;) {
      }
      split = workerStarted;
      callerDone = Clock::now();
      workAtCallerDone = detail::threadWorkSeconds();
    });
    if (!split) continue;
    waited += std::chrono::duration<double>(Clock::now() - callerDone).count();
    worked += detail::threadWorkSeconds() - workAtCallerDone;
  }
  ASSERT_GT(waited, 0.0) << "no worker took a chunk";
  EXPECT_LT(worked, 0.3 * waited);
}

TEST(ParallelFor, CapsTheThreadsAskedFor) {
  // OMP_NUM_THREADS=100000 asked libgomp for a team it set up on the caller's stack: a segfault.
  const int before = omp_get_max_threads();
  omp_set_num_threads(100000);
  EXPECT_EQ(threadCount(), kMaxThreads);
  std::atomic<int> largestIndex{0};
  std::vector<int> hits(4096, 0);
  parallelFor(0, hits.size(), 1, [&](std::size_t begin, std::size_t end) {
    int largest = largestIndex.load();
    while (largest < loopThreadIndex() &&
           !largestIndex.compare_exchange_weak(largest, loopThreadIndex())) {
    }
    for (std::size_t i = begin; i < end; ++i)
      ++hits[i];
  });
  omp_set_num_threads(before);
  EXPECT_LT(largestIndex.load(), kMaxThreads);
  EXPECT_EQ(std::count(hits.begin(), hits.end(), 1), 4096);
  EXPECT_EQ(threadCount(), std::min(before, kMaxThreads));
}

TEST(ParallelFor, RethrowsTheFirstException) {
  std::atomic<int> calls = 0;
  EXPECT_THROW(parallelFor(0, 1000, 10,
                           [&](std::size_t begin, std::size_t) {
                             ++calls;
                             if (begin == 500) throw std::runtime_error("chunk 50");
                           }),
               std::runtime_error);
  EXPECT_GE(calls.load(), 1);
}

TEST(ParallelFor, RunsSeriallyInsideAnOuterParallelRegion) {
  int inner = 0;
#pragma omp parallel num_threads(2)
  {
#pragma omp single
    parallelFor(0, 100, 1, [&](std::size_t begin, std::size_t end) {
      inner += static_cast<int>(end - begin);  // serial: no race
    });
  }
  EXPECT_EQ(inner, 100);
}

TEST(ParallelFor, RunsSeriallyInsideItsOwnChunks) {
  omp_set_num_threads(2);
  std::atomic<int> nestedElsewhere{0};
  std::vector<int> hits(64 * 64, 0);
  parallelFor(0, 64, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const int thread = loopThreadIndex();
      parallelFor(0, 64, 1, [&](std::size_t innerBegin, std::size_t innerEnd) {
        if (loopThreadIndex() != thread) ++nestedElsewhere;
        for (std::size_t j = innerBegin; j < innerEnd; ++j)
          ++hits[i * 64 + j];  // this chunk's row: no race
      });
    }
  });
  EXPECT_EQ(nestedElsewhere.load(), 0) << "an inner loop left its chunk's thread";
  EXPECT_EQ(std::count(hits.begin(), hits.end(), 1), 64 * 64);
}

TEST(ParallelFor, LoopsAfterLoopsOnChangingThreadCounts) {
  // The hand-over from one loop to the next (workers asleep, late, or joining a later loop) under
  // many short loops: every index once, every time (ThreadSanitizer checks the hand-over).
  const int before = omp_get_max_threads();
  for (int loop = 0; loop < 2000; ++loop) {
    omp_set_num_threads(2 + loop % 3);
    const std::size_t count = 1 + static_cast<std::size_t>(loop % 97);
    std::vector<int> hits(count, 0);
    parallelFor(0, count, 1 + static_cast<std::size_t>(loop % 5),
                [&](std::size_t begin, std::size_t end) {
                  for (std::size_t i = begin; i < end; ++i)
                    ++hits[i];
                });
    ASSERT_EQ(std::count(hits.begin(), hits.end(), 1), static_cast<long>(count)) << "loop " << loop;
  }
  omp_set_num_threads(before);
}

TEST(ParallelFor, FinishesInAForkedChildWhereTheWorkersAreGone) {
#if defined(__SANITIZE_THREAD__) || DELTA_TEST_TSAN
  GTEST_SKIP() << "ThreadSanitizer does not follow a multithreaded fork";
#else
  omp_set_num_threads(2);
  std::vector<int> warm(64, 0);  // the pool has its worker
  parallelFor(0, warm.size(), 1, [&](std::size_t begin, std::size_t) { warm[begin] = 1; });
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    alarm(20);  // a hang fails the test instead of holding it up
    std::vector<int> hits(1000, 0);
    parallelFor(0, hits.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        ++hits[i];
    });
    _exit(std::count(hits.begin(), hits.end(), 1) == 1000 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
#endif
}

TEST(ParallelFor, ManyThreadsCallItAtOnce) {
  std::vector<std::thread> callers;
  std::vector<long> sums(4, 0);
  for (std::size_t t = 0; t < sums.size(); ++t)
    callers.emplace_back([&, t] {
      std::vector<long> values(10000, 0);
      parallelFor(0, values.size(), 100, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
          values[i] = static_cast<long>(i);
      });
      sums[t] = std::accumulate(values.begin(), values.end(), 0L);
    });
  for (std::thread& caller : callers)
    caller.join();
  for (long sum : sums)
    EXPECT_EQ(sum, 10000L * 9999 / 2);
}

TEST(ParallelFor, OnTwoThreadsEachKeepsToItsEndOfTheRange) {
  // The caller takes chunks from the front and the worker from the back, so that loop after loop
  // each thread touches the same half of the data: whoever ran which, the caller's chunks are a
  // prefix of the range and the worker's the rest.
  const int before = omp_get_max_threads();
  omp_set_num_threads(2);
  constexpr std::size_t kChunks = 64;
  std::size_t bothTook = 0;
  for (int loop = 0; loop < 20; ++loop) {
    std::vector<int> ranBy(kChunks, -1);
    parallelFor(0, kChunks, 1, [&](std::size_t begin, std::size_t end) {
      std::this_thread::sleep_for(std::chrono::microseconds(50));  // long enough to share
      for (std::size_t c = begin; c < end; ++c)
        ranBy[c] = loopThreadIndex();
    });
    const auto firstOfWorker =
        std::find_if(ranBy.begin(), ranBy.end(), [](int thread) { return thread != 0; });
    EXPECT_TRUE(std::all_of(firstOfWorker, ranBy.end(), [](int thread) { return thread == 1; }))
        << "loop " << loop;
    bothTook += firstOfWorker != ranBy.begin() && firstOfWorker != ranBy.end();
  }
  EXPECT_GT(bothTook, 0u);  // the worker took its part in some loop
  omp_set_num_threads(before);
}

}  // namespace
}  // namespace delta
