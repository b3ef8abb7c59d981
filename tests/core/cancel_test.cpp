#include "delta/core/cancel.h"

#include <gtest/gtest.h>
#include <omp.h>
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "delta/mesh/primitives.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

namespace delta {
namespace {

TEST(CancelScope, PollsOnlyInsideAScopeAndNests) {
  pollCancellation();  // no scope: nothing to call
  EXPECT_FALSE(cancellable());
  int outerCalls = 0;
  {
    const CancelScope outer([&] { return ++outerCalls >= 2; });
    EXPECT_TRUE(cancellable());
    pollCancellation();
    EXPECT_THROW(pollCancellation(), Cancelled);
    {
      const CancelScope uninterruptible({});
      EXPECT_FALSE(cancellable());
      pollCancellation();  // the empty scope hides the outer one
    }
    EXPECT_TRUE(cancellable());
    EXPECT_THROW(pollCancellation(), Cancelled);
  }
  EXPECT_EQ(outerCalls, 3);
  EXPECT_FALSE(cancellable());
  // Another thread is not in this thread's scope.
  const CancelScope scope([] { return true; });
  bool otherThreadCancellable = true;
  std::thread([&] { otherThreadCancellable = cancellable(); }).join();
  EXPECT_FALSE(otherThreadCancellable);
}

TEST(CancelScope, NeverPollsInsideAParallelRegion) {
  std::atomic<int> calls = 0;
  const CancelScope scope([&] { return ++calls > 0; });
  std::atomic<int> cancellableInside = 0;
#pragma omp parallel num_threads(2)
  {
    cancellableInside += cancellable();
    pollCancellation();  // a worker or the region's own thread: nothing happens
  }
  EXPECT_EQ(cancellableInside, 0);
  EXPECT_EQ(calls, 0);
}

/// A chunk of work that takes about `microseconds`, so that every thread gets chunks.
void spin(int microseconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::microseconds(microseconds);
  while (std::chrono::steady_clock::now() < end) {
  }
}

TEST(CancelScope, OnOneThreadPollsBeforeEveryChunkAndStopsAtOnce) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::size_t count = 10 * 256 + 17;
  std::vector<int> visits(count, 0);
  std::size_t polls = 0;
  {
    const CancelScope scope([&] {
      ++polls;
      return false;
    });
    cancellableParallelFor(0, count, 256, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        ++visits[i];
    });
  }
  EXPECT_EQ(polls, 11u);
  for (std::size_t i = 0; i < count; ++i)
    ASSERT_EQ(visits[i], 1) << i;
  std::vector<int> stopped(count, 0);
  std::size_t calls = 0;
  {
    const CancelScope scope([&] { return ++calls == 3; });
    EXPECT_THROW(cancellableParallelFor(0, count, 256,
                                        [&](std::size_t begin, std::size_t end) {
                                          for (std::size_t i = begin; i < end; ++i)
                                            ++stopped[i];
                                        }),
                 Cancelled);
  }
  omp_set_num_threads(threads);
  std::size_t done = 0;
  for (int visit : stopped)
    done += visit;
  EXPECT_EQ(done, 2u * 256u);  // two chunks, then the stop
}

TEST(CancelScope, InParallelOnlyTheCallingThreadPollsAndAStopEndsTheLoopEarly) {
  const std::size_t count = 400 * 16;
  std::vector<int> visits(count, 0);
  std::atomic<std::size_t> polls = 0;
  const pthread_t owner = pthread_self();
  std::atomic<bool> wrongThread = false;
  {
    const CancelScope scope([&] {
      wrongThread = wrongThread || !pthread_equal(pthread_self(), owner);
      ++polls;
      return false;
    });
    cancellableParallelFor(0, count, 16, [&](std::size_t begin, std::size_t end) {
      spin(50);
      for (std::size_t i = begin; i < end; ++i)
        ++visits[i];
    });
  }
  EXPECT_GE(polls, 1u);    // the calling thread took chunks
  EXPECT_LE(polls, 400u);  // and polled once before each
  EXPECT_FALSE(wrongThread);
  for (std::size_t i = 0; i < count; ++i)
    ASSERT_EQ(visits[i], 1) << i;
  std::vector<int> stopped(count, 0);
  std::size_t calls = 0;
  const CancelScope scope([&] { return ++calls == 3; });
  EXPECT_THROW(cancellableParallelFor(0, count, 16,
                                      [&](std::size_t begin, std::size_t end) {
                                        spin(50);
                                        for (std::size_t i = begin; i < end; ++i)
                                          ++stopped[i];
                                      }),
               Cancelled);
  std::size_t done = 0;
  for (int visit : stopped) {
    ASSERT_LE(visit, 1);
    done += visit;
  }
  EXPECT_LT(done, count);
}

TEST(CancelScope, PointQueriesStopEarlyAndAnswerTheSameWhenNotStopped) {
  const QueryMesh sphere(primitives::icosphere(3));
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
  std::vector<Vec3> points(50000);
  for (Vec3& p : points)
    p = {coordinate(random), coordinate(random), coordinate(random)};
  const contactdetection::PointQuery query{.signedDistance = true};
  const auto reference = contactdetection::distances(sphere, points, query);
  std::size_t polls = 0;
  {
    const CancelScope scope([&] {
      ++polls;
      return false;
    });
    const auto polled = contactdetection::distances(sphere, points, query);
    ASSERT_EQ(polled.size(), reference.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      ASSERT_EQ(polled[i].distance, reference[i].distance) << i;
      ASSERT_EQ(polled[i].triangle, reference[i].triangle) << i;
      ASSERT_EQ(polled[i].inside, reference[i].inside) << i;
    }
  }
  EXPECT_GE(polls, 2u);
  const CancelScope scope([] { return true; });
  EXPECT_THROW(contactdetection::distances(sphere, points, query), Cancelled);
}

}  // namespace
}  // namespace delta
