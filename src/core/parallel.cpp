#include "delta/core/parallel.h"

#include <omp.h>
#include <time.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>

namespace delta::detail {
namespace {

thread_local bool tInsideLoop = false;
thread_local bool tSerialLoops = false;
thread_local int tThreadIndex = 0;       ///< loopThreadIndex()
thread_local double tSpunSeconds = 0.0;  ///< threadWorkSeconds()

/// How long a thread of the pool watches for what it waits on before it sleeps in the kernel: a
/// worker for the next loop, a caller for the last chunks of its own. Woken from the kernel, a
/// thread on this workplace's virtual machines ran 25 µs late after a short sleep and over
/// 100 µs after a long one, which took from a DEM step's regions of 50 to 150 µs most of what a
/// second thread gave them; a step's regions follow each other within this. Passive past it:
/// with other processes on every core, a waiting thread holds its core no longer (and a World
/// under such load runs its steps on one thread, world.h, which judges the load by the CPU time
/// its thread worked: threadWorkSeconds leaves out these spins, as the sleeps they stand for).
constexpr std::chrono::microseconds kSpin{50};

/// A pause in a spin: the core's hint, where it has one.
inline void relax() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

/// Returns once `value` no longer holds `old` (as std::atomic::wait), having watched it for up
/// to kSpin before sleeping.
template <typename T>
void await(const std::atomic<T>& value, T old, std::memory_order order) {
  if (value.load(order) != old) return;
  const auto start = std::chrono::steady_clock::now();
  for (unsigned spins = 1;; ++spins) {
    relax();
    const bool changed = value.load(order) != old;
    if (changed || spins % 64 == 0) {
      const std::chrono::duration<double> spun = std::chrono::steady_clock::now() - start;
      if (changed || spun > kSpin) {
        tSpunSeconds += spun.count();
        if (changed) return;
        break;
      }
    }
  }
  value.wait(old, order);
}

/// Marks this thread as running chunks while it lives.
class InsideLoop {
 public:
  InsideLoop() noexcept { tInsideLoop = true; }
  ~InsideLoop() { tInsideLoop = false; }
  InsideLoop(const InsideLoop&) = delete;
  InsideLoop& operator=(const InsideLoop&) = delete;
};

/// Δ's threads: workers started on first use and kept, asleep between loops, one loop at a time.
///
/// A loop is published by storing its fields, then opening it and advancing `generation_`
/// (release), which wakes the workers. Each participant (the caller and the workers that join)
/// takes chunks (take: the caller from the front, workers from the back) and counts them done in
/// `done_`. The caller takes chunks until none is left, waits until every chunk is done, closes the
/// loop, then waits until no worker is inside it (`active_`): a worker joins only between its
/// increment and decrement of `active_` and only while the loop is open (both sequentially
/// consistent, as the caller's closing and reading of `active_`), so once the caller sees `active_`
/// at zero after closing, no worker touches the loop again and the next caller may rewrite its
/// fields.
class Pool {
 public:
  static Pool& instance() {
    static Pool* pool = new Pool;  // never destroyed: its workers sleep until the process ends
    return *pool;
  }

  bool run(std::size_t chunks, int threads, void (*call)(const void*, std::size_t),
           const void* body) {
    std::unique_lock<std::mutex> lock(busy_, std::try_to_lock);
    if (!lock.owns_lock()) return false;
    const std::uint64_t generation = generation_.load(std::memory_order_relaxed);
    try {
      for (; workers_ < threads - 1; ++workers_)
        std::thread([this, index = workers_, generation] { work(index, generation); }).detach();
    } catch (const std::system_error&) {
      // No more threads to be had (a process or system limit): the loop runs on those there are.
    }
    threads_.store(threads, std::memory_order_relaxed);
    chunks_.store(chunks, std::memory_order_relaxed);
    call_.store(call, std::memory_order_relaxed);
    body_.store(body, std::memory_order_relaxed);
    ends_.store(chunks < kSplitUpTo ? std::uint64_t{chunks} << 32 : 0, std::memory_order_relaxed);
    next_.store(0, std::memory_order_relaxed);
    done_.store(0, std::memory_order_relaxed);
    failed_.store(false, std::memory_order_relaxed);
    failure_ = nullptr;
    open_.store(true);
    generation_.fetch_add(1, std::memory_order_release);
    generation_.notify_all();
    {
      const InsideLoop inside;
      participate();
    }
    for (std::size_t done = done_.load(std::memory_order_acquire); done < chunks;
         done = done_.load(std::memory_order_acquire))
      await(done_, done, std::memory_order_acquire);
    // Sequentially consistent, as the workers' joining: either a worker's increment of active_
    // comes first and this waits for it, or the worker then sees the loop closed.
    open_.store(false);
    for (int active = active_.load(); active != 0; active = active_.load())
      await(active_, active, std::memory_order_seq_cst);
    if (failure_) {
      std::exception_ptr failure = failure_;
      failure_ = nullptr;
      lock.unlock();
      std::rethrow_exception(failure);
    }
    return true;
  }

