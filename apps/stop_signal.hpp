// SIGINT/SIGTERM -> a stop flag that long-running nodes poll.
#pragma once

#include <atomic>
#include <csignal>

namespace plsa::app {

/// Installs the handlers once and returns the flag they set.
inline const std::atomic<bool>& stopOnSignals() {
  static std::atomic<bool> stop{false};
  static const bool installed = [] {
    struct sigaction sa {};
    sa.sa_handler = [](int) { stop.store(true); };
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    return true;
  }();
  (void)installed;
  return stop;
}

}  // namespace plsa::app
