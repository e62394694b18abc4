// Safe-state settings 0x4nn0..0x4nn3 (guide §2.5 Tables 7-10, Appendix A): per output module,
// enable/action bit masks and the values set when the device leaves OP. Access "ro,wr_op" as
// the guide lists it. The 4-channel force-guided relay uses 0x4nn1 with its low 4 bits (the guide
// has no 4-channel object); writes setting bits 4..7 answer 0x06090031.
#include "mdp/card_catalogue.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;

Object safe_state(const Module& m, SafeStateKind kind) {
  const uint8_t nibble = static_cast<uint8_t>(kind);
  Object o(m.index(0x4000, nibble), ObjectCode::Record, "Safe State Settings", 0);
  const bool wide_mask = kind == SafeStateKind::DoutX16 || kind == SafeStateKind::AoutX16;
  const DataType mask_type = wide_mask ? DataType::Unsigned16 : DataType::Unsigned8;
  const int64_t mask_max = (int64_t{1} << m.card->channels) - 1;
  const uint16_t a = acc("ro,wr_op");
  const bool digital = kind == SafeStateKind::DoutX16 || kind == SafeStateKind::DoutX8;
  const uint8_t values = digital ? 1 : m.card->channels;
  o.add(sub0(static_cast<uint8_t>(2 + values)));
  o.add(ranged(0x01, "Enable", mask_type, a, 0, 0, mask_max));
  o.add(ranged(0x02, "Action", mask_type, a, 0, 0, mask_max));
  if (digital) {
    o.add(ranged(0x03, "Value[1]", mask_type, a, 0, 0, mask_max));
  } else {
    for (uint8_t v = 1; v <= values; ++v) {
      o.add(num(static_cast<uint8_t>(2 + v), "Value[" + std::to_string(v) + "]",
                DataType::Unsigned16, a, 0));
    }
  }
  o.finalize();
  return o;
}

}  // namespace

void add_safe_state_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  for (const auto& m : cfg.modules) {
    if (m.card->safe_state) od.add(safe_state(m, *m.card->safe_state));
  }
}

}  // namespace rackcat::mdp
