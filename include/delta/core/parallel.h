#pragma once

#include <omp.h>

#include <cstddef>
#include <exception>

namespace delta {

/// The most threads a parallel loop of Δ starts, whatever OMP_NUM_THREADS or omp_set_num_threads
/// ask for (the `delta` CLI's --threads accepts 1 to this). Beyond it a loop gains nothing on
/// any machine Δ targets, and a much larger team fails inside the OpenMP runtime (libgomp sets
/// up a team on the calling thread's stack: OMP_NUM_THREADS=100000 overflowed it).
inline constexpr int kMaxThreads = 1024;

/// The threads a parallel loop of Δ uses: omp_get_max_threads() (OMP_NUM_THREADS, or what
/// omp_set_num_threads last set on this thread), capped at kMaxThreads.
///
/// Threading: may be called from any thread.
inline int threadCount() noexcept {
  const int requested = omp_get_max_threads();
  return requested < kMaxThreads ? requested : kMaxThreads;
}

/// Calls `body(begin, end)` on disjoint chunks that cover [first, last), on threadCount() OpenMP
/// threads with dynamic scheduling (chunks of `grain` indices), or serially on the calling thread
/// when the range holds at most `grain` indices or the caller is already inside a parallel region
/// (the DEM case: an outer parallel loop over particle pairs keeps each library call on its own
/// thread). This is the only place Δ uses OpenMP pragmas; kernels never spawn threads.
///
/// Chunks run in any order and on any thread: a body that writes only to slots owned by its
/// chunk gives the same result for every thread count. If a body throws, the remaining chunks are
/// skipped and the first exception is rethrown on the calling thread after the loop.
///
/// Threading: may be called from any number of threads at once; `body` must be safe to call
/// concurrently on disjoint chunks.
template <typename Body>
void parallelFor(std::size_t first, std::size_t last, std::size_t grain, const Body& body) {
  if (last <= first) return;
  if (grain == 0) grain = 1;
  const std::size_t chunks = (last - first + grain - 1) / grain;
  const int threads = threadCount();
  if (chunks == 1 || omp_in_parallel() || threads == 1) {
    body(first, last);
    return;
  }
  std::exception_ptr failure;
  bool failed = false;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
    bool skip;
#pragma omp atomic read
    skip = failed;
    if (skip) continue;
    const std::size_t begin = first + chunk * grain;
    const std::size_t end = begin + grain < last ? begin + grain : last;
    try {
      body(begin, end);
    } catch (...) {
#pragma omp critical(delta_parallel_for_failure)
      if (!failure) failure = std::current_exception();
#pragma omp atomic write
      failed = true;
    }
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace delta
