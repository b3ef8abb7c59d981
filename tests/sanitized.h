#pragma once

// DELTA_TESTS_SANITIZED: defined in a build with AddressSanitizer or ThreadSanitizer, whichever
// compiler made it (GCC defines __SANITIZE_ADDRESS__ / __SANITIZE_THREAD__; clang answers
// __has_feature instead). Their shadow memory rules out an address-space limit (ulimit -v), and
// the instrumented code runs many times slower.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define DELTA_TESTS_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define DELTA_TESTS_SANITIZED 1
#endif
#endif
