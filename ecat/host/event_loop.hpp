// The slave's main loop: one thread that receives a frame, lets the segment process it in
// place, sends the reply, and in between fires the time-driven events of the ESCs (SYNC0/
// SYNC1 pulses at the distributed-clock times, process-data watchdog expiry).
//
//   frame in -> pcap -> FrameHandler (in place) -> pcap -> frame out
//
// Other threads (a control API) run code on the loop thread with post(); SIGINT and SIGTERM
// end run() cleanly with status 0. Two wait modes (WaitMode): Blocking sleeps in ppoll() on
// the socket and an eventfd (post(), stop(), signals) with the next timer deadline as the
// timeout; BusyPoll spins on non-blocking receives and checks the clock and flags between them.
// Blocking waits adaptively: after a frame it keeps polling without blocking for a
// short bounded window (Options::spin_after_frame_ns, default 100 µs) before it sleeps again,
// because masters send mailbox exchanges in bursts (an SDO upload is 5 frames back to back):
// one wake-up per burst instead of one per frame. With no frames it sleeps (0 % idle CPU); a
// master cycling every T costs at most spin/T extra CPU. A loop thread in a real-time class
// (chrt -f) never opens that window: polling at SCHED_FIFO starves the kernel's softirq work
// on its CPU - the delivery of the very frames it waits for - and ethercrab with 16 slaves lost
// a PDU after 30 ms in about half of its runs that way (base/real_time.hpp).
//
// Bursts: the frames a master sent before it could have seen a reply - the kernel's receive
// timestamp is earlier than the moment that reply left (RawSocketLink::try_receive_sent_before)
// - are answered right after it, before its after-frame work: SOEM sends a process image
// larger than one frame as several frames back to back and collects the replies after, and a
// real ESC answers each of them as it passes, whatever its firmware is doing. One round of work
// then follows the last of them. A frame that came after the reply left still waits for the
// work (below), so a master that reacts to a reply always sees the firmware's reaction.
//
// After-frame work (set_after_frame_work) runs in slices after the reply; between slices - once
// the work has had Options::work_before_yield_ns and for Options::yield_window_ns after the
// reply - the loop takes a frame that is waiting (a
// non-blocking receive, about 0.4 µs when none is), so a master sending back to back waits for
// one slice at most, not for all the work of its previous frame. A frame found later than that
// (a master with a real cycle time, or the loop thread was descheduled) waits for the work to
// finish, exactly as before slices existed.
//
// Signals: a SIGINT/SIGTERM handler (SA_RESTART) records the signal and wakes the loop through
// its eventfd. Whichever thread the kernel picks to run it, the process is not killed, so
// threads started before the loop (with any signal mask) are harmless.
//
// The cyclic path allocates nothing: the frame is the link's fixed buffer, the handlers are
// set once, and post() allocates only on the posting thread.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <span>
#include <vector>

#include "ecat/host/raw_socket_link.hpp"

namespace rackcat::ecat {

class PcapWriter;

// Time-driven work of the slaves, in CLOCK_MONOTONIC nanoseconds (monotonic_ns()).
class TimerSource {
 public:
  virtual ~TimerSource() = default;
  // The earliest time something is due, or kNever. Asked after every frame and every
  // on_time(); must be cheap (a few comparisons).
  virtual uint64_t next_deadline_ns() const = 0;
  // Fire everything due at or before now_ns (SYNC pulses, watchdog expiry).
  virtual void on_time(uint64_t now_ns) = 0;

  static constexpr uint64_t kNever = UINT64_MAX;
};

uint64_t monotonic_ns();
// CLOCK_REALTIME nanoseconds: the clock of the kernel's receive timestamps.
uint64_t realtime_ns();

class EventLoop {
 public:
  // Processes one received frame in place. Returns the reply length to send (normally the
  // frame's own length), or 0 to send nothing.
  using FrameHandler = std::function<size_t(std::span<uint8_t> frame)>;

