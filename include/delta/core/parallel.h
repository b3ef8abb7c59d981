#pragma once

#include <cstddef>
#include <span>
#include <vector>

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
int threadCount() noexcept;

namespace detail {

/// Whether the calling thread is inside an OpenMP parallel region (detail::insideOpenMpRegion();
/// OpenMP is linked privately: a program using Δ needs it only for its own regions).
bool insideOpenMpRegion() noexcept;

/// Calls `call(body, chunk)` for every chunk in [0, chunks) on `threads` threads: the caller and
/// threads − 1 workers of Δ's pool. False, having called nothing, when the pool is running
/// another caller's loop (then the caller runs its loop itself). A chunk that throws skips the
/// ones not yet started; the first exception is rethrown here. See parallelFor.
bool runOnPool(std::size_t chunks, int threads, void (*call)(const void* body, std::size_t chunk),
               const void* body);
/// Whether this thread is running a chunk of a parallel loop of Δ's.
bool insideParallelLoop() noexcept;
/// Whether the loops this thread starts run on it alone (a SerialLoops lives on it).
bool serialLoops() noexcept;
/// The calling thread's CPU time in seconds (where the clock is not to be had, its wall time).
double threadCpuSeconds() noexcept;
/// The calling thread's CPU time less the time it spent watching for the pool's loops before it
/// would sleep (parallel.cpp): the time it worked, and the time it would have run had it slept at
/// once.
double threadWorkSeconds() noexcept;
/// While it lives, the parallel loops the constructing thread starts run on that thread alone,
/// chunk by chunk, as on one thread: what a caller does when its loops' threads are held up by
/// other processes (a World stepping on a machine whose cores are all busy). Nests.
///
/// Threading: about the constructing thread only; destroy it there.
class SerialLoops {
 public:
  SerialLoops() noexcept;
  ~SerialLoops();
  SerialLoops(const SerialLoops&) = delete;
  SerialLoops& operator=(const SerialLoops&) = delete;

 private:
  bool enclosing_;
};

/// The parts a parallel loop's chunks filled (one slot a chunk), joined in chunk order: the
/// same list for any number of threads.
template <class T>
std::vector<T> joined(std::span<const std::vector<T>> parts) {
  std::size_t total = 0;
  for (const std::vector<T>& part : parts)
    total += part.size();
  std::vector<T> all;
  all.reserve(total);
  for (const std::vector<T>& part : parts)
    all.insert(all.end(), part.begin(), part.end());
  return all;
}

}  // namespace detail

/// The calling thread's place among the threads of Δ's parallel loops: 0 for a loop's caller
/// (and for any thread that is not one of Δ's workers), 1 … kMaxThreads − 1 for the workers.
///
/// Threading: about the calling thread only.
int loopThreadIndex() noexcept;

/// Calls `body(begin, end)` on disjoint chunks that cover [first, last), on threadCount() threads,
/// each taking another chunk (of `grain` indices) when it is done with one (the caller from the
/// front of the range, the workers from the back); serially on the calling thread when the range
/// holds at most `grain` indices, when the caller is already inside a parallel loop (Δ's, or an
/// OpenMP region: the DEM case, an outer parallel loop over particle pairs, keeps each library call
/// on its own thread), or chunk by chunk on the calling thread when another thread's loop holds the
/// pool. This is the only place Δ runs threads; kernels never spawn any.
///
/// The threads are Δ's own pool (core/parallel.cpp), started on first use and kept: the caller
/// and threadCount() − 1 workers. Waiting is passive where it pays: a worker with nothing to do
/// watches for the next loop for 50 µs (a DEM step's loops follow each other within that), then
/// sleeps in the kernel (C++20 atomic wait), and the caller takes chunks
/// itself until none is left, so no loop waits on a thread the operating system has put aside.
/// (OpenMP's teams spin at every barrier: with another process busy on each core, a DEM step
/// on two threads took longer than on one; see docs/performance.md.) Work never depends on the
/// workers: after a fork, where they are gone, the caller runs every chunk.
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
  if (chunks == 1 || threads == 1 || detail::insideParallelLoop() || detail::serialLoops() ||
      detail::insideOpenMpRegion()) {
    body(first, last);
    return;
  }
  const auto chunk = [&](std::size_t c) {
    const std::size_t begin = first + c * grain;
    body(begin, begin + grain < last ? begin + grain : last);
  };
  using Chunk = decltype(chunk);
  if (!detail::runOnPool(
          chunks, threads, [](const void* f, std::size_t c) { (*static_cast<const Chunk*>(f))(c); },
          &chunk))
    for (std::size_t c = 0; c < chunks; ++c)  // chunk by chunk, as a loop on one thread would
      chunk(c);
}

}  // namespace delta
