// EventLoop: frame in -> handler in place -> frame out (and both in the pcap), post() from
// other threads, timer deadlines, and a clean stop on SIGTERM. On the loopback interface;
// skipped without CAP_NET_RAW.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <iterator>
#include <thread>

#include "ecat/host/event_loop.hpp"
#include "ecat/host/pcap_writer.hpp"
#include "ecat/host/raw_socket_link.hpp"
#include "tests/ecat/link_test_util.hpp"

namespace rackcat::ecat {
namespace {

class LinkEventLoop : public ::testing::TestWithParam<WaitMode> {
 protected:
  void SetUp() override {
    if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  }
};

// Data bytes 1..3 of the test frames carry this process's id, so tests running in parallel
// on lo neither answer nor accept each other's frames.
void stamp(std::vector<uint8_t>& frame) {
  const auto pid = static_cast<uint32_t>(getpid());
  for (int i = 0; i < 3; ++i) {
    frame[testutil::kFirstDataByte + 1 + i] = static_cast<uint8_t>(pid >> (8 * i));
  }
}

bool ours(std::span<const uint8_t> frame) {
  const auto pid = static_cast<uint32_t>(getpid());
  for (int i = 0; i < 3; ++i) {
    if (frame[testutil::kFirstDataByte + 1 + i] != static_cast<uint8_t>(pid >> (8 * i))) {
      return false;
    }
  }
  return true;
}

// Answers like an ESC (source-MAC bit 0x02 set, tag byte incremented). Frames that already
// carry the bit are our own replies looping back on lo: no answer.
size_t answer(std::span<uint8_t> frame) {
  if (frame.size() < 60 || !ours(frame) || (frame[6] & 0x02)) return 0;
  frame[6] |= 0x02;
  frame[testutil::kFirstDataByte] += 1;
  return frame.size();
}

// The master's side of one exchange on lo: sends a test frame tagged `tag` and waits for the
// loop's answer to it (tag + 1); returns the answer, empty when none came.
std::vector<uint8_t> exchange(RawSocketLink& master_link, uint8_t tag) {
  auto frame = testutil::ethercat_frame(tag);
  stamp(frame);
  master_link.send(frame);
  return testutil::receive_matching(master_link, [tag](std::span<const uint8_t> f) {
    return ours(f) && (f[6] & 0x02) && f[testutil::kFirstDataByte] == tag + 1;
  });
}

TEST_P(LinkEventLoop, AnswersFramesInPlaceAndRecordsBothDirections) {
  const std::string pcap_path =
      ::testing::TempDir() + "rackcat_loop_" + std::to_string(getpid()) + ".pcap";
  RawSocketLink link("lo");
  PcapWriter pcap(pcap_path);
  EventLoop loop(link, {.wait = GetParam(), .pcap = &pcap, .stop_on_signals = false});
  loop.set_frame_handler(answer);

  std::vector<uint8_t> reply;
  std::thread master([&] {
    RawSocketLink master_link("lo");
    reply = exchange(master_link, 0x50);
    loop.stop();
  });
  EXPECT_EQ(loop.run(), 0);
  master.join();
  ASSERT_EQ(reply.size(), 60u);
  EXPECT_EQ(reply[6], 0x02);
  EXPECT_EQ(reply[testutil::kFirstDataByte], 0x51);

  std::ifstream f(pcap_path, std::ios::binary);
  const std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(f),
                                   std::istreambuf_iterator<char>()};
  // The frame as received, immediately followed by the reply as sent. (Other tests running
  // in parallel on lo may add records of their own around them.)
  bool found_pair = false;
  size_t pos = 24;
  const uint8_t* prev = nullptr;
  while (pos + 16 <= bytes.size() && !found_pair) {
    const size_t len = bytes[pos + 8] | (bytes[pos + 9] << 8);
    const uint8_t* rec = bytes.data() + pos + 16;
    if (prev != nullptr && len == 60 && ours({prev, 60}) && ours({rec, 60}) && prev[6] == 0x00 &&
        prev[testutil::kFirstDataByte] == 0x50 && rec[6] == 0x02 &&
        rec[testutil::kFirstDataByte] == 0x51) {
      found_pair = true;
    }
    prev = len == 60 ? rec : nullptr;
    pos += 16 + len;
  }
  EXPECT_TRUE(found_pair) << "no received frame followed by its reply in the capture";
  std::remove(pcap_path.c_str());
}

TEST_P(LinkEventLoop, PostedWorkRunsOnTheLoopThread) {
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = GetParam(), .pcap = nullptr, .stop_on_signals = false});
  std::thread::id ran_on;
  std::atomic<int> runs{0};
  std::thread other([&] {
    for (int i = 0; i < 100; ++i) loop.post([&] { runs.fetch_add(1); });
    loop.post([&] {
      ran_on = std::this_thread::get_id();
      loop.stop();
    });
  });
  EXPECT_EQ(loop.run(), 0);
  other.join();
  EXPECT_EQ(runs.load(), 100);
  EXPECT_EQ(ran_on, std::this_thread::get_id());
}

