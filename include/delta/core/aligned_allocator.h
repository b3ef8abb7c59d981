#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace delta {

/// A standard allocator whose blocks start on an `Alignment`-byte boundary, so that SIMD code
/// may use aligned loads on the first element of a `std::vector`.
///
/// Threading: stateless; safe to use from any thread.
template <typename T, std::size_t Alignment>
struct AlignedAllocator {
  static_assert(Alignment >= alignof(T) && (Alignment & (Alignment - 1)) == 0);
  using value_type = T;

  template <typename U>
  struct rebind {
    using other = AlignedAllocator<U, Alignment>;
  };

  AlignedAllocator() noexcept = default;
  template <typename U>
  AlignedAllocator(const AlignedAllocator<U, Alignment>&) noexcept {}

  /// `n` elements, uninitialised, on an `Alignment`-byte boundary. Throws std::bad_alloc (or
  /// std::bad_array_new_length when n·sizeof(T) overflows), as `new` does.
  T* allocate(std::size_t n) {
    if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(::operator new (n * sizeof(T), std::align_val_t{Alignment}));
  }
  void deallocate(T* p, std::size_t) noexcept {
    ::operator delete (p, std::align_val_t{Alignment});
  }

  template <typename U>
  bool operator==(const AlignedAllocator<U, Alignment>&) const noexcept {
    return true;
  }
};

/// A vector of doubles whose storage is 64-byte aligned (one cache line, one AVX-512 register).
using AlignedDoubles = std::vector<double, AlignedAllocator<double, 64>>;

}  // namespace delta
