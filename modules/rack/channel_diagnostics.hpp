// Per-channel diagnosis of the slot cards (ETG.1020 ch. 13 messages; causes after the PROFINET
// ChannelErrorType of the PROFINET/PROFIBUS diagnostic records description): every
// cycle the channel states are compared with what was last reported and each change becomes
// one 0x10F3 message (and its Emergency) through mdp::Device::report_diagnosis: an "appears"
// message when a cause becomes active, a "removed" one (class information) when it goes.
//
//   line break (0x0006)       thermocouple / RTD input open (InputChannel::open)
//   upper limit (0x0007)      analog input above the card's 0x3nn1:08 maximum voltage
//   lower limit (0x0008)      analog input below the card's 0x3nn1:09 minimum voltage
//   overload (0x0004)         output overload (OutputChannel::overload, fault injection)
//   overtemperature (0x0005)  output driver overtemperature (OutputChannel::overtemperature)
//   UART errors               a new receive overflow / framing / parity / transmit overflow bit
//                             of a UART channel (events: no "removed" message)
// Short circuits of sourcing outputs (wiring faults) come from the exception tree.
// Modules of a RIM that is not online keep their state (nothing is measured there).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "mdp/device.hpp"
#include "modules/cards/card_driver.hpp"

namespace rackcat::modules {

class UartDriver;

class ChannelDiagnostics {
 public:
  // `drivers` index = module number - 1; the spans must outlive this object.
  ChannelDiagnostics(mdp::Device& device, std::span<const std::unique_ptr<CardDriver>> drivers);

  // Device thread, no allocation. `online(module index)`: the module's RIM is online.
  template <class Online>
  void evaluate(Online&& online) {
    for (const uint16_t i : watched_) {
      if (online(i)) evaluate_module(i);
    }
  }
  // An output fault (overload / overtemperature) was injected on module index i: its output
  // channels are evaluated from now on (without one they have no cause to report). No
  // allocation (device thread). Throws std::out_of_range for an index without a module.
  void watch_outputs(size_t module_index);
  // Forget what was reported (0xFBF0 device reset: the history is empty again); the next
  // evaluate() reports what is still active.
  void reset();

 private:
  void evaluate_module(size_t i);
  void report(size_t module_index, size_t channel, uint16_t text);

  // The modules that can have anything to report, in module order: input causes, a UART, or
  // an output fault injected once (watch_outputs). The cyclic path visits only these (issue
  // 16: the others cost a line of racks nothing, not even a flag per module).
  std::vector<uint16_t> watched_;
  mdp::Device& device_;
  std::span<const std::unique_ptr<CardDriver>> drivers_;
  std::vector<UartDriver*> uarts_;  // index = module index, null if no UART
  // Whether the card's inputs can have a cause at all (sensor break, analog limits): fixed by
  // the card kind, so the cyclic path skips the channels of the others.
  std::vector<uint8_t> input_causes_;
  std::vector<std::array<uint8_t, 16>> inputs_;   // reported cause bits per input channel
  std::vector<std::array<uint8_t, 16>> outputs_;  // ... per output channel
  std::vector<std::array<uint8_t, 4>> uart_errors_;
};

}  // namespace rackcat::modules
