// Thermocouple EMF per the NIST ITS-90 reference functions (NIST Monograph 175, the ITS-90
// thermocouple database): temperature -> EMF polynomials (type K above 0 °C with its
// exponential term) and the approximate inverse polynomials EMF -> temperature. Units are
// °C and mV throughout, as in the NIST tables.
//
// A thermocouple card (guide Table 3: 0xF012 K, 0xF013 J, 0xF014 R) measures the EMF of the
// loop, which is E(T_hot) - E(T_cold junction); it adds E(T_cj) from its terminal-block
// sensor (cold-junction compensation) and applies the inverse function.
#pragma once

#include <cstdint>
#include <optional>

namespace rackcat::modules {

enum class TcType : uint8_t { K, J, R };

struct TcRange {
  double min_c;
  double max_c;
};

// Temperature range of the reference function (K: -270..1372, J: -210..1200, R: -50..1768.1).
TcRange tc_reference_range(TcType type);
// Range of the inverse function (K: -200..1372, J: -210..1200, R: -50..1768.1).
TcRange tc_inverse_range(TcType type);

// E(t) in mV; t is clamped to the reference range.
double tc_emf_mv(TcType type, double t_c);
// t(E) in °C from the inverse polynomials; E outside the inverse range is clamped to it.
double tc_temperature_c(TcType type, double emf_mv);

// What the card reports for one channel.
struct TcMeasurement {
  double loop_emf_mv = 0.0;    // E(T_hot) - E(T_cj), what the input amplifier sees
  double temperature_c = 0.0;  // after cold-junction compensation and linearisation
  bool open_circuit = false;
};

// Simulate a channel: hot junction at t_hot_c, terminals at t_cj_c. `open` models a broken
// wire (no current through the loop): the card then reports an open circuit.
TcMeasurement tc_measure(TcType type, double t_hot_c, double t_cj_c, bool open);

}  // namespace rackcat::modules
