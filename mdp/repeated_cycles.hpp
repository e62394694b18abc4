// Cycles that repeat the last one (issue 16): a master that sends the same output data every
// cycle, to a device whose inputs depend on nothing but that data, gets the same input data
// back every cycle. Running every card, the exception tree and the process image for it costs
// a line of devices per slave what a round through all of that touches; comparing the output
// data costs a few bytes.
//
// The rule, in the order the device sees a cycle (Device::write_outputs, then read_inputs):
//   - a full cycle records its output data and the input data it produced;
//   - the device has settled when a full cycle had the previous full cycle's output data,
//     produced its input data again, nothing outside the cycle touched the device during
//     either of them or between them (disturb()), and every cycle listener says a repeat would
//     change nothing (CycleListener::repeats_cycle): after a change or a disturbance, two full
//     cycles;
//   - a settled device skips a cycle whose output data is the recorded one, as long as nothing
//     disturbed it and every listener still agrees (a timer of its own may be due): the SM3
//     image is the one the firmware handed over already (ecat::Application::update_inputs
//     answers false, so the master reads the same buffer, ETG.1000.4 §6.7.2);
//   - a refresh of the inputs alone (read_inputs with no write_outputs since the last one: a
//     master that writes SM2 and reads SM3 in separate frames, LWR then LRD) is skipped on the
//     same terms; one that runs leaves the recording standing if it packed the recorded inputs
//     (the next full cycle with the recorded outputs settles again), and drops it otherwise.
// Whatever reads or changes the device from outside the cycle (a mailbox request, an ESM
// transition, SYNC, the watchdog, the control API, a RIM link) calls disturb() first, so the
// next cycle runs in full. No allocation after arm().
#pragma once

#include <array>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/short_copy.hpp"

namespace rackcat::mdp {

// 40 bytes: its owner keeps it on the cache line every cycle reads anyway (mdp::Device).
class RepeatedCycles {
 public:
  // The process data starts (entering SAFEOP, not the cyclic path): its sizes, and whether a
  // cycle can repeat at all (`possible`: no mapped object runs a process-data hook, no mapped
  // entry holds a time). Images that do not fit in place are recorded in `spill`, which the
  // owner keeps until the next arm().
  void arm(size_t output_bytes, size_t input_bytes, bool possible, std::vector<uint8_t>& spill) {
    const size_t total = output_bytes + input_bytes;
    if (total > kInline) {
      spill.assign(total, 0);
      images_ = spill.data();
    } else {
      spill.clear();
      images_ = inline_.data();
    }
    // SyncManager lengths are 16-bit (ETG.1000.4 §6.7.1): larger sizes never repeat.
    possible_ =
        possible && output_bytes != 0 && output_bytes <= UINT16_MAX && input_bytes <= UINT16_MAX;
    output_bytes_ = possible_ ? static_cast<uint16_t>(output_bytes) : 0;
    input_bytes_ = possible_ ? static_cast<uint16_t>(input_bytes) : 0;
    recorded_ = false;
    settled_ = false;
    ++disturbances_;
  }
  // Something outside the cycle is about to read or change the device.
  void disturb() { ++disturbances_; }

  // write_outputs: true when this cycle repeats the last one and may be skipped (then the
  // next inputs_wanted() answers false). `repeats` asks the listeners.
  template <class Repeats>
  bool skip_outputs(std::span<const uint8_t> sm2, Repeats&& repeats) {
    if (settled_ && settled_at_ == disturbances_ && same(sm2, images_, output_bytes_) &&
        repeats()) {
      skipping_ = true;
      return true;
    }
    settled_ = false;
    skipping_ = false;
    full_ = true;
    cycle_start_ = disturbances_;
    outputs_repeated_ = false;
    if (possible_ && sm2.size() == output_bytes_) {
      // A recording made before a disturbance proves nothing about the device after it.
      outputs_repeated_ =
          recorded_ && settled_at_ == disturbances_ && same(sm2, images_, output_bytes_);
      if (!outputs_repeated_) base::copy_bytes(images_, sm2.data(), sm2.size());
    }
    return false;
  }
  // read_inputs: false when this cycle's write_outputs skipped it, or when it refreshes the
  // inputs alone on a settled device that nothing disturbed and whose listeners agree (the
  // SM3 image stands either way). `repeats` asks the listeners, only for such a refresh.
  template <class Repeats>
  bool inputs_wanted(Repeats&& repeats) {
    if (skipping_) {
      skipping_ = false;
      return false;
    }
    return full_ || !settled_ || settled_at_ != disturbances_ || !repeats();
  }
  // read_inputs, after it packed `sm3`: for a full cycle records it and decides whether the
  // device has settled (`repeats` asks the listeners, only when the cycle repeated the last
  // one); for a refresh of the inputs alone keeps the recording only if `sm3` is its inputs.
  template <class Repeats>
  void inputs_made(std::span<const uint8_t> sm3, Repeats&& repeats) {
    if (!full_) {
      recorded_ = recorded_ && settled_at_ == disturbances_ &&
                  same(sm3, images_ + output_bytes_, input_bytes_);
      settled_ = false;
      return;
    }
    const bool recording = possible_ && sm3.size() == input_bytes_;
    bool inputs_repeated = false;
    if (recording) {
      uint8_t* const inputs = images_ + output_bytes_;
      inputs_repeated = recorded_ && same(sm3, inputs, input_bytes_);
      if (!inputs_repeated) base::copy_bytes(inputs, sm3.data(), sm3.size());
    }
    settled_ = recording && outputs_repeated_ && inputs_repeated && cycle_start_ == disturbances_ &&
               repeats();
    settled_at_ = disturbances_;
    recorded_ = recording && cycle_start_ == disturbances_;
    full_ = false;
  }

 private:
  static constexpr size_t kInline = 8;  // output + input bytes recorded in place (a tiny device)
  static bool same(std::span<const uint8_t> a, const uint8_t* b, size_t n) {
    return a.size() == n && base::same_bytes(a.data(), b, n);
  }

  bool settled_ = false;
  bool skipping_ = false;
  bool full_ = false;              // this cycle's write_outputs ran in full
  bool outputs_repeated_ = false;  // ... with the recorded output data
  bool recorded_ = false;          // the images hold the last full cycle's data (undisturbed)
  bool possible_ = false;
  uint16_t output_bytes_ = 0;
  // Counted modulo 2^32: a wrong "nothing happened" would need exactly 2^32 disturbances
  // between two cycles.
  uint32_t disturbances_ = 0;
  uint32_t settled_at_ = 0;  // disturbances_ at the end of the last full cycle
  uint32_t cycle_start_ = 0;
  uint16_t input_bytes_ = 0;
  std::array<uint8_t, kInline> inline_{};
  uint8_t* images_ = inline_.data();  // the recorded outputs, then the recorded inputs
};
static_assert(sizeof(RepeatedCycles) == 40);

}  // namespace rackcat::mdp
