// Threads other than the device thread leave the real-time class.
//
// rackcat is run under `chrt -f N` (README, the interop tests) so that the device thread
// answers each frame within the master's timeout. Linux threads inherit the scheduling policy
// of the thread that creates them, so without this every helper thread - the capture writer,
// the log writer, the HTTP server, the parameter and firmware workers, the RIM link - would
// also be SCHED_FIFO at the same priority. A FIFO thread is never preempted by an equal one:
// a capture writer flushing megabytes, or an HTTP worker, then holds the CPU the device
// thread needs and a frame waits milliseconds for its reply (seen as SOEM SDO timeouts).
// Each helper thread calls this first; the device thread keeps the policy it was started with.
#pragma once

#include <pthread.h>
#include <sched.h>

namespace rackcat::base {

// Returns false only if the kernel refused, which POSIX does not allow for a thread lowering
// itself to SCHED_OTHER; the thread then runs on at the policy it inherited, the state before
// the call, so callers have nothing to undo and only tests look at the result.
inline bool leave_real_time() noexcept {
  int policy = 0;
  sched_param param{};
  if (pthread_getschedparam(pthread_self(), &policy, &param) != 0) return false;
  if (policy != SCHED_FIFO && policy != SCHED_RR) return true;
  param.sched_priority = 0;
  return pthread_setschedparam(pthread_self(), SCHED_OTHER, &param) == 0;
}

}  // namespace rackcat::base
