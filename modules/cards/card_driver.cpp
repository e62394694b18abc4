#include "modules/cards/card_driver.hpp"

#include <algorithm>
#include <stdexcept>

#include "modules/cards/drivers.hpp"
#include "modules/cards/substitute.hpp"

namespace rackcat::modules {

CardDriver::CardDriver(const mdp::Module& module, coe::ObjectDictionary& od, size_t inputs,
                       size_t outputs)
    : inputs_(inputs),
      affine_(inputs),
      outputs_(outputs),
      sources_(inputs),
      module_(module),
      od_(od) {
  for (size_t i = 0; i < inputs; ++i) set_source(i, std::make_unique<ConstantSource>(0.0));
  namespace sv = mdp::substitute;
  output_reaction_ = object(0x4000, sv::kOutputReaction);
  input_reaction_ = object(0x4000, sv::kInputReaction);
  input_value_ = object(0x4000, sv::kInputValue);
  if (input_reaction_ != nullptr) reaction_channels_ = input_reaction_->max_subindex();
  if (coe::Object* status = object(0x4000, sv::kInputStatus)) {  // 0x4nnC
    input_status_slot_ = coe::EntrySlot(*status, 0);
  }
}

uint16_t CardDriver::output_reaction(size_t i) const {
  if (output_reaction_ == nullptr || i >= output_reaction_->max_subindex()) {
    return mdp::substitute::kGuide;
  }
  return static_cast<uint16_t>(output_reaction_->get_u(static_cast<uint8_t>(i + 1)));
}

void CardDriver::substitute_inputs(bool rim_offline) {
  if (input_reaction_ == nullptr) return;
  // Nothing missing now nor at the last pass, and the codes that pass remembered as the last
  // valid ones are still the codes: 0x4nnC reads 0 already (issue 16: no per-channel work while
  // the inputs repeat).
  if (!rim_offline && codes_repeated_ && none_missing_) return;
  uint32_t status = 0;
  // Bounds and base hoisted: the stores below must not make the loop reload the vector.
  const size_t n = std::min(inputs_.size(), reaction_channels_);
  InputChannel* const channels = inputs_.data();
  for (size_t i = 0; i < n; ++i) {
    InputChannel& in = channels[i];
    if (!rim_offline && !in.open) {
      in.last_valid = in.code;
      continue;
    }
    status |= 1u << i;
    const auto sub = static_cast<uint8_t>(i + 1);
    const auto reaction = static_cast<uint16_t>(input_reaction_->get_u(sub));
    if (reaction == mdp::substitute::kGuide) continue;  // the card's own code stays
    const uint32_t value = input_value_ ? static_cast<uint32_t>(input_value_->get_u(sub)) : 0;
    in.code = input_substitute(reaction, in.code, in.last_valid, value);
    put_input_code(i, in.code);
  }
  input_status_slot_.set(status);
  none_missing_ = status == 0;
}

void CardDriver::set_source(size_t i, std::unique_ptr<Source> source) {
  if (source == nullptr) throw std::invalid_argument("no source");
  affine_.at(i) = source->affine();
  sources_.at(i) = std::move(source);
  sources_vary_ = std::any_of(sources_.begin(), sources_.end(),
                              [](const auto& s) { return s && s->varies_within_cycle(); });
}

coe::Object* CardDriver::object(uint16_t area_base, uint8_t nibble) {
  return od_.find(module_.index(area_base, nibble));
}

void CardDriver::set_wiring_fault(size_t i, WiringFault fault) {
  outputs_[i].fault = fault;
  drive(i, outputs_[i].driven, outputs_[i].code);
}

void CardDriver::de_energise() {
  for (size_t i = 0; i < outputs_.size(); ++i) drive(i, 0.0, 0);
}

uint32_t CardDriver::safe_wiring_faults() const {
  uint32_t bits = 0;
  for (size_t i = 0; i < outputs_.size(); ++i) {
    if (outputs_[i].driven >= 0.5 && outputs_[i].wire < 0.5) bits |= 1u << i;
  }
  return bits;
}

uint32_t CardDriver::unsafe_wiring_faults() const {
  uint32_t bits = 0;
  for (size_t i = 0; i < outputs_.size(); ++i) {
    if (outputs_[i].driven < 0.5 && outputs_[i].wire >= 0.5) bits |= 1u << i;
  }
  return bits;
}

std::unique_ptr<CardDriver> make_driver(const mdp::Module& module, coe::ObjectDictionary& od) {
  using mdp::Signal;
  switch (module.card->signal) {
    case Signal::DigitalIn:
    case Signal::DigitalInInverted:
      return make_digital_input_driver(module, od);
    case Signal::DigitalOutSource:
    case Signal::DigitalOutSink:
    case Signal::DigitalOutOpto:
    case Signal::Relay:
    case Signal::RelayForceGuided:
      return make_digital_output_driver(module, od);
    case Signal::DigitalInOut:
      return make_dio_driver(module, od);
    case Signal::AnalogIn:
      return make_analog_input_driver(module, od);
    case Signal::AnalogOut:
      return make_analog_output_driver(module, od);
    case Signal::Thermocouple:
      return make_thermocouple_driver(module, od);
    case Signal::Rtd:
      return make_rtd_driver(module, od);
    case Signal::Uart:
      return make_uart_driver(module, od);
    case Signal::Encoder:
      return make_encoder_driver(module, od);
  }
  return nullptr;
}

}  // namespace rackcat::modules
