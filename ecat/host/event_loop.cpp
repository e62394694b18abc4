#include "ecat/host/event_loop.hpp"

#include <poll.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/prctl.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <ctime>

#include "base/real_time.hpp"
#include "ecat/host/pcap_writer.hpp"

namespace rackcat::ecat {
namespace {

// The capture is written out by the PcapWriter's own thread (pcap_writer.hpp); the loop
// only hands it frames.

// Shared with the signal handler: only lock-free atomics and write(2), which are
// async-signal-safe.
std::atomic<int> g_stop_signal{0};
std::atomic<int> g_wake_fd{-1};
static_assert(std::atomic<int>::is_always_lock_free);

void on_stop_signal(int sig) {
  const int saved_errno = errno;
  g_stop_signal.store(sig, std::memory_order_release);
  const int fd = g_wake_fd.load(std::memory_order_acquire);
  if (fd >= 0) {
    const uint64_t one = 1;
    (void)!::write(fd, &one, sizeof(one));
  }
  errno = saved_errno;
}

}  // namespace

uint64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

uint64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

void EventLoop::install_stop_signal_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  // SA_RESTART: other threads' blocking calls carry on; the loop is woken by the eventfd.
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

EventLoop::EventLoop(RawSocketLink& link, Options options) : link_(link), options_(options) {
  event_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (event_fd_ < 0) throw std::runtime_error("event loop: eventfd failed");
  if (options_.stop_on_signals) {
    install_stop_signal_handler();
    g_wake_fd.store(event_fd_, std::memory_order_release);
  }
  // Posted work is rare; reserving keeps the loop-side swap from allocating.
  posted_.reserve(16);
  running_posted_.reserve(16);
}

EventLoop::~EventLoop() {
  if (options_.stop_on_signals) {
    int expected = event_fd_;
    g_wake_fd.compare_exchange_strong(expected, -1, std::memory_order_acq_rel);
  }
  if (event_fd_ >= 0) ::close(event_fd_);
}

void EventLoop::post(std::function<void()> fn) {
  {
    std::lock_guard lock(posted_mutex_);
    posted_.push_back(std::move(fn));
  }
  posted_pending_.store(true, std::memory_order_release);
  const uint64_t one = 1;
  (void)!::write(event_fd_, &one, sizeof(one));
}

void EventLoop::stop() {
  stop_requested_.store(true, std::memory_order_release);
  const uint64_t one = 1;
  (void)!::write(event_fd_, &one, sizeof(one));
}

void EventLoop::run_posted() {
  uint64_t count = 0;
  (void)!::read(event_fd_, &count, sizeof(count));
  if (!posted_pending_.exchange(false, std::memory_order_acq_rel)) return;
  {
    std::lock_guard lock(posted_mutex_);
    running_posted_.swap(posted_);
  }
  for (auto& fn : running_posted_) fn();
  running_posted_.clear();
}

bool EventLoop::take_stop_signal() {
  if (!options_.stop_on_signals) return false;
  const int sig = g_stop_signal.exchange(0, std::memory_order_acq_rel);
  if (sig == 0) return false;
  stop_signal_ = sig;
  stop_requested_.store(true, std::memory_order_release);
  return true;
}

void EventLoop::handle_frame(std::span<uint8_t> frame) {
  const uint64_t replied = answer(frame);
  if (!after_frame_) return;
  // The rest of a burst first. A frame that reached the socket before this reply left was
  // sent by a master that had not seen the reply: SOEM sends a process image larger than one
  // frame as several frames back to back and then collects the replies. Nothing in those can
  // depend on what the firmware makes of this frame - a real ESC answers each frame as it
  // passes while its firmware runs beside it - so they are answered now, and the one round
  // after the last covers them all (Segment::process). A frame sent once the master had the
  // reply (the next cycle, a mailbox poll) still finds every frame's work done.
  // (No reply, no burst: the master saw nothing.)
  for (auto next = replied != 0 ? link_.try_receive_sent_before(replied) : std::span<uint8_t>{};
       !next.empty(); next = link_.try_receive_sent_before(replied)) {
    ++burst_frames_;
    (void)answer(next);
  }
  work_done_ns_ = 0;
  run_slice();
}

uint64_t EventLoop::answer(std::span<uint8_t> frame) {
  ++frames_;
  if (options_.pcap != nullptr) options_.pcap->write(frame);
  if (!on_frame_) return 0;
  const size_t reply = on_frame_(frame);
  // The yield window starts before the send: sending on a veth wakes the master in the
  // same system call, and the scheduler may run it before this thread returns - a clock read
  // after the send could then be later than the master's next frame. The same holds for the
  // burst's bound (handle_frame), on the clock of the kernel's receive timestamps.
  uint64_t sent = 0;
  if (after_frame_) frame_done_ns_ = monotonic_ns();
  if (reply != 0 && reply <= frame.size()) {
    if (after_frame_) sent = realtime_ns();
    const auto out = frame.first(reply);
    link_.send(out);
    if (options_.pcap != nullptr) options_.pcap->write(out);
  }
  return sent;
}

void EventLoop::run_slice() {
  const uint64_t start = monotonic_ns();
  work_left_ = after_frame_();
  work_done_ns_ += monotonic_ns() - start;
}

bool EventLoop::work_slice() {
  // A frame that is waiting may overtake the work once the work has had its minimum share
  // (work_before_yield_ns of slices since the last reply: a short round is always finished
  // first) and only within the yield window; its reply is followed by a slice of its own.
  // Otherwise the work is finished before the socket is looked at again. The window is
  // checked on both sides of the receive: a thread descheduled in between finds a frame that
  // may have come much later, and finishes the work before it answers that frame.
  if (work_done_ns_ >= options_.work_before_yield_ns &&
      monotonic_ns() - frame_done_ns_ < options_.yield_window_ns) {
    const auto frame = link_.try_receive();
    if (!frame.empty()) {
      if (monotonic_ns() - frame_done_ns_ >= options_.yield_window_ns) {
        while (after_frame_()) {
        }
      }
      handle_frame(frame);
      return true;
    }
  }
  run_slice();
  return false;
}

void EventLoop::fire_timers(uint64_t now) {
  if (timers_ != nullptr && timers_->next_deadline_ns() <= now) timers_->on_time(now);
}

int EventLoop::run() {
  // Timer slack widens every sleep by 50 µs by default; SYNC pulses want the exact time.
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  stop_signal_ = 0;
  running_.store(true, std::memory_order_relaxed);
  // A stop() that came before run() ends it at once; it is consumed here so that the loop
  // can be run again.
  const int rc = options_.wait == WaitMode::BusyPoll ? run_busy_poll() : run_blocking();
  stop_requested_.store(false, std::memory_order_release);
  running_.store(false, std::memory_order_relaxed);
  if (options_.pcap != nullptr) options_.pcap->flush();
  return rc;
}

uint64_t EventLoop::spin_window_ns() const {
  return base::runs_real_time() ? 0 : options_.spin_after_frame_ns;
}

int EventLoop::run_blocking() {
  pollfd fds[2] = {{link_.fd(), POLLIN, 0}, {event_fd_, POLLIN, 0}};
  const uint64_t spin_ns = spin_window_ns();
  // Posts and signals that arrived before run() are handled on the first pass.
  if (take_stop_signal()) return 0;
  run_posted();
  uint64_t spin_until = 0;  // adaptive waiting: no sleep before this time (after a frame)
  while (!stop_requested_.load(std::memory_order_acquire)) {
    uint64_t now = monotonic_ns();
    fire_timers(now);
    if (work_left_) {
      if (work_slice() && spin_ns != 0) spin_until = monotonic_ns() + spin_ns;
      if (posted_pending_.load(std::memory_order_acquire)) run_posted();
      if (g_stop_signal.load(std::memory_order_relaxed) != 0 && take_stop_signal()) break;
      continue;
    }
    if (now < spin_until) {
      // The bounded window after a frame: non-blocking receives, posts and signals checked
      // between them, timers above; then back to sleeping in ppoll.
      const auto frame = link_.try_receive();
      if (!frame.empty()) {
        handle_frame(frame);
        spin_until = monotonic_ns() + spin_ns;
      }
      if (posted_pending_.load(std::memory_order_acquire)) run_posted();
      if (g_stop_signal.load(std::memory_order_relaxed) != 0 && take_stop_signal()) break;
      // The master may share this core: give it the CPU whenever it is runnable, so the
      // window costs only time nobody else wants.
      sched_yield();
      continue;
    }
    uint64_t deadline = timers_ != nullptr ? timers_->next_deadline_ns() : TimerSource::kNever;
    timespec timeout{};
    timespec* timeout_ptr = nullptr;
    if (deadline != TimerSource::kNever) {
      const uint64_t wait = deadline > now ? deadline - now : 0;
      timeout.tv_sec = static_cast<time_t>(wait / 1'000'000'000ull);
      timeout.tv_nsec = static_cast<long>(wait % 1'000'000'000ull);
      timeout_ptr = &timeout;
    }
    const int ready = ::ppoll(fds, 2, timeout_ptr, nullptr);
    if (ready < 0) {
      if (errno == EINTR) continue;
      return 1;
    }
    if ((fds[0].revents | fds[1].revents) & POLLNVAL) return 1;
    if (ready == 0) continue;
    // One frame per wake-up: if more are queued ppoll returns at once, and we save the
    // receive call that would only report "empty".
    // POLLERR (the interface went down): the receive call consumes the pending error, so the
    // loop does not spin on it; frames flow again when the interface comes back.
    if (fds[0].revents & (POLLIN | POLLERR)) {
      const auto frame = link_.try_receive();
      if (!frame.empty()) {
        handle_frame(frame);
        if (spin_ns != 0) spin_until = monotonic_ns() + spin_ns;
      }
    }
    if (fds[1].revents & POLLIN) {
      run_posted();
      if (take_stop_signal()) break;
    }
  }
  return 0;
}

int EventLoop::run_busy_poll() {
  uint64_t now = monotonic_ns();
  uint64_t deadline = timers_ != nullptr ? timers_->next_deadline_ns() : TimerSource::kNever;
  while (!stop_requested_.load(std::memory_order_acquire)) {
    if (work_left_) {
      if (work_slice() && timers_ != nullptr) deadline = timers_->next_deadline_ns();
    } else if (const auto frame = link_.try_receive(); !frame.empty()) {
      handle_frame(frame);
      // A frame may have programmed new SYNC times or kicked a watchdog.
      if (timers_ != nullptr) deadline = timers_->next_deadline_ns();
    }
    now = monotonic_ns();
    if (now >= deadline) {
      timers_->on_time(now);
      deadline = timers_->next_deadline_ns();
    }
    if (posted_pending_.load(std::memory_order_acquire)) {
      run_posted();
      if (timers_ != nullptr) deadline = timers_->next_deadline_ns();
    }
    if (g_stop_signal.load(std::memory_order_relaxed) != 0 && take_stop_signal()) break;
  }
  return 0;
}

}  // namespace rackcat::ecat
