// The wire test slave's device: 4 output bytes (RxPDO 0x1600) copied to 4 input bytes
// (TxPDO 0x1A00), so a master sees its outputs come back one cycle later. No mailbox
// protocol. Counts SYNC0 pulses and watchdog expiries for the test's final report.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <ctime>
#include <vector>

#include "ecat/application.hpp"
#include "tests/ecat_wire_slave/test_sii_image.hpp"

namespace rackcat::tests {

class LoopbackApplication final : public ecat::Application {
 public:
  explicit LoopbackApplication(const TestSiiIdentity& identity) : sii_(build_test_sii(identity)) {
    sync0_times_.reserve(kMaxSyncTimes);  // recorded on the cyclic path: no allocation there
  }

  std::span<const uint8_t> eeprom() const override { return sii_; }
  uint16_t on_state_request(EsmState, EsmState) override { return 0; }
  void on_state_changed(EsmState, EsmState to) override { state_ = to; }
  ecat::ProcessDataSizes process_data_sizes() const override {
    return {kTestProcessDataBytes, kTestProcessDataBytes};
  }

  bool update_inputs(std::span<uint8_t> inputs) override {
    const size_t n = std::min(inputs.size(), last_outputs_.size());
    std::copy_n(last_outputs_.begin(), n, inputs.begin());
    return true;
  }
  void on_outputs(std::span<const uint8_t> outputs) override {
    const size_t n = std::min(outputs.size(), last_outputs_.size());
    std::copy_n(outputs.begin(), n, last_outputs_.begin());
    ++outputs_received_;
  }
  void on_sync(int which, uint64_t) override {
    if (which != 0) return;
    ++sync0_events_;
    if (sync0_times_.size() < kMaxSyncTimes) {
      timespec ts{};
      clock_gettime(CLOCK_MONOTONIC, &ts);
      sync0_times_.push_back(static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull +
                             static_cast<uint64_t>(ts.tv_nsec));
    }
  }
  void on_watchdog_expired() override {
    last_outputs_.fill(0);  // safe state
    ++watchdog_expiries_;
  }

  uint64_t sync0_events() const { return sync0_events_; }
  // CLOCK_MONOTONIC time at which the application saw each SYNC0 (the first kMaxSyncTimes).
  const std::vector<uint64_t>& sync0_times() const { return sync0_times_; }
  uint64_t outputs_received() const { return outputs_received_; }
  uint64_t watchdog_expiries() const { return watchdog_expiries_; }
  EsmState state() const { return state_; }

 private:
  static constexpr size_t kMaxSyncTimes = 1 << 17;
  std::vector<uint8_t> sii_;
  std::vector<uint64_t> sync0_times_;
  std::array<uint8_t, kTestProcessDataBytes> last_outputs_{};
  uint64_t sync0_events_ = 0;
  uint64_t outputs_received_ = 0;
  uint64_t watchdog_expiries_ = 0;
  EsmState state_ = EsmState::Init;
};

}  // namespace rackcat::tests
