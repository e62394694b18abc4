#include "ecat/event_loop.hpp"

#include <poll.h>
#include <pthread.h>
#include <sys/eventfd.h>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <ctime>

#include "ecat/pcap_writer.hpp"

namespace rackcat::ecat {
namespace {

// How often the busy-poll loop looks at signals, and how often the pcap buffer is written
// out while frames flow (so a killed process still leaves a useful capture).
constexpr uint64_t kHousekeepingNs = 1'000'000;
constexpr uint64_t kPcapFlushNs = 1'000'000'000;

sigset_t stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  return set;
}

}  // namespace

uint64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

void EventLoop::block_stop_signals() {
  sigset_t set = stop_signals();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

EventLoop::EventLoop(RawSocketLink& link, Options options) : link_(link), options_(options) {
  event_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (event_fd_ < 0) throw std::runtime_error("event loop: eventfd failed");
  if (options_.stop_on_signals) {
    block_stop_signals();
    sigset_t set = stop_signals();
    signal_fd_ = signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
    if (signal_fd_ < 0) {
      ::close(event_fd_);
      throw std::runtime_error("event loop: signalfd failed");
    }
  }
  // Posted work is rare; reserving keeps the loop-side swap from allocating.
  posted_.reserve(16);
  running_posted_.reserve(16);
}

EventLoop::~EventLoop() {
  if (signal_fd_ >= 0) ::close(signal_fd_);
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

bool EventLoop::drain_signals() {
  if (signal_fd_ < 0) return false;
  signalfd_siginfo info{};
  bool stop = false;
  while (::read(signal_fd_, &info, sizeof(info)) == static_cast<ssize_t>(sizeof(info))) {
    stop_signal_ = static_cast<int>(info.ssi_signo);
    stop = true;
  }
  if (stop) stop_requested_.store(true, std::memory_order_release);
  return stop;
}

void EventLoop::handle_frame(std::span<uint8_t> frame) {
  ++frames_;
  if (options_.pcap != nullptr) options_.pcap->write(frame);
  if (!on_frame_) return;
  const size_t reply = on_frame_(frame);
  if (reply == 0 || reply > frame.size()) return;
  const auto out = frame.first(reply);
  link_.send(out);
  if (options_.pcap != nullptr) options_.pcap->write(out);
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

int EventLoop::run_blocking() {
  pollfd fds[3] = {{link_.fd(), POLLIN, 0}, {event_fd_, POLLIN, 0}, {signal_fd_, POLLIN, 0}};
  const nfds_t nfds = signal_fd_ >= 0 ? 3 : 2;
  uint64_t next_flush = monotonic_ns() + kPcapFlushNs;
  // Posts and signals that arrived before run() are handled on the first pass.
  if (drain_signals()) return 0;
  run_posted();
  while (!stop_requested_.load(std::memory_order_acquire)) {
    uint64_t now = monotonic_ns();
    fire_timers(now);
    uint64_t deadline = timers_ != nullptr ? timers_->next_deadline_ns() : TimerSource::kNever;
    if (options_.pcap != nullptr) {
      if (now >= next_flush) {
        options_.pcap->flush();
        next_flush = now + kPcapFlushNs;
      }
      deadline = std::min(deadline, next_flush);
    }
    timespec timeout{};
    timespec* timeout_ptr = nullptr;
    if (deadline != TimerSource::kNever) {
      const uint64_t wait = deadline > now ? deadline - now : 0;
      timeout.tv_sec = static_cast<time_t>(wait / 1'000'000'000ull);
      timeout.tv_nsec = static_cast<long>(wait % 1'000'000'000ull);
      timeout_ptr = &timeout;
    }
    const int ready = ::ppoll(fds, nfds, timeout_ptr, nullptr);
    if (ready < 0) {
      if (errno == EINTR) continue;
      return 1;
    }
    if ((fds[0].revents | fds[1].revents | fds[2].revents) & POLLNVAL) return 1;
    if (ready == 0) continue;
    // One frame per wake-up: if more are queued ppoll returns at once, and we save the
    // receive call that would only report "empty".
    // POLLERR (the interface went down): the receive call consumes the pending error, so the
    // loop does not spin on it; frames flow again when the interface comes back.
    if (fds[0].revents & (POLLIN | POLLERR)) {
      const auto frame = link_.try_receive();
      if (!frame.empty()) handle_frame(frame);
    }
    if (fds[1].revents & POLLIN) run_posted();
    if (nfds > 2 && (fds[2].revents & POLLIN) && drain_signals()) break;
  }
  return 0;
}

int EventLoop::run_busy_poll() {
  uint64_t now = monotonic_ns();
  uint64_t next_housekeeping = now;
  uint64_t next_flush = now + kPcapFlushNs;
  uint64_t deadline = timers_ != nullptr ? timers_->next_deadline_ns() : TimerSource::kNever;
  while (!stop_requested_.load(std::memory_order_acquire)) {
    const auto frame = link_.try_receive();
    if (!frame.empty()) {
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
    if (now >= next_housekeeping) {
      next_housekeeping = now + kHousekeepingNs;
      if (drain_signals()) break;
      if (options_.pcap != nullptr && now >= next_flush) {
        options_.pcap->flush();
        next_flush = now + kPcapFlushNs;
      }
    }
  }
  return 0;
}

}  // namespace rackcat::ecat
