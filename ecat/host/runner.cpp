#include "ecat/host/runner.hpp"

namespace rackcat::ecat {
namespace {

// The segment's deadlines (SYNC pulses, watchdogs) as the loop's timer source. Both use
// CLOCK_MONOTONIC nanoseconds. The bound may be early (a retriggered watchdog): on_time()
// then fires nothing and the segment computes the exact next time.
class SegmentTimers final : public TimerSource {
 public:
  explicit SegmentTimers(Segment& segment) : segment_(segment) {}
  uint64_t next_deadline_ns() const override { return segment_.next_event_bound_ns(); }
  void on_time(uint64_t) override { segment_.service(); }

 private:
  Segment& segment_;
};

// How long one slice of the slaves' firmware runs before the loop looks for a waiting frame
// again (a non-blocking receive, ~0.4 µs): a master sending back to back waits about half
// of it on average; the firmware of one tiny-rack slave takes about 0.7 µs.
constexpr uint64_t kFirmwareSliceNs = 2'000;

}  // namespace

Runner::Runner(RunnerOptions options) : options_(std::move(options)) {}

Runner::~Runner() = default;

int Runner::open(const char* program, FILE* err) {
  EventLoop::install_stop_signal_handler();
  try {
    link_ = std::make_unique<RawSocketLink>(options_.interface_name);
  } catch (const LinkError& e) {
    std::fprintf(err, "%s: %s\n", program, e.what());
    return e.kind() == LinkErrorKind::System ? kExitFailure : kExitUsage;
  }
  if (!options_.pcap_path.empty()) {
    try {
      pcap_ = std::make_unique<PcapWriter>(options_.pcap_path);
    } catch (const std::exception& e) {
      std::fprintf(err, "%s: %s\n", program, e.what());
      return kExitUsage;
    }
  }
  if (options_.drop_privileges) {
    try {
      privileges_ = drop_privileges({.user = options_.user, .use_sudo_user = true});
    } catch (const PrivilegeError& e) {
      std::fprintf(err, "%s: %s\n", program, e.what());
      return kExitUsage;
    }
  }
  // The capture's writer thread starts only now: no thread may predate the drop.
  if (pcap_) pcap_->start();
  try {
    loop_ = std::make_unique<EventLoop>(
        *link_, EventLoop::Options{.wait = options_.wait,
                                   .pcap = pcap_.get(),
                                   .stop_on_signals = true,
                                   .yield_window_ns = options_.firmware_yield_window_ns});
  } catch (const std::exception& e) {
    std::fprintf(err, "%s: %s\n", program, e.what());
    return kExitFailure;
  }
  return kExitOk;
}

int Runner::run(Segment& segment) {
  if (!loop_) return kExitFailure;
  SegmentTimers timers(segment);
  loop_->set_frame_handler([&segment](std::span<uint8_t> frame) { return segment.process(frame); });
  segment.set_deferred_firmware(true);
  if (options_.firmware_yield_window_ns == 0) {
    // No frame may overtake the firmware (the default): the whole round runs after the reply,
    // without the slices' clock read per slave - they exist only to look for a waiting frame.
    loop_->set_after_frame_work([&segment] {
      segment.after_frame();
      return false;
    });
  } else {
    // The firmware runs in slices of about kFirmwareSliceNs between frames (event_loop.hpp).
    loop_->set_after_frame_work(
        [&segment] { return segment.run_firmware_slice(kFirmwareSliceNs); });
  }
  loop_->set_timer_source(&timers);
  const int rc = loop_->run();
  loop_->set_timer_source(nullptr);
  loop_->set_after_frame_work(nullptr);
  segment.set_deferred_firmware(false);
  segment.after_frame();
  if (pcap_) pcap_->flush();
  return rc;
}

}  // namespace rackcat::ecat