  struct Options {
    WaitMode wait = WaitMode::Blocking;
    PcapWriter* pcap = nullptr;   // not owned; flushed when run() returns
    bool stop_on_signals = true;  // SIGINT/SIGTERM end run()
    // Blocking mode: after a frame, poll without sleeping this long for the next (0 = off).
    // Not used on a real-time thread (spin_window_ns()).
    uint64_t spin_after_frame_ns = 100'000;
    // After-frame work yields to a waiting frame only this long after the last reply was
    // sent (see set_after_frame_work): a master sending back to back. A frame found later
    // (a master with a longer cycle, or this thread was descheduled) is answered once the work
    // is done, so at cycle times above the window every slave's inputs are as fresh as before.
    // 0 (the default): never; every frame's work is finished before the next frame.
    uint64_t yield_window_ns = 0;
    // ... and only once the work has run this long since the last reply: a round of work
    // shorter than this (16 tiny racks: about 12 µs) is always finished before the next frame
    // is answered, at any frame rate.
    uint64_t work_before_yield_ns = 20'000;
  };

  // Installs the SIGINT/SIGTERM handler. From then on such a signal no longer kills the
  // process: it is remembered and ends the next (or current) run() of the loop constructed
  // with stop_on_signals. Call it early (the Runner does, before opening anything) so a signal
  // during start-up is not lost; the constructor calls it too. Idempotent.
  static void install_stop_signal_handler();

  EventLoop(RawSocketLink& link, Options options);
  ~EventLoop();
  EventLoop(const EventLoop&) = delete;
  EventLoop& operator=(const EventLoop&) = delete;

  void set_frame_handler(FrameHandler handler) { on_frame_ = std::move(handler); }
  // Work a frame leaves for after its reply has been sent (the slaves' firmware:
  // Segment::run_firmware_slice), done in bounded slices: one slice right after each reply,
  // then - while the handler returns true (more to do) - a frame waiting in the socket is
  // answered before the next slice, once the work has run Options::work_before_yield_ns and
  // as long as the frame is found within Options::yield_window_ns of the last reply;
  // otherwise the work is finished first. Every frame is followed by at
  // least one slice, so the work progresses at any frame rate; the loop sleeps only once the
  // work is done.
  using WorkSlice = std::function<bool()>;
  void set_after_frame_work(WorkSlice slice) { after_frame_ = std::move(slice); }
  void set_timer_source(TimerSource* source) { timers_ = source; }

  // Runs until stop() or SIGINT/SIGTERM. Returns 0 on a clean stop, 1 when the loop could
  // not wait (a failing system call). Runs on the calling thread.
  int run();

  // Thread-safe (and safe from the loop thread itself).
  void post(std::function<void()> fn);
  void stop();

  // The window run() polls after a frame when called on this thread: spin_after_frame_ns, or
  // 0 on a real-time thread.
  uint64_t spin_window_ns() const;

  bool running() const { return running_.load(std::memory_order_relaxed); }
  int stop_signal() const { return stop_signal_; }  // the signal that ended run(), or 0
  uint64_t frames_handled() const { return frames_; }
  // Frames answered before the after-frame work of the frame ahead of them in their burst.
  uint64_t burst_frames() const { return burst_frames_; }

 private:
  // A frame, the rest of its burst, then the first slice of after-frame work.
  void handle_frame(std::span<uint8_t> frame);
  // Processes and answers one frame; returns when its reply was sent (realtime_ns(), taken
  // just before the send) when there is after-frame work, else 0 (also when it sent none: a
  // master saw nothing, so no burst follows it).
  uint64_t answer(std::span<uint8_t> frame);
  // One step of pending after-frame work: a waiting frame (true; only within the yield
  // window after the last frame), else one slice (false).
  bool work_slice();
  void run_slice();  // one call of after_frame_, its time added to work_done_ns_
  void run_posted();
  bool take_stop_signal();  // true when a stop signal arrived (and records it)
  void fire_timers(uint64_t now);
  int run_blocking();
  int run_busy_poll();

  RawSocketLink& link_;
  Options options_;
  FrameHandler on_frame_;
  WorkSlice after_frame_;
  bool work_left_ = false;      // after_frame_ returned true: run it again before sleeping
  uint64_t frame_done_ns_ = 0;  // when the last frame's reply was sent (the yield window)
  uint64_t work_done_ns_ = 0;   // time in after-frame work since then
  TimerSource* timers_ = nullptr;
  int event_fd_ = -1;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> posted_pending_{false};
  std::atomic<bool> running_{false};
  int stop_signal_ = 0;
  uint64_t frames_ = 0;
  uint64_t burst_frames_ = 0;
  std::mutex posted_mutex_;
  std::vector<std::function<void()>> posted_;
  std::vector<std::function<void()>> running_posted_;
};

}  // namespace rackcat::ecat