 private:
  Pool() = default;

  /// Takes chunks of the open loop until none is left.
  void participate() {
    const std::size_t chunks = chunks_.load(std::memory_order_relaxed);
    const auto call = call_.load(std::memory_order_relaxed);
    const void* body = body_.load(std::memory_order_relaxed);
    // The chunks this thread ran are counted done once, when it finds none left: one update of
    // the shared count a thread, not a chunk (the two threads took turns at its cache line for
    // each of a sphere step's chunks of a few microseconds).
    std::size_t ran = 0;
    const bool front = tThreadIndex == 0;
    for (std::size_t chunk = take(chunks, front); chunk < chunks; chunk = take(chunks, front)) {
      if (!failed_.load(std::memory_order_relaxed)) {
        try {
          call(body, chunk);
        } catch (...) {
          const std::lock_guard<std::mutex> guard(failureMutex_);
          if (!failure_) failure_ = std::current_exception();
          failed_.store(true, std::memory_order_relaxed);
        }
      }
      ++ran;
    }
    if (ran > 0 && done_.fetch_add(ran, std::memory_order_acq_rel) + ran == chunks)
      done_.notify_all();
  }

  /// The next chunk for this thread, or `chunks` where none is left. The caller takes them from
  /// the front and the workers from the back, so that on two threads each keeps to its half of
  /// the range loop after loop, and the data a half touches stays in its core's cache (a sphere
  /// step's loops of a few microseconds a chunk spent their time moving cache lines between the
  /// cores); where one thread is late, the other takes its half too.
  std::size_t take(std::size_t chunks, bool front) noexcept {
    if (chunks >= kSplitUpTo) return next_.fetch_add(1, std::memory_order_relaxed);
    std::uint64_t ends = ends_.load(std::memory_order_relaxed);
    while (true) {
      const std::uint64_t first = ends & 0xffffffffu, end = ends >> 32;
      if (first >= end) return chunks;
      const std::uint64_t taken = front ? ends + 1 : ends - (std::uint64_t{1} << 32);
      if (ends_.compare_exchange_weak(ends, taken, std::memory_order_relaxed))
        return front ? first : end - 1;
    }
  }

  /// Worker `index`: sleeps until the generation moves past `seen`, then joins the loop if it is
  /// open and wants this many workers.
  void work(int index, std::uint64_t seen) {
    tThreadIndex = index + 1;
    while (true) {
      await(generation_, seen, std::memory_order_acquire);
      seen = generation_.load(std::memory_order_acquire);
      active_.fetch_add(1);
      if (open_.load() && index < threads_.load(std::memory_order_relaxed) - 1) {
        const InsideLoop inside;
        participate();
      }
      if (active_.fetch_sub(1) == 1) active_.notify_all();
    }
  }

  std::mutex busy_;  ///< held by the caller whose loop runs
  int workers_ = 0;  ///< started (under busy_)
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<bool> open_{false};
  std::atomic<int> active_{0};  ///< workers between joining and leaving
  // The loop: written by its caller before it opens, read by the participants.
  std::atomic<int> threads_{0};
  std::atomic<std::size_t> chunks_{0};
  std::atomic<void (*)(const void*, std::size_t)> call_{nullptr};
  std::atomic<const void*> body_{nullptr};
  /// Loops of fewer chunks take them from both ends of one word (take): the first not taken in
  /// its low half, the end of those not taken in its high half. Larger ones count up `next_`.
  static constexpr std::size_t kSplitUpTo = std::size_t{1} << 32;
  std::atomic<std::uint64_t> ends_{0};
  std::atomic<std::size_t> next_{0};
  std::atomic<std::size_t> done_{0};
  std::atomic<bool> failed_{false};
  std::mutex failureMutex_;
  std::exception_ptr failure_;  ///< under failureMutex_ while the loop runs
};

}  // namespace

bool runOnPool(std::size_t chunks, int threads, void (*call)(const void*, std::size_t),
               const void* body) {
  return Pool::instance().run(chunks, threads, call, body);
}

bool insideOpenMpRegion() noexcept {
  return omp_in_parallel() != 0;
}

bool insideParallelLoop() noexcept {
  return tInsideLoop;
}

bool serialLoops() noexcept {
  return tSerialLoops;
}

double threadCpuSeconds() noexcept {
  timespec time{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &time) == 0)
    return static_cast<double>(time.tv_sec) + 1e-9 * static_cast<double>(time.tv_nsec);
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double threadWorkSeconds() noexcept {
  return threadCpuSeconds() - tSpunSeconds;
}

SerialLoops::SerialLoops() noexcept : enclosing_(tSerialLoops) {
  tSerialLoops = true;
}

SerialLoops::~SerialLoops() {
  tSerialLoops = enclosing_;
}

}  // namespace delta::detail

namespace delta {

int threadCount() noexcept {
  const int requested = omp_get_max_threads();
  return requested < kMaxThreads ? requested : kMaxThreads;
}

int loopThreadIndex() noexcept {
  return detail::tThreadIndex;
}

}  // namespace delta
