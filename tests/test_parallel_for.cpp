// parallelFor: every index once, on the threads asked for, the first failure rethrown.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "plsa/core/parallel_for.hpp"

TEST(ParallelFor, RunsEveryIndexOnceOnAtMostTheThreadsAsked) {
  for (int threads : {1, 2, 5}) {
    for (std::size_t count : {std::size_t{0}, std::size_t{1}, std::size_t{3}, std::size_t{100}}) {
      std::vector<std::atomic<int>> runs(count);
      std::mutex m;
      std::set<std::thread::id> seen;
      plsa::parallelFor(count, threads, [&](std::size_t i) {
        ++runs[i];
        const std::lock_guard<std::mutex> lock(m);
        seen.insert(std::this_thread::get_id());
      });
      for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(runs[i].load(), 1) << "index " << i << " of " << count;
      EXPECT_LE(seen.size(), static_cast<std::size_t>(threads));
      if (threads == 1 && count > 0) {
        EXPECT_EQ(*seen.begin(), std::this_thread::get_id()) << "one thread: the caller";
      }
    }
  }
}

TEST(ParallelFor, FinishesTheOtherIndicesThenRethrowsTheFailure) {
  std::atomic<int> done{0};
  try {
    plsa::parallelFor(20, 2, [&](std::size_t i) {
      if (i == 7) throw std::runtime_error("index 7 failed");
      ++done;
    });
    FAIL() << "the failure was swallowed";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "index 7 failed");
  }
  EXPECT_EQ(done.load(), 19);
}
