// Offline work spread over threads: work(0) .. work(count - 1), each index
// once, on up to `threads` threads (the calling one among them). Never in the
// real-time path: it starts threads. Link Threads::Threads where it is used.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace plsa {

/// Runs work(i) for every i in [0, count) on min(threads, count) threads (at
/// least one: the caller's), the indices dealt out as threads come free; waits
/// for all, then rethrows the first exception any work threw.
template <typename Work>
void parallelFor(std::size_t count, int threads, const Work& work) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto drain = [&] {
    for (std::size_t i = next++; i < count; i = next++) {
      try {
        work(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
      }
    }
  };
  const auto extra = static_cast<std::size_t>(std::max(1, threads)) - 1;
  std::vector<std::thread> pool;
  for (std::size_t t = 0; t < std::min(extra, count > 0 ? count - 1 : 0); ++t) pool.emplace_back(drain);
  drain();
  for (std::thread& th : pool) th.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace plsa
