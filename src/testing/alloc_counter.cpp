// Global replacements of operator new (and, without sanitizers, malloc) that
// count allocations on threads with an armed AllocGuard.
#include "plsa/testing/alloc_guard.hpp"

#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PLSA_COUNT_MALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define PLSA_COUNT_MALLOC 0
#endif
#endif
#ifndef PLSA_COUNT_MALLOC
#define PLSA_COUNT_MALLOC 1
#endif

namespace {
// Trivially constructed thread-locals: no allocation and no guard on access.
thread_local bool t_armed = false;
thread_local std::uint64_t t_count = 0;

inline void note() noexcept {
  if (t_armed) ++t_count;
}
}  // namespace

namespace plsa::testing {

std::uint64_t threadAllocationCount() noexcept { return t_count; }
bool countsMalloc() noexcept { return PLSA_COUNT_MALLOC != 0; }

AllocGuard::AllocGuard() noexcept : start_(t_count), was_armed_(t_armed) { t_armed = true; }
AllocGuard::~AllocGuard() { t_armed = was_armed_; }
std::uint64_t AllocGuard::allocations() const noexcept { return t_count - start_; }

}  // namespace plsa::testing

#if PLSA_COUNT_MALLOC
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  note();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t m) {
  note();
  return __libc_calloc(n, m);
}
void* realloc(void* p, std::size_t n) {
  note();
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
}
#endif

namespace {
void* countedNew(std::size_t n) {
  note();
  // With malloc counted too, go to libc directly so one new counts once.
#if PLSA_COUNT_MALLOC
  void* p = __libc_malloc(n == 0 ? 1 : n);
#else
  void* p = std::malloc(n == 0 ? 1 : n);
#endif
  if (!p) throw std::bad_alloc();
  return p;
}
void* countedAlignedNew(std::size_t n, std::align_val_t al) {
  note();
  const std::size_t a = static_cast<std::size_t>(al);
  void* p = std::aligned_alloc(a, ((n == 0 ? 1 : n) + a - 1) / a * a);
  if (!p) throw std::bad_alloc();
  return p;
}
void countedDelete(void* p) noexcept {
#if PLSA_COUNT_MALLOC
  __libc_free(p);
#else
  std::free(p);
#endif
}
}  // namespace

void* operator new(std::size_t n) { return countedNew(n); }
void* operator new[](std::size_t n) { return countedNew(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return countedNew(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return countedNew(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t n, std::align_val_t a) { return countedAlignedNew(n, a); }
void* operator new[](std::size_t n, std::align_val_t a) { return countedAlignedNew(n, a); }
void operator delete(void* p) noexcept { countedDelete(p); }
void operator delete[](void* p) noexcept { countedDelete(p); }
void operator delete(void* p, std::size_t) noexcept { countedDelete(p); }
void operator delete[](void* p, std::size_t) noexcept { countedDelete(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
