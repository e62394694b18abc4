// The absolute rotary encoder card (CAE-10) after the encoder guide
// (the PROFINET absolute encoder user guide, "the guide"): one input
// channel whose source is the shaft angle in revolutions (constant, ramp, replay, plant ...);
// the telegram 0x7nnD (STW2_ENC, G1_STW1) / 0x6nnD (ZSW2_ENC, G1_ZSW1, G1_XIST1, G1_XIST2,
// NIST_B); settings 0x8nn0, preset 0x8nn1, information 0x9nn0 (docs/ENCODER.md).
//
// Per cycle: read_outputs() (OP) takes the master's control words: the master's sign-of-life
// is monitored (guide "User data reliability": failure counter +10 per wrong count, -1 per
// good one, sensor error 0x0F04 at 10 x the permitted failures), a rising edge of G1_STW1 bit 12
// executes the preset (bit 11: set or shift), bit 15 acknowledges a sensor error once its cause
// is gone. write_inputs() samples the shaft, computes position and velocity and writes 0x6nnD.
// Injected faults (hardware error, position jump, frozen position) and the sign-of-life failure
// set G1_ZSW1 bit 15 with their code in G1_XIST2 and raise a 0x10F3 message with its Emergency.
#pragma once

#include <array>
#include <cstdint>

#include "mdp/device.hpp"
#include "mdp/encoder_settings.hpp"
#include "modules/cards/card_driver.hpp"

namespace rackcat::modules {

enum class EncoderFault : uint8_t { Hardware = 0, Jump = 1, Frozen = 2 };

// G1_XIST2 error codes (guide "Error codes in G1_XIST2": 0x0F04 synchronization fault; "a
// device specific error code is transmitted in G1_XIST2" for the others: rackcat's choice).
namespace encoder_error {
inline constexpr uint16_t kHardware = 0x0001;
inline constexpr uint16_t kJump = 0x1002;
inline constexpr uint16_t kFrozen = 0x1003;
inline constexpr uint16_t kLifeSign = 0x0F04;
}  // namespace encoder_error

class EncoderDriver final : public CardDriver {
 public:
  EncoderDriver(const mdp::Module& m, coe::ObjectDictionary& od);

  // Diagnosis messages go to this device (the Rack attaches it once the drivers exist); also
  // wraps 0x8nn0's write check so a refused combination leaves a message, and makes 0x8nn1:02
  // execute a preset at once.
  void attach(mdp::Device& device);

  void read_outputs() override;
  void write_inputs(double t, double dt) override;
  void clear_inputs() override;
  const char* input_unit() const override { return "rev"; }
  bool set_parameter(std::string_view key, double value) override;

  // Fault injection (control API). `jump_steps`: the physical steps a jump adds (Jump only).
  void set_fault(EncoderFault fault, bool active, int64_t jump_steps = 0);
  bool fault(EncoderFault f) const { return (faults_ & bit(f)) != 0; }

  // The velocity is the count's change over the newest stored sample at least this old (a gate
  // time; over all stored ones while there is none): a held source (a plant steps every 1 ms)
  // is then off by at most one plant step per gate, 5 %, rather than by 100 % between two
  // frames that straddle a step.
  static constexpr double kVelocityGate = 0.020;

  // State for `rackcat ctl list` and tests.
  uint32_t position() const { return position_; }
  double velocity() const { return velocity_; }
  bool sensor_error() const { return sensor_error_; }
  uint16_t error_code() const { return error_code_; }

 private:
  static uint8_t bit(EncoderFault f) { return static_cast<uint8_t>(1u << static_cast<int>(f)); }
  mdp::encoder::Settings settings() const;
  void preset(bool shift);
  void monitor_life_sign(uint8_t master_ls);
  void update_error();
  void report(uint16_t text, uint16_t detail);

  mdp::Device* device_ = nullptr;
  coe::Object* in_;
  coe::Object* out_;
  coe::Object* settings_;
  coe::Object* preset_;
  coe::Object* info_;
  mdp::encoder::Hardware hw_;

  // Shaft.
  int64_t steps_ = 0;  // physical steps of the last sample, after faults
  // The samples of the last kSamples cycles (newest at head_), for the velocity.
  struct Sample {
    double t;
    int64_t count;
  };
  static constexpr size_t kSamples = 64;
  std::array<Sample, kSamples> samples_{};
  size_t head_ = 0;
  size_t stored_ = 0;
  double velocity_ = 0.0;   // filtered, in the configured unit
  uint32_t position_ = 0;   // G1_XIST2 position (with the preset)
  uint64_t unshifted_ = 0;  // position before the offset
  // Faults.
  uint8_t faults_ = 0;
  int64_t jump_steps_ = 0;
  int64_t frozen_at_ = 0;
  // Control words.
  uint16_t stw2_ = 0;
  uint16_t stw_ = 0;
  bool preset_ack_ = false;
  uint8_t pending_preset_ = 0;  // 1 set, 2 shift: executed on the next sample
  uint8_t slave_ls_ = 0;
  // Master sign-of-life (guide "Controller's Sign-Of-Life").
  bool ls_started_ = false;
  uint8_t ls_expected_ = 0;
  uint16_t ls_counter_ = 0;
  bool ls_failed_ = false;
  // Sensor error: latched until acknowledged with its causes gone.
  bool sensor_error_ = false;
  uint16_t error_code_ = 0;
};

}  // namespace rackcat::modules
