#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <stdexcept>
#include <utility>

#include "delta/core/parallel.h"

namespace delta {

/// Thrown by pollCancellation() when the calling thread's CancelScope asks the computation to
/// stop. Not a delta::Error: nothing was wrong with the input. What the stopped call was making
/// is discarded (a grid under construction) or left as its documentation says (an output span
/// may hold some answers).
///
/// Threading: an immutable value; safe to share.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("cancelled") {}
};

namespace detail {
/// The poll of the innermost CancelScope of this thread; null outside every scope.
inline thread_local const std::function<bool()>* currentCancelPoll = nullptr;
}  // namespace detail

/// Makes the long computations that the constructing thread runs during the scope's lifetime
/// stoppable. Point queries (contactdetection::distances: before each chunk of a few hundred
/// points the calling thread searches) and grid builds (ib::AdaptiveGrid: between batches of
/// cells, and in their queries) call `requested` often, so keep it cheap (read an atomic flag,
/// or look at a clock first). When it returns true, the computation throws Cancelled; it may
/// instead throw an exception of its own, which propagates unchanged (the Python module raises
/// KeyboardInterrupt this way).
///
/// `requested` runs on the thread that made the scope only, never on an OpenMP worker (it may
/// run inside the computation's parallel region, as the region's own thread, while the workers
/// go on with their chunks). Other computations (DEM steps, mesh–mesh contacts) do not poll, and
/// neither does a query called inside an enclosing parallel region. An empty `requested` makes
/// what runs in the scope uninterruptible (a scope nested in a cancellable one, around work that
/// must not stop half-way).
///
/// Scopes nest; each restores the enclosing one when it ends. Without a scope nothing polls (the
/// same code and speed as before).
///
/// Threading: a scope belongs to the thread that made it; other threads are not affected.
class CancelScope {
 public:
  explicit CancelScope(std::function<bool()> requested)
      : requested_(std::move(requested)), enclosing_(detail::currentCancelPoll) {
    detail::currentCancelPoll = &requested_;
  }
  ~CancelScope() { detail::currentCancelPoll = enclosing_; }
  CancelScope(const CancelScope&) = delete;
  CancelScope& operator=(const CancelScope&) = delete;

 private:
  std::function<bool()> requested_;
  const std::function<bool()>* enclosing_;
};

/// Whether the calling thread polls: it is in a CancelScope with a poll and not inside a
/// parallel loop (Δ's or an OpenMP region, where a library call runs serially on its thread,
/// which never polls).
///
/// Threading: about the calling thread only.
inline bool cancellable() noexcept {
  const std::function<bool()>* poll = detail::currentCancelPoll;
  return poll != nullptr && static_cast<bool>(*poll) && !detail::insideParallelLoop() &&
         !detail::insideOpenMpRegion();
}

/// Calls the poll of the calling thread's CancelScope (see there) when cancellable(); throws
/// Cancelled when it asks to stop, and lets what it throws propagate. Does nothing otherwise.
///
/// Threading: about the calling thread only.
inline void pollCancellation() {
  if (cancellable() && (*detail::currentCancelPoll)()) throw Cancelled();
}

/// parallelFor(first, last, grain, body) (core/parallel.h), in one parallel region as always;
/// when the calling thread is cancellable(), the calling thread (the parallel region's own
/// thread, never a worker) calls its scope's poll before each chunk of `grain` indices it takes
/// (with one thread, it runs the chunks itself, in order, polling before each).
/// A poll that asks to stop (Cancelled) or throws ends the loop as a throwing body does: chunks
/// under way on other threads finish, the others are skipped, and the exception is rethrown
/// here. So the latency of a stop is about one chunk's work.
///
/// Threading: as parallelFor.
template <typename Body>
void cancellableParallelFor(std::size_t first, std::size_t last, std::size_t grain,
                            const Body& body) {
  if (!cancellable()) {
    parallelFor(first, last, grain, body);
    return;
  }
  const std::function<bool()>& requested = *detail::currentCancelPoll;
  if (threadCount() == 1) {  // parallelFor would make one call of the whole range
    const std::size_t step = grain == 0 ? 1 : grain;
    for (std::size_t begin = first; begin < last; begin += std::min(step, last - begin)) {
      if (requested()) throw Cancelled();
      body(begin, begin + std::min(step, last - begin));
    }
    return;
  }
  // Thread 0 of the loop is the calling thread (and so is a loop run serially).
  parallelFor(first, last, grain, [&](std::size_t begin, std::size_t end) {
    if (loopThreadIndex() == 0 && requested()) throw Cancelled();
    body(begin, end);
  });
}

}  // namespace delta
