// Substitute value objects 0x4nn8, 0x4nnA, 0x4nnB, 0x4nnC per module (mdp/substitute_values.hpp,
// INTERBUS Basic profile §7.3.2 and objects 0x0020/0x0030/0x0031). A reaction code outside the
// profile's set answers 0x06090030 "value range of parameter exceeded" (ETG.1000.6 Table 41)
// and changes nothing.
#include <string>

#include "coe/bits.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"
#include "mdp/substitute_values.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;
using coe::AbortCode;

bool digital(const CardType& c) {
  return c.signal != Signal::AnalogIn && c.signal != Signal::AnalogOut &&
         c.signal != Signal::Thermocouple && c.signal != Signal::Rtd;
}

Object reaction_array(uint16_t index, const char* name, uint8_t channels, bool (*valid)(uint64_t)) {
  Object o(index, ObjectCode::Array, name, static_cast<uint16_t>(DataType::Unsigned16));
  o.add(sub0(channels));
  for (uint8_t c = 1; c <= channels; ++c) {
    o.add(num(c, "Channel " + std::to_string(c - 1), DataType::Unsigned16, acc("rw"),
              substitute::kGuide));
  }
  o.finalize();
  o.edit_hooks().validate_write = [valid](const Object& obj, int subindex,
                                          std::span<const uint8_t> data, EsmState) {
    if (subindex == 0) return AbortCode::None;  // sub 0 is read-only; the SDO server says so
    if (subindex > 0) {
      return data.size() >= 2 && valid(le::get16(data.data())) ? AbortCode::None
                                                               : AbortCode::ValueRange;
    }
    // Complete access: every entry of the candidate image.
    for (const auto& e : obj.entries()) {
      if (e.subindex == 0) continue;
      const size_t at = e.bit_offset / 8;
      if (at + 2 > data.size()) break;
      if (!valid(le::get16(&data[at]))) return AbortCode::ValueRange;
    }
    return AbortCode::None;
  };
  return o;
}

}  // namespace

void add_substitute_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  for (const auto& m : cfg.modules) {
    const CardType& c = *m.card;
    if (substitute::has_output_channels(c)) {
      od.add(reaction_array(m.index(0x4000, substitute::kOutputReaction),
                            "Output Substitute Reaction", c.channels,
                            [](uint64_t v) { return substitute::valid_output_reaction(v); }));
    }
    if (!substitute::has_input_channels(c)) continue;
    od.add(reaction_array(m.index(0x4000, substitute::kInputReaction), "Input Substitute Reaction",
                          c.channels,
                          [](uint64_t v) { return substitute::valid_input_reaction(v); }));
    Object values(m.index(0x4000, substitute::kInputValue), ObjectCode::Array,
                  "Input Substitute Value", static_cast<uint16_t>(DataType::Unsigned16));
    values.add(sub0(c.channels));
    for (uint8_t ch = 1; ch <= c.channels; ++ch) {
      // The channel's process-data code: 0/1 for a digital channel, the 16-bit code else.
      values.add(ranged(ch, "Channel " + std::to_string(ch - 1), DataType::Unsigned16, acc("rw"), 0,
                        0, digital(c) ? 1 : 0xFFFF));
    }
    od.add(std::move(values));
    od.add(var(m.index(0x4000, substitute::kInputStatus), "Input Substitute Status",
               num(0, "Input Substitute Status", DataType::Unsigned16, acc("ro") | kTx, 0)));
  }
}

}  // namespace rackcat::mdp
