// A small device for the ESC tests: a fixed SII image hand-built per ETG.2010 (identity,
// mailbox SMs at 0x1000/0x1080, 4 output and 6 input bytes, strings, general, FMMU and SM
// categories), a mailbox that echoes every request's data, and records of what the ESC called.
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "ecat/application.hpp"
#include "ecat/slave/mailbox_protocol.hpp"

namespace rackcat::ecat::test {

inline constexpr uint32_t kVendorId = 0x00000ACE;
inline constexpr uint32_t kProductCode = 0x00010001;
inline constexpr uint32_t kRevision = 0x00000003;
inline constexpr uint32_t kSerial = 0x12345678;
inline constexpr uint16_t kMbxOutStart = 0x1000;  // SM0, master -> slave
inline constexpr uint16_t kMbxInStart = 0x1080;   // SM1, slave -> master
inline constexpr uint16_t kMbxSize = 128;
inline constexpr uint16_t kOutputsStart = 0x1100;  // SM2
inline constexpr uint16_t kInputsStart = 0x1180;   // SM3
inline constexpr uint16_t kOutputBytes = 4;
inline constexpr uint16_t kInputBytes = 6;

// The SII image: words 0-0x3F header, categories from word 0x40.
std::vector<uint8_t> make_test_sii();

// The device is its own mailbox protocol (registered for CoE): it echoes every request.
class TestApplication : public Application, public MailboxProtocol {
 public:
  TestApplication();

  std::span<const uint8_t> eeprom() const override { return sii; }
  void on_eeprom_write(uint16_t word_address, std::span<const uint8_t> data) override;
  uint16_t on_state_request(EsmState from, EsmState to) override;
  void on_state_changed(EsmState from, EsmState to) override;
  ProcessDataSizes process_data_sizes() const override { return sizes; }
  void add_mailbox_protocols(MailboxServer& server) override;
  mailbox::Answer on_request(const MailboxRequest& request, std::span<uint8_t> reply) override;
  size_t poll(std::span<uint8_t> reply) override;
  bool mailbox_pending() const override { return !pending_emergency.empty(); }
  bool update_inputs(std::span<uint8_t> inputs) override;
  void on_outputs(std::span<const uint8_t> outputs) override;
  void on_sync(int which, uint64_t system_time_ns) override;
  void on_watchdog_expired() override { ++watchdog_expiries; }

  std::vector<uint8_t> sii;
  ProcessDataSizes sizes{kOutputBytes, kInputBytes};
  uint16_t veto_code = 0;             // returned by on_state_request when non-zero
  EsmState veto_to = EsmState::Init;  // ... for requests to this state
  std::vector<uint8_t> inputs_value = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66};
  // What update_inputs answers; false leaves the image untouched (the device's "unchanged").
  bool inputs_changed = true;
  std::vector<uint8_t> last_outputs;
  int outputs_count = 0;
  int inputs_count = 0;
  // base::RoundTime::now() when update_inputs ran (the firmware round's time).
  std::chrono::steady_clock::time_point inputs_time{};
  int mailbox_requests = 0;
  std::vector<uint8_t> last_request;       // its mailbox data
  std::vector<uint8_t> pending_emergency;  // mailbox data sent by poll() once
  int polls = 0;                           // poll() calls: the firmware ran with SM1 free
  std::vector<std::pair<EsmState, EsmState>> transitions;
  std::vector<std::pair<int, uint64_t>> syncs;
  int watchdog_expiries = 0;
  std::vector<std::pair<uint16_t, uint16_t>> eeprom_writes;  // word address, value
};

}  // namespace rackcat::ecat::test
