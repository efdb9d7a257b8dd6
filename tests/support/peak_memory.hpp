#pragma once
// Test support: the process's peak resident memory, for tests that a hostile declared size is
// refused (or never allocated) rather than paid for. ctest runs every test in its own process,
// so a test's growth of the peak is what it allocated; run together, earlier tests may hide it.

#include <sys/resource.h>

#include <cstddef>

namespace ringtrack::test {

/// Peak resident set size of this process so far, bytes.
inline std::size_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

}  // namespace ringtrack::test
