// Puts the calling thread on a real-time footing where the system permits
// it: SCHED_FIFO at a given priority, all memory locked (now and future), the
// heap kept mapped, and the stack pre-faulted, so a control loop does not
// wait for the scheduler or a page fault. Says what it got and why not.
#pragma once

#include <malloc.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace plsa {

struct RealTimeSetUp {
  bool fifo = false;    ///< SCHED_FIFO granted
  bool locked = false;  ///< mlockall succeeded
  std::string words;    ///< what was granted and refused, for logs
};

/// priority 1..99 for SCHED_FIFO; 0 leaves the scheduling as it is (memory is
/// still locked and pre-faulted). Never throws; refusals are reported.
inline RealTimeSetUp enterRealTime(int priority) {
  RealTimeSetUp r;
  if (priority > 0) {
    sched_param sp{};
    sp.sched_priority = priority;
    r.fifo = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
    r.words = r.fifo ? "SCHED_FIFO priority " + std::to_string(priority)
                     : std::string("SCHED_FIFO not permitted (") + std::strerror(errno) +
                           "; run as root or with CAP_SYS_NICE, or raise RLIMIT_RTPRIO), normal scheduling";
  } else {
    r.words = "normal scheduling (no real-time priority asked)";
  }
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  // A sanitizer maps terabytes of shadow memory: locking it all would fault it in.
  r.words += ", memory not locked (sanitizer build)";
#else
  mallopt(M_TRIM_THRESHOLD, -1);  // freed heap stays mapped and faulted in
  mallopt(M_MMAP_MAX, 0);
  r.locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
  r.words += r.locked ? ", memory locked" : std::string(", mlockall not permitted (") + std::strerror(errno) + ")";
#endif
  volatile char stack[256 * 1024];
  for (std::size_t i = 0; i < sizeof stack; i += 4096) stack[i] = 0;
  r.words += ", 256 KB of stack pre-faulted";
  return r;
}

}  // namespace plsa