class OneShotTimer : public TimerSource {
 public:
  OneShotTimer(EventLoop& loop, uint64_t at) : loop_(loop), at_(at) {}
  uint64_t next_deadline_ns() const override { return fired_at_ ? kNever : at_; }
  void on_time(uint64_t now) override {
    fired_at_ = now;
    loop_.stop();
  }
  uint64_t fired_at() const { return fired_at_; }

 private:
  EventLoop& loop_;
  uint64_t at_;
  uint64_t fired_at_ = 0;
};

TEST_P(LinkEventLoop, TimerSourceFiresAtItsDeadlineNotBefore) {
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = GetParam(), .pcap = nullptr, .stop_on_signals = false});
  const uint64_t deadline = monotonic_ns() + 3'000'000;
  OneShotTimer timer(loop, deadline);
  loop.set_timer_source(&timer);
  EXPECT_EQ(loop.run(), 0);
  EXPECT_GE(timer.fired_at(), deadline);
}

TEST_P(LinkEventLoop, SigtermStopsTheLoopWithStatusZero) {
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = GetParam(), .pcap = nullptr, .stop_on_signals = true});
  loop.post([] { kill(getpid(), SIGTERM); });
  EXPECT_EQ(loop.run(), 0);
  EXPECT_EQ(loop.stop_signal(), SIGTERM);
}

TEST_P(LinkEventLoop, SigintReceivedByAnotherThreadStillStopsTheLoop) {
  // A thread started before the loop (a device's background writer, say) with SIGINT not
  // blocked: the kernel may run the handler there; the process must not die of it.
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = GetParam(), .pcap = nullptr, .stop_on_signals = true});
  std::atomic<bool> done{false};
  std::thread other([&] {
    sigset_t only_int;
    sigemptyset(&only_int);
    sigaddset(&only_int, SIGINT);
    pthread_sigmask(SIG_UNBLOCK, &only_int, nullptr);
    while (!done.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  // The loop thread blocks SIGINT for this test, so the kernel must deliver it to `other`.
  sigset_t only_int;
  sigemptyset(&only_int);
  sigaddset(&only_int, SIGINT);
  pthread_sigmask(SIG_BLOCK, &only_int, nullptr);
  loop.post([] { kill(getpid(), SIGINT); });
  EXPECT_EQ(loop.run(), 0);
  EXPECT_EQ(loop.stop_signal(), SIGINT);
  done.store(true);
  other.join();
  pthread_sigmask(SIG_UNBLOCK, &only_int, nullptr);
}

TEST_P(LinkEventLoop, StopBeforeRunIsNotLost) {
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = GetParam(), .pcap = nullptr, .stop_on_signals = false});
  loop.stop();
  EXPECT_EQ(loop.run(), 0);
  // Consumed: the loop runs again until the next stop().
  loop.post([&] { loop.stop(); });
  EXPECT_EQ(loop.run(), 0);
}

