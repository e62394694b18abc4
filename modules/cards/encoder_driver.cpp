// The absolute rotary encoder card: see encoder_driver.hpp and docs/ENCODER.md.
#include "modules/cards/encoder_driver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mdp/diagnosis_catalogue.hpp"
#include "modules/cards/drivers.hpp"
#include "modules/cards/encoder_math.hpp"

namespace rackcat::modules {
namespace {

namespace enc = mdp::encoder;
namespace text = mdp::diag::text;

// Telegram bits (guide "Encoder control word (STW2_ENC)", "(ZSW2_ENC)", "(G1_STW)", "(G1_ZSW)").
constexpr uint16_t kStw2ControlByPlc = 1u << 10;
constexpr uint16_t kZsw2ControlRequested = 1u << 9;
constexpr uint16_t kStwShiftMode = 1u << 11;  // home position mode: 0 set, 1 shift
constexpr uint16_t kStwPreset = 1u << 12;     // rising edge: set preset / request shift
constexpr uint16_t kStwAbsolute = 1u << 13;   // request absolute value cyclically
constexpr uint16_t kStwParking = 1u << 14;    // activate parking sensor
constexpr uint16_t kStwAcknowledge = 1u << 15;
constexpr uint16_t kZswPresetDone = 1u << 12;
constexpr uint16_t kZswSensorError = 1u << 15;

// 0x6nnD / 0x7nnD subindices (mdp/card_catalogue.cpp kEncoderInputs / kEncoderOutputs).
constexpr uint8_t kZsw2 = 1, kZsw = 2, kXist1 = 3, kXist2 = 4, kNistB = 5;
constexpr uint8_t kStw2 = 1, kStw = 2;

// "Valid values for the master's sign of life are 1 to 15, 0 indicates an error".
uint8_t next_life_sign(uint8_t v) {
  return v >= 15 ? 1 : static_cast<uint8_t>(v + 1);
}

struct FaultInfo {
  EncoderFault fault;
  uint16_t text;
  uint16_t code;
};
constexpr FaultInfo kFaults[] = {
    {EncoderFault::Hardware, text::kEncoderHardware, encoder_error::kHardware},
    {EncoderFault::Jump, text::kEncoderJump, encoder_error::kJump},
    {EncoderFault::Frozen, text::kEncoderFrozen, encoder_error::kFrozen},
};

}  // namespace

EncoderDriver::EncoderDriver(const mdp::Module& m, coe::ObjectDictionary& od)
    : CardDriver(m, od, 1, 0),
      in_(&require_object(od, m.index(0x6000, static_cast<uint8_t>(mdp::IoKind::Encoder)), m)),
      out_(&require_object(od, m.index(0x7000, static_cast<uint8_t>(mdp::IoKind::Encoder)), m)),
      settings_(&require_object(od, m.index(0x8000, 0), m)),
      preset_(&require_object(od, m.index(0x8000, 1), m)),
      info_(&require_object(od, m.index(0x9000, 0), m)) {
  hw_.steps_per_turn = static_cast<uint32_t>(info_->get_u(enc::kStepsPerTurn));
  hw_.turns = static_cast<uint32_t>(info_->get_u(enc::kTurns));
}

void EncoderDriver::attach(mdp::Device& device) {
  device_ = &device;
  auto inner = settings_->hooks().validate_write;
  settings_->edit_hooks().validate_write = [this, inner](const coe::Object& obj, int subindex,
                                                         std::span<const uint8_t> data,
                                                         EsmState state) {
    const coe::AbortCode rc = inner ? inner(obj, subindex, data, state) : coe::AbortCode::None;
    if (rc != coe::AbortCode::None) {
      report(text::kEncoderParameter, static_cast<uint16_t>(subindex > 0 ? subindex : 0));
    }
    return rc;
  };
  // Guide 3.11.7: "Class 4 functionality must be enabled!" for a preset.
  preset_->edit_hooks().validate_write = [this](const coe::Object&, int subindex,
                                                std::span<const uint8_t> data, EsmState) {
    if (subindex != enc::kPresetCommand || data.empty() || data[0] == 0) {
      return coe::AbortCode::None;
    }
    return settings().class4 ? coe::AbortCode::None : coe::AbortCode::ParameterIncompatible;
  };
  preset_->edit_hooks().after_write = [this](coe::Object& o, int subindex) {
    if (subindex != enc::kPresetCommand && subindex != -1) return;
    const auto cmd = static_cast<uint8_t>(o.get_u(enc::kPresetCommand));
    if (cmd == 0) return;
    // Executes at once on the position of the last sample (no cycles run in PREOP).
    preset(cmd == enc::kPresetShift);
    o.set_u(enc::kPresetCommand, 0);
  };
}

enc::Settings EncoderDriver::settings() const {
  return enc::read_settings(*settings_);
}

void EncoderDriver::report(uint16_t text_id, uint16_t detail) {
  if (!device_) return;
  mdp::Device::DiagnosisReport r;
  r.text_id = text_id;
  r.rim = module_.rim;
  r.module = module_.number;
  r.channel = 0;
  r.detail = detail;
  device_->report_diagnosis(r);
}

void EncoderDriver::preset(bool shift) {
  const enc::Settings s = settings();
  if (!s.class4) return;
  const uint64_t range = enc::position_range(hw_, s);
  const auto offset = static_cast<int32_t>(static_cast<uint32_t>(preset_->get_u(enc::kOffset)));
  const int64_t next = shift ? encoder::shift_offset(range, offset, s.preset)
                             : encoder::preset_offset(range, unshifted_, s.preset);
  preset_->set_u(enc::kOffset, static_cast<uint32_t>(next));
  position_ = static_cast<uint32_t>(encoder::shifted(hw_, s, unshifted_, next));
  preset_ack_ = true;
}

void EncoderDriver::monitor_life_sign(uint8_t ls) {
  // Guide "Monitoring (C-LS)" and Figures 1-3: the reference counts on every controller cycle;
  // a wrong count adds 10 to the failure counter, a right one takes 1 off; at 10 x the
  // permitted failures (0x8nn0:07) the encoder reports the failure (error code 0x0F04). The
  // master starts its sign-of-life with any value 1..15; 0 before that means "not started".
  if (!ls_started_) {
    if (ls == 0) return;
    ls_started_ = true;
    ls_expected_ = next_life_sign(ls);
    return;
  }
  const auto limit = static_cast<uint16_t>(10u * settings().max_life_failures);
  if (ls == ls_expected_) {
    if (ls_counter_ > 0) --ls_counter_;
  } else {
    ls_counter_ = static_cast<uint16_t>(std::min<unsigned>(ls_counter_ + 10u, limit));
  }
  ls_expected_ = next_life_sign(ls_expected_);
  if (!ls_failed_ && ls_counter_ >= limit) {
    ls_failed_ = true;
    report(text::kEncoderLifeSign, encoder_error::kLifeSign);
  }
}

void EncoderDriver::read_outputs() {
  const auto stw2 = static_cast<uint16_t>(out_->get_u(kStw2));
  const auto stw = static_cast<uint16_t>(out_->get_u(kStw));
  monitor_life_sign(static_cast<uint8_t>(stw2 >> 12));
  // STW2_ENC bit 10 = 0: "EO IO Data is not valid. Except Sign-Of-Life".
  const uint16_t valid = (stw2 & kStw2ControlByPlc) ? stw : 0;
  const auto rising = static_cast<uint16_t>(valid & ~stw_);
  if (rising & kStwPreset) pending_preset_ = (valid & kStwShiftMode) ? 2 : 1;
  if (!(valid & kStwPreset)) preset_ack_ = false;
  if (rising & kStwAcknowledge) {
    if (ls_failed_) {
      // "After fault acknowledgement, the DO application then attempts to automatically
      // resynchronize itself to the Sign-Of-Life of the controller application."
      ls_failed_ = false;
      ls_started_ = false;
      ls_counter_ = 0;
      report(mdp::diag::removed_text(text::kEncoderLifeSign), encoder_error::kLifeSign);
    }
    if (faults_ == 0) {
      sensor_error_ = false;
      error_code_ = 0;
    }
  }
  stw2_ = stw2;
  stw_ = valid;
  update_error();
}

void EncoderDriver::update_error() {
  uint16_t code = 0;
  for (const FaultInfo& f : kFaults) {
    if (!code && (faults_ & bit(f.fault))) code = f.code;
  }
  if (!code && ls_failed_) code = encoder_error::kLifeSign;
  if (code) {
    sensor_error_ = true;
    error_code_ = code;
  }
}

void EncoderDriver::write_inputs(double t, double /*dt*/) {
  InputChannel& ch = inputs_[0];
  ch.value = sample(0, t);
  int64_t raw = encoder::steps_of(hw_, ch.value);
  if (faults_ & bit(EncoderFault::Jump)) raw += jump_steps_;
  if (faults_ & bit(EncoderFault::Frozen)) raw = frozen_at_;
  steps_ = raw;

  const enc::Settings s = settings();
  const int64_t d = encoder::directed(s, raw);
  unshifted_ = encoder::unshifted(hw_, s, d);
  if (pending_preset_) {
    preset(pending_preset_ == 2);
    pending_preset_ = 0;
  }
  const auto offset = static_cast<int32_t>(static_cast<uint32_t>(preset_->get_u(enc::kOffset)));
  position_ = static_cast<uint32_t>(encoder::shifted(hw_, s, unshifted_, offset));
  const uint32_t xist1 =
      s.class4 && s.preset_not_xist1 ? static_cast<uint32_t>(unshifted_) : position_;

  // Velocity from the change of the count (3.11.11: "With each cycle will calculate the
  // velocity from the position value") over the gate time, filtered every cycle (3.11.12).
  const Sample newest = samples_[head_];
  if (stored_ == 0 || t > newest.t) {
    head_ = (head_ + 1) % kSamples;
    samples_[head_] = {t, d};
    stored_ = std::min(stored_ + 1, kSamples);
    if (stored_ > 1) {
      Sample from = samples_[(head_ + kSamples - stored_ + 1) % kSamples];  // the oldest
      for (size_t age = 1; age < stored_; ++age) {
        const Sample& x = samples_[(head_ + kSamples - age) % kSamples];
        if (t - x.t >= kVelocityGate) {
          from = x;
          break;
        }
      }
      const double steps_per_s = static_cast<double>(d - from.count) / (t - from.t);
      velocity_ = encoder::filter_velocity(s.velocity_filter, velocity_,
                                           encoder::velocity_in_unit(hw_, s, steps_per_s));
    }
  }

  slave_ls_ = next_life_sign(slave_ls_);
  const bool parking = (stw_ & kStwParking) != 0;
  const bool show_error = sensor_error_ && !parking;  // parking: "transmits no error messages"
  const auto zsw2 = static_cast<uint16_t>((slave_ls_ << 12) | kZsw2ControlRequested);
  const auto zsw = static_cast<uint16_t>((preset_ack_ ? kZswPresetDone : 0) |
                                         (stw_ & (kStwAbsolute | kStwParking)) |
                                         (show_error ? kZswSensorError : 0));
  const double v = std::round(velocity_);
  const double lo = std::numeric_limits<int32_t>::min();
  const double hi = std::numeric_limits<int32_t>::max();
  const auto nist = static_cast<int32_t>(v < lo ? lo : v > hi ? hi : v);
  in_->set_u(kZsw2, zsw2);
  in_->set_u(kZsw, zsw);
  in_->set_u(kXist1, xist1);
  in_->set_u(kXist2, show_error ? error_code_ : position_);
  in_->set_u(kNistB, static_cast<uint32_t>(nist));
  ch.code = position_;

  info_->set_u(enc::kRoundAxis, enc::round_axis(hw_, s) ? 1 : 0);
  info_->set_u(enc::kErrorCode, sensor_error_ ? error_code_ : 0);
  info_->set_u(enc::kLifeFailureCounter, ls_counter_);
}

void EncoderDriver::clear_inputs() {
  for (uint8_t sub = kZsw2; sub <= kNistB; ++sub) in_->set_u(sub, 0);
}

bool EncoderDriver::set_parameter(std::string_view key, double) {
  // The hardware options are read (and checked, file:line) when the dictionary is built.
  return key == "singleturn_bits" || key == "multiturn_bits";
}

void EncoderDriver::set_fault(EncoderFault f, bool active, int64_t jump_steps) {
  const bool was = fault(f);
  if (f == EncoderFault::Jump && active) jump_steps_ = jump_steps;
  if (was == active) return;
  if (active) {
    if (f == EncoderFault::Frozen) frozen_at_ = steps_;
    faults_ = static_cast<uint8_t>(faults_ | bit(f));
  } else {
    faults_ = static_cast<uint8_t>(faults_ & ~bit(f));
  }
  for (const FaultInfo& x : kFaults) {
    if (x.fault != f) continue;
    report(active ? x.text : mdp::diag::removed_text(x.text), x.code);
  }
  update_error();
}

std::unique_ptr<CardDriver> make_encoder_driver(const mdp::Module& m, coe::ObjectDictionary& od) {
  return std::make_unique<EncoderDriver>(m, od);
}

}  // namespace rackcat::modules
