// Modular Device Profile objects (ETG.5001.1; guide Appendix A): 0xF000 Modular Device Profile,
// 0xF002 Detect Modules Command, 0xF010 Module Profile List, 0xF030 Configured Module Ident List
// and 0xF050 Detected Module Ident List.
//
// The guide's abort table calls 0xF030 "detected" and 0xF050 "configured"; ETG.5001.1 (and the
// guide's own Appendix A) have 0xF030 configured and 0xF050 detected, which is what is built.
#include <algorithm>
#include <array>
#include <cstring>

#include "coe/bits.hpp"
#include "mdp/card_catalogue.hpp"
#include "mdp/command_bytes.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;
using coe::AbortCode;

Object ident_list(const RackConfig& cfg, uint16_t index, const char* name, uint8_t entries,
                  uint16_t access) {
  Object o(index, ObjectCode::Array, name, static_cast<uint16_t>(DataType::Unsigned32));
  o.add(sub0(static_cast<uint8_t>(cfg.modules.size()), access));
  for (uint16_t s = 1; s <= entries; ++s) {
    const uint32_t ident = s <= cfg.modules.size() ? cfg.modules[s - 1].card->module_ident : 0;
    o.add(num(static_cast<uint8_t>(s), "Module " + std::to_string(s), DataType::Unsigned32, access,
              ident));
  }
  o.finalize();
  return o;
}

// Whether the configured list in `image` (0xF030 layout, complete-access image) equals 0xF050.
bool matches_detected(const coe::ObjectDictionary& od, std::span<const uint8_t> image) {
  const Object* detected = od.find(0xF050);
  if (!detected || image.empty()) return false;
  const uint8_t n = image[0];
  if (n != detected->sub0()) return false;
  for (uint8_t i = 1; i <= n; ++i) {
    const size_t at = 2 + 4 * (i - 1u);
    if (at + 4 > image.size()) return false;
    if (le::get32(&image[at]) != detected->get_u(i)) return false;
  }
  return true;
}

}  // namespace

bool module_lists_mismatch(const coe::ObjectDictionary& od) {
  const Object* configured = od.find(0xF030);
  if (!configured || configured->sub0() == 0) return false;
  return !matches_detected(od, configured->image());
}

void add_mdp_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  Object mdp(0xF000, ObjectCode::Record, "Modular Device Profile",
             coe::record_type::kModularDeviceProfile);
  mdp.add(sub0(2));
  mdp.add(num(1, "Index distance", DataType::Unsigned16, acc("ro") | kTx, kIndexDistance));
  mdp.add(num(2, "Maximum number of modules", DataType::Unsigned16, acc("ro") | kTx, kMaxModules));
  od.add(std::move(mdp));

  // Command bytes: the guide gives the size (ARRAY [0..3] OF BYTE) but no sequence; rackcat uses
  // "scan" (0x73 0x63 0x61 0x6E) in the style of 0xFBF2's "save". Other bytes: 0x06040043.
  Object detect(0xF002, ObjectCode::Record, "Detect Modules Command",
                coe::record_type::kCommandPar);
  detect.add(sub0(2));
  detect.add(octets(1, "Command", 4, acc("ro,wr_preop")));
  detect.add(num(2, "Status", DataType::Unsigned8, acc("ro"), 0));
  detect.finalize();
  detect.edit_hooks().validate_write = [](const Object& obj, int subindex,
                                          std::span<const uint8_t> data, EsmState) {
    const auto cmd = written_bytes(obj, 1, subindex, data);
    if (cmd.empty()) return AbortCode::None;
    if (subindex == -1 && std::equal(cmd.begin(), cmd.end(), obj.bytes(1).begin())) {
      return AbortCode::None;  // complete access writing back what it read
    }
    return std::equal(cmd.begin(), cmd.end(), cmd::kScan.begin(), cmd::kScan.end())
               ? AbortCode::None
               : AbortCode::ParameterIncompatible;
  };
  od.add(std::move(detect));

  // ETG.5001.1 reading: one subindex per module position. The guide lists one row per card
  // kind with the module ident as value; the value is kept, the numbering follows ETG.5001.
  Object profiles(0xF010, ObjectCode::Array, "Module Profile List",
                  static_cast<uint16_t>(DataType::Unsigned32));
  profiles.add(sub0(static_cast<uint8_t>(cfg.modules.size())));
  for (const auto& m : cfg.modules) {
    profiles.add(num(static_cast<uint8_t>(m.number), std::string(m.card->name),
                     DataType::Unsigned32, acc("ro"), m.card->module_ident));
  }
  od.add(std::move(profiles));

  Object configured =
      ident_list(cfg, 0xF030, "Configured Module Ident List", 255, acc("ro,wr_preop"));
  const coe::ObjectDictionary* dict = &od;
  configured.edit_hooks().validate_write = [dict](const Object& obj, int subindex,
                                                  std::span<const uint8_t> data, EsmState) {
    std::array<uint8_t, 2 + 4 * 255> cand{};
    const auto cur = obj.image();
    std::memcpy(cand.data(), cur.data(), std::min(cur.size(), cand.size()));
    if (subindex == -1) {
      std::memcpy(cand.data(), data.data(), std::min(data.size(), cand.size()));
    } else if (subindex == 0) {
      cand[0] = data.empty() ? 0 : data[0];
    } else if (data.size() >= 4) {
      std::memcpy(&cand[2 + 4 * (subindex - 1)], data.data(), 4);
    }
    // ETG.5001.1: subindex 0 = 0 switches the check off; entries beyond subindex 0 are staged
    // (the master writes 0, the entries, then the count). What is in use must match 0xF050.
    if (cand[0] == 0 || subindex > cand[0]) return AbortCode::None;
    return matches_detected(*dict, cand) ? AbortCode::None : AbortCode::ModuleListMismatch;
  };
  od.add(std::move(configured));
  od.add(ident_list(cfg, 0xF050, "Detected Module Ident List",
                    static_cast<uint8_t>(cfg.modules.size()), acc("ro")));
}

void attach_mdp_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device) {
  // 0xF002 Detect Modules: the detected list becomes the configured rack, then drivers remove
  // what is offline (modules/, Detect Modules Override).
  od.find(0xF002)->edit_hooks().after_write = [&device](Object& obj, int) {
    const auto c = obj.bytes(1);
    if (!std::equal(c.begin(), c.end(), cmd::kScan.begin(), cmd::kScan.end())) return;
    // Every configured module; the rack then narrows it to what it detects (guide Table 23).
    device.detect_modules();
    obj.set_u(2, cmd::kStatusScanComplete);
    restore_command(obj);
  };
}

}  // namespace rackcat::mdp
