// Per-channel diagnosis messages of the slot cards: see channel_diagnostics.hpp.
#include "modules/rack/channel_diagnostics.hpp"

#include <algorithm>
#include <stdexcept>

#include "mdp/diagnosis_catalogue.hpp"
#include "modules/cards/uart_driver.hpp"

namespace rackcat::modules {
namespace {

using mdp::diag::channel_error_text;
using mdp::diag::ChannelError;

// Cause bits of one channel.
constexpr uint8_t kLineBreak = 1u << 0;
constexpr uint8_t kUpperLimit = 1u << 1;
constexpr uint8_t kLowerLimit = 1u << 2;
constexpr uint8_t kOverload = 1u << 3;
constexpr uint8_t kOvertemperature = 1u << 4;

struct Cause {
  uint8_t bit;
  ChannelError error;
};
constexpr Cause kCauses[] = {
    {kLineBreak, ChannelError::LineBreak},
    {kUpperLimit, ChannelError::UpperLimit},
    {kLowerLimit, ChannelError::LowerLimit},
    {kOverload, ChannelError::Overload},
    {kOvertemperature, ChannelError::Overtemperature},
};

struct UartCause {
  uint8_t bit;
  uint16_t text;
};
constexpr UartCause kUartCauses[] = {
    {uart::kErrRxOverflow, mdp::diag::text::kUartOverflow},
    {uart::kErrFraming, mdp::diag::text::kUartFraming},
    {uart::kErrParity, mdp::diag::text::kUartParity},
    {uart::kErrTxOverflow, mdp::diag::text::kUartTxOverflow},
};

uint8_t input_causes(const CardDriver& d, const InputChannel& in) {
  uint8_t bits = 0;
  if (in.open && d.has_sensor_break()) bits |= kLineBreak;
  if (d.card().signal == mdp::Signal::AnalogIn) {
    if (in.value > d.card().max_voltage) bits |= kUpperLimit;
    if (in.value < d.card().min_voltage) bits |= kLowerLimit;
  }
  return bits;
}

uint8_t output_causes(const OutputChannel& out) {
  return static_cast<uint8_t>((out.overload ? kOverload : 0) |
                              (out.overtemperature ? kOvertemperature : 0));
}

}  // namespace

ChannelDiagnostics::ChannelDiagnostics(mdp::Device& device,
                                       std::span<const std::unique_ptr<CardDriver>> drivers)
    : device_(device),
      drivers_(drivers),
      uarts_(drivers.size(), nullptr),
      input_causes_(drivers.size(), 0),
      inputs_(drivers.size()),
      outputs_(drivers.size()),
      uart_errors_(drivers.size()) {
  // Every module can be watched (watch_outputs): an output-fault injection on the device thread
  // then inserts without allocating.
  watched_.reserve(drivers.size());
  for (size_t i = 0; i < drivers.size(); ++i) {
    uarts_[i] = dynamic_cast<UartDriver*>(drivers[i].get());
    input_causes_[i] =
        drivers[i]->has_sensor_break() || drivers[i]->card().signal == mdp::Signal::AnalogIn;
    if (input_causes_[i] || uarts_[i] != nullptr) watched_.push_back(static_cast<uint16_t>(i));
  }
  reset();
}

void ChannelDiagnostics::watch_outputs(size_t module_index) {
  if (module_index >= drivers_.size()) throw std::out_of_range("no module at this index");
  const auto i = static_cast<uint16_t>(module_index);
  const auto at = std::lower_bound(watched_.begin(), watched_.end(), i);
  if (at == watched_.end() || *at != i) watched_.insert(at, i);
}

void ChannelDiagnostics::reset() {
  for (auto& a : inputs_) a.fill(0);
  for (auto& a : outputs_) a.fill(0);
  for (auto& a : uart_errors_) a.fill(0);
}

void ChannelDiagnostics::report(size_t module_index, size_t channel, uint16_t text) {
  const CardDriver& d = *drivers_[module_index];
  mdp::Device::DiagnosisReport r;
  r.text_id = text;
  r.rim = d.module().rim;
  r.module = d.module().number;
  r.channel = static_cast<uint8_t>(channel);
  device_.report_diagnosis(r);
}

void ChannelDiagnostics::evaluate_module(size_t i) {
  const CardDriver& d = *drivers_[i];
  auto diff = [&](uint8_t& reported, uint8_t now, size_t ch) {
    if (reported == now) return;
    for (const Cause& c : kCauses) {
      if (!((reported ^ now) & c.bit)) continue;
      const uint16_t appears = channel_error_text(c.error);
      report(i, ch, (now & c.bit) ? appears : mdp::diag::removed_text(appears));
    }
    reported = now;
  };
  const auto ins = d.inputs();
  // input_causes() is 0 for every channel of the other cards (and so is what was reported).
  for (size_t ch = 0; input_causes_[i] && ch < ins.size() && ch < 16; ++ch) {
    diff(inputs_[i][ch], input_causes(d, ins[ch]), ch);
  }
  const auto outs = d.outputs();
  for (size_t ch = 0; ch < outs.size() && ch < 16; ++ch) {
    diff(outputs_[i][ch], output_causes(outs[ch]), ch);
  }
  if (UartDriver* u = uarts_[i]) {
    for (size_t ch = 0; ch < 4; ++ch) {
      const uint8_t now = u->channel(ch).errors.load(std::memory_order_relaxed);
      const uint8_t rising = static_cast<uint8_t>(now & ~uart_errors_[i][ch]);
      for (const UartCause& c : kUartCauses) {
        if (rising & c.bit) report(i, ch, c.text);
      }
      uart_errors_[i][ch] = now;
    }
  }
}

}  // namespace rackcat::modules
