// Process-data exchange as the firmware runs it (ETG.1000.6 §5.3 SAFEOP/OP; ETG.1000.4 §6.7.2
// buffered SyncManagers):
//   - every cycle: when the master has written SM2 (AL event bit 10) the firmware reads it
//     (the newest complete buffer) and, in OP, hands it to the device; then it asks the device
//     for inputs and writes SM3, which the master reads in its next frame. When the master has
//     read SM3 (AL event bit 11, e.g. a device without outputs) the inputs are refreshed too.
//   - DC synchronous (SYNC0 running when SAFEOP was entered): the inputs are also produced at
//     each SYNC0 event, the point in time every slave of the segment shares.
//   - the process-data watchdog (0x0440 bit 0 cleared, AL event bit 6): in OP the outputs go
//     to the safe state and the ESM falls to SAFEOP with 0x001B (ETG.1000.6 Table 11).
// Buffers are sized on PREOP -> SAFEOP; the cyclic path does not allocate.
#include <algorithm>
#include <cstddef>
#include <span>

#include "ecat/al_status_code.hpp"
#include "ecat/registers.hpp"
#include "ecat/slave/firmware.hpp"

namespace rackcat::ecat {

void Firmware::pd_start() {
  const size_t outputs = sm_[2].enabled ? sm_[2].length : 0;
  const size_t inputs = sm_[3].enabled ? sm_[3].length : 0;
  images_.assign(outputs + inputs, 0);
  outputs_ = std::span<uint8_t>(images_).first(outputs);
  inputs_ = std::span<uint8_t>(images_).subspan(outputs, inputs);
  set_sm_deactivated(2, false);
  set_sm_deactivated(3, false);
  // The master's first read in SAFEOP finds valid inputs.
  inputs_handed_over_ = false;
  pd_produce_inputs();
}

void Firmware::pd_outputs_written() {
  const Sm& s = sm_taken_[2];
  if (!s.enabled || outputs_.size() != s.length) return;
  // One block read of the whole buffer: its first byte clears the event and opens the newest
  // buffer the master completed, its last byte releases it (ETG.1000.4 §6.7.2).
  pdi_.read_buffer(2, s.start, outputs_);
  if (state_ == EsmState::Op) app_.on_outputs(outputs_);
}

void Firmware::pd_produce_inputs() {
  const Sm& s = sm_taken_[3];
  if (!s.enabled || inputs_.size() != s.length || inputs_.empty()) return;
  // An image the device reports unchanged is the one SM3 already serves (Application::
  // update_inputs); the first one after pd_start always goes out.
  if (!app_.update_inputs(inputs_) && inputs_handed_over_) return;
  // One block write of the whole buffer: its last byte hands it to the master (the newest of
  // the three buffers).
  pdi_.write_buffer(3, s.start, inputs_);
  inputs_handed_over_ = true;
}

void Firmware::pd_sync(int which) {
  // Reading the SYNC status (0x098E/0x098F) clears the event. The pulse's system time: SYNC0
  // is one cycle before the next pulse in 0x0990 (or that time itself for a single shot),
  // SYNC1's is in 0x0998.
  pdi_.read8(static_cast<uint16_t>(reg::kDcSync0Status + which));
  uint64_t t = 0;
  if (which == 0) {
    const uint64_t next = pdi_.read64(reg::kDcStartTime);
    const uint32_t cycle = pdi_.read32(reg::kDcSync0Cycle);
    t = next - cycle;
  } else {
    t = pdi_.read64(reg::kDcNextSync1);
  }
  app_.on_sync(which, t);
  if (which == 0 && dc_synchronised_ && (state_ == EsmState::SafeOp || state_ == EsmState::Op)) {
    pd_produce_inputs();
  }
}

void Firmware::pd_watchdog() {
  // Reading the watchdog status clears the event.
  const uint8_t status = pdi_.read8(reg::kWatchdogStatusProcessData);
  if ((status & 0x01) == 0 && observer_ != nullptr) {
    observer_->on_watchdog_expired(state_, pdi_.read8(reg::kWatchdogCounterProcessData));
  }
  if ((status & 0x01) == 0 && state_ == EsmState::Op) {
    app_.on_watchdog_expired();
    esm_error(EsmState::SafeOp, al_code::kSmWatchdog, EsmState::SafeOp);
  }
}

}  // namespace rackcat::ecat
