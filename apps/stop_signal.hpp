// SIGINT, SIGTERM, SIGHUP (terminal closed) and SIGQUIT -> a stop flag that
// long-running nodes poll, so each ends through its own vent-and-report path.
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
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) sigaction(sig, &sa, nullptr);
    return true;
  }();
  (void)installed;
  return stop;
}

}  // namespace plsa::app