// After-frame work in slices (set_after_frame_work): the first frame leaves work that never
// ends by itself (capped at 5 s of slices); a second frame sent once the first reply is back is
// answered while that work is still pending (a yield window longer than the test), and every
// frame is followed by a slice.
TEST_P(LinkEventLoop, AfterFrameWorkYieldsToAWaitingFrame) {
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = GetParam(),
                        .pcap = nullptr,
                        .stop_on_signals = false,
                        .yield_window_ns = 60'000'000'000ull});
  constexpr int kCap = 50'000;  // x 100 µs
  std::atomic<int> slices{0};
  std::atomic<int> slices_at_second{-1};
  std::atomic<bool> second_answered{false};
  loop.set_frame_handler([&](std::span<uint8_t> frame) {
    const size_t n = answer(frame);
    if (n != 0 && frame[testutil::kFirstDataByte] == 0x31) {
      slices_at_second.store(slices.load());
      second_answered.store(true);
    }
    return n;
  });
  loop.set_after_frame_work([&] {
    const int k = slices.fetch_add(1) + 1;
    if (second_answered.load()) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(100));
    return k < kCap;
  });
  std::atomic<int> replies{0};
  std::thread master([&] {
    RawSocketLink master_link("lo");
    for (uint8_t tag : {0x20, 0x30}) {
      if (!exchange(master_link, tag).empty()) replies.fetch_add(1);
    }
    loop.post([&] { loop.stop(); });
  });
  EXPECT_EQ(loop.run(), 0);
  master.join();
  EXPECT_EQ(replies.load(), 2);
  // Frame 1's work had begun (at least its first slice) and was not finished when frame 2 came.
  EXPECT_GE(slices_at_second.load(), 1);
  EXPECT_LT(slices_at_second.load(), kCap);
  // Frame 2 was followed by a slice of its own (which found the work done).
  EXPECT_GT(slices.load(), slices_at_second.load());
}

// Outside the yield window (0 here: always outside) the work of the first frame is finished
// before the second frame is taken, however early it arrives: 20 slices of 100 µs, then frame 2.
TEST_P(LinkEventLoop, AfterFrameWorkOutsideTheYieldWindowFinishesFirst) {
  RawSocketLink link("lo");
  EventLoop loop(
      link, {.wait = GetParam(), .pcap = nullptr, .stop_on_signals = false, .yield_window_ns = 0});
  constexpr int kSlices = 20;
  std::atomic<int> slices{0};
  std::atomic<int> slices_at_second{-1};
  loop.set_frame_handler([&](std::span<uint8_t> frame) {
    const size_t n = answer(frame);
    if (n != 0 && frame[testutil::kFirstDataByte] == 0x41) slices_at_second.store(slices.load());
    return n;
  });
  loop.set_after_frame_work([&] {
    if (slices_at_second.load() >= 0) return false;  // frame 2's slice: nothing left
    const int k = slices.fetch_add(1) + 1;
    std::this_thread::sleep_for(std::chrono::microseconds(100));
    return k < kSlices;
  });
  std::atomic<int> replies{0};
  std::thread master([&] {
    RawSocketLink master_link("lo");
    for (uint8_t tag : {0x30, 0x40}) {
      if (!exchange(master_link, tag).empty()) replies.fetch_add(1);
    }
    loop.post([&] { loop.stop(); });
  });
  EXPECT_EQ(loop.run(), 0);
  master.join();
  EXPECT_EQ(replies.load(), 2);
  // (On lo the loop also receives its own first reply, which it does not answer but follows
  // with a slice too: at least kSlices.)
  EXPECT_GE(slices_at_second.load(), kSlices);
}

// A burst (frames the master sent before it could have seen a reply, as SOEM sends a process
// image larger than one frame): all of it is answered before the first frame's after-frame
// work, which then runs once for all. Here the three frames are queued before the loop starts;
// the work is 20 slices of 100 µs, none of which may come before the last reply. In a network
// namespace of its own: another test's frame on lo would start the work of its own.
TEST_P(LinkEventLoop, FramesOfABurstAreAnsweredBeforeTheWorkOfTheFirst) {
  const WaitMode wait = GetParam();
  testutil::expect_ok_in_own_network([wait] {
    RawSocketLink link("lo");
    EventLoop loop(link,
                   {.wait = wait, .pcap = nullptr, .stop_on_signals = false, .yield_window_ns = 0});
    constexpr int kSlices = 20;
    std::atomic<int> slices{0};
    std::array<std::atomic<int>, 3> slices_at{-1, -1, -1};
    loop.set_frame_handler([&](std::span<uint8_t> frame) {
      const size_t n = answer(frame);
      const uint8_t tag = frame[testutil::kFirstDataByte];  // answered: incremented
      if (n != 0 && tag >= 0x51 && tag <= 0x71 && tag % 0x10 == 1) {
        slices_at[(tag - 0x51) / 0x10].store(slices.load());
      }
      return n;
    });
    loop.set_after_frame_work([&] {
      const int k = slices.fetch_add(1) + 1;
      std::this_thread::sleep_for(std::chrono::microseconds(100));
      return k < kSlices;
    });
    RawSocketLink master_link("lo");
    if (!testutil::wait_for_receive_timestamps(
            link, [&master_link](const std::vector<uint8_t>& f) { return master_link.send(f); })) {
      return 9;
    }
    for (uint8_t tag : {0x50, 0x60, 0x70}) {
      auto frame = testutil::ethercat_frame(tag);
      stamp(frame);
      if (!master_link.send(frame)) return 1;
    }
    std::atomic<int> replies{0};
    std::thread master([&] {
      for (uint8_t tag : {0x50, 0x60, 0x70}) {
        const auto got = testutil::receive_matching(master_link, [tag](std::span<const uint8_t> f) {
          return ours(f) && (f[6] & 0x02) && f[testutil::kFirstDataByte] == tag + 1;
        });
        if (!got.empty()) replies.fetch_add(1);
      }
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (slices.load() < kSlices && std::chrono::steady_clock::now() < until) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      loop.post([&] { loop.stop(); });
    });
    const int rc = loop.run();
    master.join();
    if (rc != 0 || replies.load() != 3) return 2;
    for (const auto& at : slices_at) {
      if (at.load() != 0) return 3;  // a reply of the burst came after some of the work
    }
    if (loop.burst_frames() != 2) return 4;
    if (slices.load() < kSlices) return 5;  // the work ran, once, to the end
    return 0;
  });
}

