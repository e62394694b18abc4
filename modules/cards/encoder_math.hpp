// Position, scaling, round-axis, preset and velocity arithmetic of the absolute rotary encoder
// card, after the encoder guide (the PROFINET absolute encoder user guide,
// "the guide"), section numbers as in its function table (3.11.x). Pure functions on integers
// (no state, no allocation); the card driver (encoder_driver.hpp) keeps the state.
//
// The chain, per sample (docs/ENCODER.md works through examples):
//   steps  = floor(shaft revolutions x steps per turn)          physical step count, signed
//   d      = -steps if class 4 and code sequence CCW, else steps (3.11.1: counting direction)
//   u      = unshifted(d): without class 4 or scaling d mod hardware total; with scaling
//            floor(d' x units per revolution / steps per turn) mod total range, where d' is the
//            hardware counter (d mod total) or, on a round axis (3.11.13), the count itself
//   pos    = (u + offset) mod range                              3.11.7 / 3.11.8 (class 4)
#pragma once

#include <cstdint>

#include "mdp/encoder_settings.hpp"

namespace rackcat::modules::encoder {

using mdp::encoder::Hardware;
using mdp::encoder::Settings;

// Floor division and the non-negative remainder (m > 0).
int64_t floor_div(int64_t a, int64_t b);
uint64_t floor_mod(int64_t a, uint64_t m);

// Physical steps of a shaft angle in revolutions: floor(revolutions x steps per turn).
int64_t steps_of(const Hardware& hw, double revolutions);
// Counting direction (3.11.1): CCW counts the other way; only with class 4 (3.11.2).
int64_t directed(const Settings& s, int64_t steps);
// The position before the preset offset, in [0, position_range).
uint64_t unshifted(const Hardware& hw, const Settings& s, int64_t directed_steps);
// The position with the offset applied (offset in [0, range); no offset without class 4).
uint64_t shifted(const Hardware& hw, const Settings& s, uint64_t unshifted_position,
                 int64_t offset);
// Offsets a preset computes (3.11.7): "set" makes the current position equal to `preset`
// (a negative value counts back from the range: -1 is range - 1); "shift" moves the position
// by `preset` (G1_STW1 bit 11 = 1).
int64_t preset_offset(uint64_t range, uint64_t unshifted_position, int64_t preset);
int64_t shift_offset(uint64_t range, int64_t offset, int64_t shift);

// Velocity (3.11.11) from physical steps per second, in the configured unit: measuring units
// (scaled steps) per s, per 100 ms, per 10 ms, or revolutions per minute.
double velocity_in_unit(const Hardware& hw, const Settings& s, double steps_per_s);
// The exponential moving average of 3.11.12 ("ratio between old and actual velocity value":
// fine 7:3, normal 96:4, coarse 996:4).
double filter_velocity(uint8_t filter, double old_value, double new_value);

}  // namespace rackcat::modules::encoder
