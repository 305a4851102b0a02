// Counts heap allocations made by the current thread inside a scope, so a test
// can prove a hot loop allocates nothing (budget 0). Link plsa::alloc_counter,
// which replaces global operator new (and malloc, outside sanitizer builds).
#pragma once

#include <cstdint>

namespace plsa::testing {

/// Allocations counted on this thread since start-up (only while a guard is armed).
std::uint64_t threadAllocationCount() noexcept;
/// Whether malloc/calloc/realloc are counted too (false under ASan/TSan,
/// which own malloc; operator new is always counted).
bool countsMalloc() noexcept;

/// Arms counting for this thread in its lifetime; `allocations()` reads the
/// count since construction.
class AllocGuard {
 public:
  AllocGuard() noexcept;
  ~AllocGuard();
  AllocGuard(const AllocGuard&) = delete;
  AllocGuard& operator=(const AllocGuard&) = delete;
  std::uint64_t allocations() const noexcept;

 private:
  std::uint64_t start_;
  bool was_armed_;
};

}  // namespace plsa::testing
