#include "mdp/module_enumeration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "mdp/object_dictionary_builder.hpp"

namespace rackcat::mdp {
namespace {

std::vector<uint32_t> idents(const RackConfig& cfg, std::span<const uint8_t> present) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < cfg.modules.size(); ++i) {
    if (i >= present.size() || present[i] != 0) out.push_back(cfg.modules[i].card->module_ident);
  }
  return out;
}

// The values in use of a list object (ARRAY of UINT16/UINT32): sub 0 entries.
std::vector<uint64_t> in_use(const coe::Object& o) {
  std::vector<uint64_t> v;
  for (uint8_t s = 1; s <= o.sub0() && o.entry(s) != nullptr; ++s) v.push_back(o.get_u(s));
  return v;
}

// Sets the defaults of list object `o` to `values` (sub 0 = count, the rest 0); with `load`
// the live values too.
template <class T>
void set_list(coe::Object& o, const std::vector<T>& values, bool load) {
  const uint8_t n = static_cast<uint8_t>(values.size());
  const uint8_t sub0_value[1] = {n};
  o.set_default(0, sub0_value);
  // set_default may copy shared descriptions: subindices first, then the defaults.
  std::vector<uint8_t> subs;
  for (const auto& e : o.entries()) {
    if (e.subindex != 0) subs.push_back(e.subindex);
  }
  for (const uint8_t sub : subs) {
    const uint64_t v = sub <= values.size() ? values[sub - 1] : 0;
    uint8_t bytes[8];
    for (size_t b = 0; b < 8; ++b) bytes[b] = static_cast<uint8_t>(v >> (8 * b));
    o.set_default(sub, bytes);
  }
  if (load) o.load_defaults();
}

template <class T>
bool same(const std::vector<uint64_t>& live, const std::vector<T>& list) {
  return live.size() == list.size() && std::equal(live.begin(), live.end(), list.begin());
}

}  // namespace

void enumerate_modules(coe::ObjectDictionary& od, const RackConfig& cfg,
                       std::span<const uint8_t> previous, std::span<const uint8_t> present) {
  const std::vector<uint32_t> now = idents(cfg, present);
  const std::vector<uint32_t> before = idents(cfg, previous);
  for (uint16_t index : {uint16_t{0xF050}, uint16_t{0x3000}}) {
    if (coe::Object* o = od.find(index)) set_list(*o, now, true);
  }
  if (coe::Object* configured = od.find(0xF030)) {
    // Following the enumeration unless the master set a list of its own.
    set_list(*configured, now, same(in_use(*configured), before));
  }
  for (const bool rx : {true, false}) {
    coe::Object* assign = od.find(rx ? 0x1C12 : 0x1C13);
    if (assign == nullptr) continue;
    const auto was = default_assignment(cfg, rx, previous);
    set_list(*assign, default_assignment(cfg, rx, present), same(in_use(*assign), was));
  }
}

std::string module_list_difference(const coe::ObjectDictionary& od) {
  const coe::Object* configured = od.find(0xF030);
  const coe::Object* detected = od.find(0xF050);
  if (configured == nullptr || detected == nullptr || !module_lists_mismatch(od)) return {};
  const auto c = in_use(*configured), d = in_use(*detected);
  for (size_t i = 0; i < std::max(c.size(), d.size()); ++i) {
    const uint64_t cv = i < c.size() ? c[i] : 0, dv = i < d.size() ? d[i] : 0;
    if (i >= c.size() || i >= d.size() || cv != dv) {
      return fmt::format(
          "configured module list 0xF030 ({} modules) differs from the detected list 0xF050 ({} "
          "modules) at module {}: configured 0x{:08X}, detected 0x{:08X}",
          c.size(), d.size(), i + 1, cv, dv);
    }
  }
  return {};
}

}  // namespace rackcat::mdp
