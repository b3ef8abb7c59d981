#include "delta/core/parallel.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

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
      owner[i] = omp_get_thread_num();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  EXPECT_NE(std::count(owner.begin(), owner.end(), 0), 64) << "everything ran on thread 0";
}

TEST(ParallelFor, CapsTheThreadsAskedFor) {
  // OMP_NUM_THREADS=100000 asked libgomp for a team it set up on the caller's stack: a segfault.
  const int before = omp_get_max_threads();
  omp_set_num_threads(100000);
  EXPECT_EQ(threadCount(), kMaxThreads);
  std::atomic<int> largestTeam{0};
  std::vector<int> hits(4096, 0);
  parallelFor(0, hits.size(), 1, [&](std::size_t begin, std::size_t end) {
    int team = largestTeam.load();
    while (team < omp_get_num_threads() &&
           !largestTeam.compare_exchange_weak(team, omp_get_num_threads())) {
    }
    for (std::size_t i = begin; i < end; ++i)
      ++hits[i];
  });
  omp_set_num_threads(before);
  EXPECT_LE(largestTeam.load(), kMaxThreads);
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

}  // namespace
}  // namespace delta
