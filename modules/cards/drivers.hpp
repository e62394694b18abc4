// Factories of the slot-card drivers, one per card kind (make_driver() picks by the
// catalogue's Signal). Each throws std::runtime_error when the module's process-data objects
// are missing from the dictionary (a device/catalogue mismatch at start-up).
#pragma once

#include <memory>

#include "modules/cards/card_driver.hpp"

namespace rackcat::modules {

// DINx16 / DINx8 / DINx4 and the 8x-oversampled DINx16x8 / DINx8x8 (24 V, 5 V, inverted).
std::unique_ptr<CardDriver> make_digital_input_driver(const mdp::Module&, coe::ObjectDictionary&);
// DOUTx16 / DOUTx8 / DOUTx4: sourcing (wire read-back, wiring faults), sinking, opto, relays,
// force-guided relays (feedback contacts in DINx4).
std::unique_ptr<CardDriver> make_digital_output_driver(const mdp::Module&, coe::ObjectDictionary&);
// E84 DIO: 8 inputs + 8 outputs, the outputs' read-back in DIOx8 subindex 2.
std::unique_ptr<CardDriver> make_dio_driver(const mdp::Module&, coe::ObjectDictionary&);
// AINx8 / AINx16 and the oversampled AINx8x8 / AINx16x8.
std::unique_ptr<CardDriver> make_analog_input_driver(const mdp::Module&, coe::ObjectDictionary&);
// AOUTx8 / AOUTx16.
std::unique_ptr<CardDriver> make_analog_output_driver(const mdp::Module&, coe::ObjectDictionary&);
// Thermocouplex8 (K, J, R) and 0x5nn4 loop resistance.
std::unique_ptr<CardDriver> make_thermocouple_driver(const mdp::Module&, coe::ObjectDictionary&);
// RTDx4 (Pt100).
std::unique_ptr<CardDriver> make_rtd_driver(const mdp::Module&, coe::ObjectDictionary&);
// UARTx4 (modules/cards/uart_driver.hpp).
std::unique_ptr<CardDriver> make_uart_driver(const mdp::Module&, coe::ObjectDictionary&);
// Absolute rotary encoder (modules/cards/encoder_driver.hpp).
std::unique_ptr<CardDriver> make_encoder_driver(const mdp::Module&, coe::ObjectDictionary&);

// Shared helpers of the drivers.
coe::Object& require_object(coe::ObjectDictionary& od, uint16_t index, const mdp::Module& m);
float read_real32(const coe::Object& o, uint8_t subindex);

}  // namespace rackcat::modules