// Under chrt -f the loop must not poll after a frame: a SCHED_FIFO thread that never sleeps
// starves the softirq work that delivers the next frame (ethercrab with 16 slaves lost PDUs
// after 30 ms in about half of its runs). At normal priority the window stays.
TEST(LinkEventLoopSpin, NoWindowOnARealTimeThread) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = WaitMode::Blocking,
                        .pcap = nullptr,
                        .stop_on_signals = false,
                        .spin_after_frame_ns = 100'000});
  EXPECT_EQ(loop.spin_window_ns(), 100'000u);
  sched_param rt{};
  rt.sched_priority = 1;
  ASSERT_EQ(pthread_setschedparam(pthread_self(), SCHED_FIFO, &rt), 0);
  EXPECT_EQ(loop.spin_window_ns(), 0u);
  sched_param normal{};
  ASSERT_EQ(pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal), 0);
  EXPECT_EQ(loop.spin_window_ns(), 100'000u);
}

// Adaptive waiting (blocking mode): a frame opens a window in which the loop polls without
// sleeping. Inside that window (made long here) it still answers a burst of frames, fires its
// timers, runs posted work and stops on request - nothing waits for the window to close.
TEST(LinkEventLoopSpin, BurstTimerPostAndStopInsideTheWindowAfterAFrame) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  RawSocketLink link("lo");
  EventLoop loop(link, {.wait = WaitMode::Blocking,
                        .pcap = nullptr,
                        .stop_on_signals = false,
                        .spin_after_frame_ns = 60'000'000'000ull});
  loop.set_frame_handler(answer);
  const uint64_t deadline = monotonic_ns() + 3'000'000'000ull;  // safety stop, never reached
  struct StopAt final : TimerSource {
    EventLoop& loop;
    uint64_t at;
    uint64_t fired = 0;
    StopAt(EventLoop& l, uint64_t t) : loop(l), at(t) {}
    uint64_t next_deadline_ns() const override { return fired ? kNever : at; }
    void on_time(uint64_t now) override {
      fired = now;
      loop.stop();
    }
  } safety(loop, deadline);
  loop.set_timer_source(&safety);
  std::atomic<int> replies{0};
  std::atomic<bool> posted_ran{false};
  std::thread master([&] {
    RawSocketLink master_link("lo");
    for (uint8_t tag = 0x10; tag < 0x10 + 2 * 5; tag += 2) {  // a burst of 5, like an SDO
      if (!exchange(master_link, tag).empty()) replies.fetch_add(1);
    }
    // Still inside the window: posted work runs and stop() ends the loop.
    loop.post([&] {
      posted_ran.store(true);
      loop.stop();
    });
  });
  EXPECT_EQ(loop.run(), 0);
  master.join();
  EXPECT_EQ(replies.load(), 5);
  EXPECT_TRUE(posted_ran.load());
  EXPECT_EQ(safety.fired, 0u);  // stopped by the post, long before the safety timer
}

INSTANTIATE_TEST_SUITE_P(BothWaitModes, LinkEventLoop,
                         ::testing::Values(WaitMode::Blocking, WaitMode::BusyPoll),
                         [](const auto& info) {
                           return info.param == WaitMode::Blocking ? "Blocking" : "BusyPoll";
                         });

}  // namespace
}  // namespace rackcat::ecat
