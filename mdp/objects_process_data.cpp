// Process-data objects: inputs 0x6nn0..0x6nnC and outputs 0x7nn0..0x7nn3, 0x7nnB (guide
// Appendix A), one per module with the layout of mdp/card_catalogue.cpp. Entries are TxPDO
// (inputs, "ro") or RxPDO (outputs, "rw") mappable. Sample arrays ("ARRAY [0..7] OF UINT") are
// OCTET_STRING entries of the array's size; DINx4/DOUTx4 pack BIT4 and a 4-bit pad.
#include "mdp/card_catalogue.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;

Object io_object(const Module& m, const IoLayout& l) {
  const bool has_pad = l.pad_bits != 0;
  // Entries of different types (the encoder telegram) make a RECORD, like a padded layout.
  const bool record = has_pad || !l.fields().empty();
  Object o(m.index(l.output ? 0x7000 : 0x6000, static_cast<uint8_t>(l.kind)),
           record ? ObjectCode::Record : ObjectCode::Array, std::string(l.name),
           record ? 0 : static_cast<uint16_t>(l.entry_type));
  if (has_pad) o.set_packed(true);
  const uint16_t a = l.output ? (acc("rw") | kRx) : (acc("ro") | kTx);
  o.add(sub0(static_cast<uint8_t>(l.entries + (has_pad ? 1 : 0))));
  // Thermocouple and RTD channels carry rackcat's temperature word, 0.1 °C per bit
  // (docs/MODULES.md "16-bit temperature scaling"). The analog codes are fractions of the
  // card's full scale (not a power of ten of a unit), which an ETG.1004 code cannot express.
  const bool temperature = m.card->signal == Signal::Thermocouple || m.card->signal == Signal::Rtd;
  for (uint8_t s = 1; s <= l.entries; ++s) {
    Entry e = coe::make_entry(s, l.entry_name(s), l.type_of(s), l.bits_of(s), a,
                              std::vector<uint8_t>((l.bits_of(s) + 7) / 8, 0));
    if (temperature && !l.output) e.unit = coe::unit::kDeciCelsius;
    o.add(std::move(e));
  }
  if (has_pad) o.add(pad(static_cast<uint8_t>(l.entries + 1), l.pad_bits));
  o.finalize();
  return o;
}

}  // namespace

void add_process_data_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  for (const auto& m : cfg.modules) {
    if (m.card->input) od.add(io_object(m, *io_layout(*m.card->input, false)));
  }
  for (const auto& m : cfg.modules) {
    if (m.card->output) od.add(io_object(m, *io_layout(*m.card->output, true)));
  }
}

}  // namespace rackcat::mdp
