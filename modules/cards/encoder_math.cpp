// Encoder arithmetic: see encoder_math.hpp.
#include "modules/cards/encoder_math.hpp"

#include <cmath>

namespace rackcat::modules::encoder {

using mdp::encoder::position_range;
using mdp::encoder::round_axis;

int64_t floor_div(int64_t a, int64_t b) {
  int64_t q = a / b;
  if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
  return q;
}

uint64_t floor_mod(int64_t a, uint64_t m) {
  const auto mm = static_cast<int64_t>(m);
  int64_t r = a % mm;
  if (r < 0) r += mm;
  return static_cast<uint64_t>(r);
}

int64_t steps_of(const Hardware& hw, double revolutions) {
  return static_cast<int64_t>(std::floor(revolutions * static_cast<double>(hw.steps_per_turn)));
}

int64_t directed(const Settings& s, int64_t steps) {
  return s.class4 && s.ccw ? -steps : steps;
}

uint64_t unshifted(const Hardware& hw, const Settings& s, int64_t d) {
  const uint64_t total = hw.total();
  if (!(s.class4 && s.scaling)) return floor_mod(d, total);
  const uint64_t range = s.total_range;
  // On a round axis the count itself is scaled; it is reduced modulo steps x range first,
  // which changes floor(d x units / steps) by a multiple of the range only (keeps the product
  // below 2^60). Otherwise the hardware counter d mod total is.
  const uint64_t base =
      round_axis(hw, s) ? floor_mod(d, uint64_t{hw.steps_per_turn} * range) : floor_mod(d, total);
  return (base * s.units_per_rev / hw.steps_per_turn) % range;
}

uint64_t shifted(const Hardware& hw, const Settings& s, uint64_t u, int64_t offset) {
  if (!s.class4) return u;
  const uint64_t range = position_range(hw, s);
  return floor_mod(static_cast<int64_t>(u) + offset, range);
}

int64_t preset_offset(uint64_t range, uint64_t u, int64_t preset) {
  return static_cast<int64_t>(floor_mod(preset - static_cast<int64_t>(u), range));
}

int64_t shift_offset(uint64_t range, int64_t offset, int64_t shift) {
  return static_cast<int64_t>(floor_mod(offset + shift, range));
}

double velocity_in_unit(const Hardware& hw, const Settings& s, double steps_per_s) {
  const double per_turn = static_cast<double>(hw.steps_per_turn);
  const double units = s.class4 && s.scaling
                           ? steps_per_s * static_cast<double>(s.units_per_rev) / per_turn
                           : steps_per_s;
  switch (s.velocity_unit) {
    case 1:
      return units * 0.1;
    case 2:
      return units * 0.01;
    case 3:
      return steps_per_s / per_turn * 60.0;
    default:
      return units;
  }
}

double filter_velocity(uint8_t filter, double old_value, double new_value) {
  switch (filter) {
    case 1:
      return (96.0 * old_value + 4.0 * new_value) / 100.0;
    case 2:
      return (996.0 * old_value + 4.0 * new_value) / 1000.0;
    default:
      return (7.0 * old_value + 3.0 * new_value) / 10.0;
  }
}

}  // namespace rackcat::modules::encoder
