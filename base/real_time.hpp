// The real-time scheduling class, and what rackcat's threads do with it.
//
// rackcat is run under `chrt -f N` (README, the interop tests) so that the device thread
// answers each frame within the master's timeout. Two rules follow from how Linux schedules
// SCHED_FIFO threads:
//   - Threads inherit the policy of the thread that creates them, and a FIFO thread is never
//     preempted by an equal one: every helper thread (capture and log writers, HTTP server,
//     parameter and firmware workers) calls leave_real_time() first, or a capture writer
//     flushing megabytes holds the CPU the device thread needs.
//   - A FIFO thread that polls without sleeping starves everything below it on its CPU,
//     including the kernel's softirq thread that delivers received frames: sched_yield()
//     only lets threads of the same priority run. The event loop therefore sleeps between
//     frames when it runs real-time (runs_real_time(), EventLoop::spin_window_ns()).
#pragma once

#include <pthread.h>
#include <sched.h>

namespace rackcat::base {

// Whether the calling thread runs in a real-time class (SCHED_FIFO or SCHED_RR).
inline bool runs_real_time() noexcept {
  int policy = 0;
  sched_param param{};
  if (pthread_getschedparam(pthread_self(), &policy, &param) != 0) return false;
  return policy == SCHED_FIFO || policy == SCHED_RR;
}

// Moves the calling thread to SCHED_OTHER if it runs real-time. Returns false only if the
// kernel refused, which POSIX does not allow for a thread lowering itself; the thread then runs
// on at the policy it inherited, the state before the call, so callers have nothing to undo.
inline bool leave_real_time() noexcept {
  if (!runs_real_time()) return true;
  sched_param param{};
  param.sched_priority = 0;
  return pthread_setschedparam(pthread_self(), SCHED_OTHER, &param) == 0;
}

}  // namespace rackcat::base
