#include "apps/pdo_layout.hpp"

#include <utility>

namespace rackcat::apps {
namespace {

void walk(const coe::ObjectDictionary& od, uint16_t assign_index, bool output, PdoLayout& out) {
  const coe::Object* assign = od.find(assign_index);
  if (!assign) return;
  uint32_t& bit = output ? out.output_bits : out.input_bits;
  const auto pdos = static_cast<uint8_t>(assign->get_u(0));
  for (uint8_t i = 1; i <= pdos; ++i) {
    const auto pdo_index = static_cast<uint16_t>(assign->get_u(i));
    const coe::Object* pdo = od.find(pdo_index);
    if (!pdo) continue;
    const auto n = static_cast<uint8_t>(pdo->get_u(0));
    for (uint8_t k = 1; k <= n; ++k) {
      const auto m = static_cast<uint32_t>(pdo->get_u(k));
      PdoLayoutEntry e;
      e.output = output;
      e.pdo = pdo_index;
      e.index = static_cast<uint16_t>(m >> 16);
      e.subindex = static_cast<uint8_t>(m >> 8);
      e.bits = static_cast<uint8_t>(m);
      e.bit_offset = bit;
      if (e.index == 0 || (e.index < 0x1000 && e.subindex == 0)) {
        e.name = "padding";  // ETG.1000.6 §5.6.7.4.7: data type index = gap
      } else if (const coe::Object* o = od.find(e.index)) {
        const coe::Entry* entry = o->entry(e.subindex);
        e.name = o->name();
        if (entry && o->code() != coe::ObjectCode::Var && !entry->name.empty()) {
          e.name += " / " + entry->name;
        }
      }
      bit += e.bits;
      out.entries.push_back(std::move(e));
    }
  }
}

}  // namespace

PdoLayout pdo_layout(const coe::ObjectDictionary& od) {
  PdoLayout layout;
  walk(od, 0x1C12, true, layout);
  walk(od, 0x1C13, false, layout);
  return layout;
}

}  // namespace rackcat::apps
