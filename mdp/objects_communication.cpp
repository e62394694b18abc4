// Communication area 0x1000-0x1C33 (ETG.1000.6 §5.6.7.4; ETG.1020 §8 for 0x1C32/0x1C33; guide
// Appendix A for 0x100B, the mapping objects and the assignment objects).
#include <array>
#include <cstring>

#include "coe/bits.hpp"
#include "coe/pdo_mapping.hpp"
#include "mdp/card_catalogue.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"
#include "mdp/sync_manager_layout.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;
using coe::AbortCode;

// ETG.5001.1: device type of a modular device = profile 5001 (0x1389).
constexpr uint32_t kDeviceTypeMdp = 0x00001389;
constexpr uint8_t kMaxAssignEntries = 255;

Object mapping_object(const Module& m, const IoLayout& layout) {
  const uint16_t pdo = layout.output ? sm::rx_pdo_index(m.number) : sm::tx_pdo_index(m.number);
  const uint16_t target =
      m.index(layout.output ? 0x7000 : 0x6000, static_cast<uint8_t>(layout.kind));
  Object o(pdo, ObjectCode::Record, std::string(layout.pdo_name), coe::record_type::kPdoMapping);
  const uint8_t count = static_cast<uint8_t>(layout.entries + (layout.pad_bits ? 1 : 0));
  o.add(sub0(count));
  for (uint8_t s = 1; s <= layout.entries; ++s) {
    const uint32_t value = (uint32_t{target} << 16) | (uint32_t{s} << 8) | layout.bits_of(s);
    o.add(num(s, layout.entry_name(s), DataType::Unsigned32, acc("ro"), value));
  }
  if (layout.pad_bits) {
    // ETG.1000.6 §5.6.7.4.8: a gap in a PDO is mapped as index 0, subindex 0, length n.
    o.add(num(static_cast<uint8_t>(layout.entries + 1), "Padding", DataType::Unsigned32, acc("ro"),
              layout.pad_bits));
  }
  o.finalize();
  return o;
}

// The other PDOs assigned in the direction of mapping object `pdo`, in bits (0 when `pdo` is not
// assigned: its length then only matters once it is, and 0x1C12/0x1C13 check that).
uint32_t other_assigned_bits(const coe::ObjectDictionary& od, uint16_t pdo, coe::PdoDirection dir,
                             bool& assigned) {
  assigned = false;
  const coe::Object* assign = od.find(dir == coe::PdoDirection::Rx ? 0x1C12 : 0x1C13);
  if (!assign) return 0;
  uint32_t bits = 0;
  for (uint8_t i = 1; i <= assign->sub0() && i <= assign->max_subindex(); ++i) {
    const auto index = static_cast<uint16_t>(assign->get_u(i));
    if (index == pdo) {
      assigned = true;
      continue;
    }
    if (const coe::Object* m = od.find(index)) {
      AbortCode rc;
      bits += static_cast<uint32_t>(coe::mapping_bits(od, *m, dir, rc));
    }
  }
  return bits;
}

// A user PDO (sync_manager_layout.hpp): subindex 0 and the entries writable in PREOP, checked by
// coe's mapping rules (0x06010003 entries change only while subindex 0 is 0, 0x06020000 /
// 0x06090011 no such object / subindex, 0x06040041 not mappable in this direction, 0x06040043
// length differs from the entry's, 0x06040042 longer than the SyncManager takes) and, while the
// PDO is assigned, the whole assignment's length (0x06040042).
Object user_pdo(coe::ObjectDictionary& od, bool rx) {
  const uint16_t index = rx ? sm::kUserRxPdo : sm::kUserTxPdo;
  const auto dir = rx ? coe::PdoDirection::Rx : coe::PdoDirection::Tx;
  Object o(index, ObjectCode::Record, rx ? "User RxPDO" : "User TxPDO",
           coe::record_type::kPdoMapping);
  o.add(sub0(0, acc("ro,wr_preop")));
  for (uint8_t s = 1; s <= sm::kUserPdoEntries; ++s) {
    o.add(num(s, "SubIndex " + std::string(s < 10 ? "00" : "0") + std::to_string(s),
              DataType::Unsigned32, acc("ro,wr_preop"), 0));
  }
  o.finalize();
  auto checks = coe::pdo_mapping_validator(od, dir, sm::kMaxProcessDataBytes);
  o.edit_hooks().validate_write = [checks, &od, index, dir](const Object& obj, int subindex,
                                                            std::span<const uint8_t> data,
                                                            EsmState state) {
    if (AbortCode rc = checks(obj, subindex, data, state); rc != AbortCode::None) return rc;
    // Only subindex 0 (or a complete write) brings entries into use.
    if (subindex >= 1) return AbortCode::None;
    bool assigned = false;
    const uint32_t others = other_assigned_bits(od, index, dir, assigned);
    if (!assigned) return AbortCode::None;
    const uint8_t n = data.empty() ? 0 : data[0];
    uint32_t bits = 0;
    for (uint8_t i = 1; i <= n && i <= obj.max_subindex(); ++i) {
      const coe::Entry* e = obj.entry(i);
      const size_t at = e->bit_offset / 8;
      const uint32_t v = subindex == -1 && at + 4 <= data.size()
                             ? le::get32(data.data() + at)
                             : static_cast<uint32_t>(obj.get_u(i));
      bits += v & 0xFF;
    }
    return (others + bits + 7) / 8 > sm::kMaxProcessDataBytes ? AbortCode::PdoLengthExceeded
                                                              : AbortCode::None;
  };
  return o;
}

// The assignment list in use after a write to 0x1C12/0x1C13 (single entry or complete
// access), without allocating.
struct Assignment {
  std::array<uint16_t, kMaxAssignEntries> pdo{};
  uint8_t count = 0;
};

Assignment candidate(const Object& obj, int subindex, std::span<const uint8_t> data) {
  std::array<uint8_t, 2 + 2 * kMaxAssignEntries> img{};
  const auto cur = obj.image();
  std::memcpy(img.data(), cur.data(), std::min(cur.size(), img.size()));
  if (subindex == -1) {
    std::memcpy(img.data(), data.data(), std::min(data.size(), img.size()));
  } else if (subindex == 0) {
    img[0] = data.empty() ? 0 : data[0];
  } else if (const coe::Entry* e = obj.entry(static_cast<uint8_t>(subindex));
             e && data.size() >= 2) {
    img[e->bit_offset / 8] = data[0];
    img[e->bit_offset / 8 + 1] = data[1];
  }
  Assignment a;
  a.count = img[0];
  for (uint8_t i = 0; i < a.count && i < kMaxAssignEntries; ++i) {
    a.pdo[i] = le::get16(&img[2 + 2 * i]);
  }
  return a;
}

Object assignment_object(const RackConfig& cfg, coe::ObjectDictionary& od, bool rx) {
  Object o(rx ? 0x1C12 : 0x1C13, ObjectCode::Array, rx ? "RxPDO assign" : "TxPDO assign",
           static_cast<uint16_t>(DataType::Unsigned16));
  const std::vector<uint16_t> defaults = default_assignment(cfg, rx, {});
  o.add(sub0(static_cast<uint8_t>(defaults.size()), acc("ro,wr_preop")));
  for (uint16_t s = 1; s <= kMaxAssignEntries; ++s) {
    const uint16_t def = s <= defaults.size() ? defaults[s - 1] : 0;
    o.add(num(static_cast<uint8_t>(s), rx ? "Output assignment" : "Input assignment",
              DataType::Unsigned16, acc("ro,wr_preop"), def));
  }
  o.finalize();
  auto checks = coe::pdo_assign_validator(od, rx ? coe::PdoDirection::Rx : coe::PdoDirection::Tx,
                                          sm::kMaxProcessDataBytes);
  o.edit_hooks().validate_write = [checks](const Object& obj, int subindex,
                                           std::span<const uint8_t> data, EsmState state) {
    if (AbortCode rc = checks(obj, subindex, data, state); rc != AbortCode::None) return rc;
    const Assignment a = candidate(obj, subindex, data);
    for (uint8_t i = 0; i < a.count; ++i) {
      for (uint8_t j = 0; j < i; ++j) {
        if (a.pdo[i] == a.pdo[j]) return AbortCode::ParameterIncompatible;
      }
    }
    return AbortCode::None;
  };
  return o;
}

Object sync_parameter_object(bool outputs) {
  Object o(outputs ? 0x1C32 : 0x1C33, ObjectCode::Record,
           outputs ? "SM output parameter" : "SM input parameter",
           coe::record_type::kSmSynchronisation);
  o.add(sub0(0x20));
  Entry type = num(0x01, "Synchronization Type", DataType::Unsigned16, acc("ro,wr_preop"),
                   outputs ? kSyncSmEvent : kSyncWithSm2);
  o.add(type);
  o.add(num(0x02, "Cycle Time", DataType::Unsigned32, acc("ro,wr_preop"), 1000000));
  o.add(num(0x03, "Shift Time", DataType::Unsigned32, acc("ro"), 0));
  o.add(num(0x04, "Synchronization Types supported", DataType::Unsigned16, acc("ro"),
            kSyncTypesSupported));
  o.add(num(0x05, "Minimum Cycle Time", DataType::Unsigned32, acc("ro"), 250000));
  o.add(num(0x06, "Calc and Copy Time", DataType::Unsigned32, acc("ro"), 20000));
  o.add(num(0x07, "Minimum Delay Time", DataType::Unsigned32, acc("ro"), 0));
  // 1 = measure the local cycle time, 2 = reset the counters (ETG.1020 §8.2.2 "Get Cycle Time").
  o.add(ranged(0x08, "Get Cycle Time", DataType::Unsigned16, acc("rw"), 0, 0, 2));
  o.add(num(0x09, "Delay Time", DataType::Unsigned32, acc("ro"), 0));
  o.add(num(0x0A, "Sync0 Cycle Time", DataType::Unsigned32, acc("ro,wr_preop"), 0));
  o.add(num(0x0B, "SM-Event Missed", DataType::Unsigned16, acc("ro"), 0));
  o.add(num(0x0C, "Cycle Time Too Small", DataType::Unsigned16, acc("ro"), 0));
  o.add(num(0x20, "Sync Error", DataType::Boolean, acc("ro"), 0));
  o.finalize();
  o.edit_hooks().validate_write = [outputs](const Object& obj, int subindex,
                                            std::span<const uint8_t> data, EsmState) {
    const auto v = written_bytes(obj, 0x01, subindex, data);
    if (v.size() < 2) return AbortCode::None;
    const uint16_t t = le::get16(v.data());
    const bool ok = t == kSyncFreeRun || t == kSyncSmEvent || t == kSyncDcSync0 ||
                    (!outputs && t == kSyncWithSm2);
    return ok ? AbortCode::None : AbortCode::ValueRange;
  };
  return o;
}

}  // namespace

std::vector<uint16_t> default_assignment(const RackConfig& cfg, bool rx,
                                         std::span<const uint8_t> enumerated) {
  // Every enumerated module's PDO of this direction in module order, as long as the total fits
  // the SM maximum (a rack of 120 oversampled analog cards has more than 16 KiB of inputs; the
  // master then assigns the subset it wants).
  std::vector<uint16_t> defaults;
  uint32_t bits = 0;
  for (size_t i = 0; i < cfg.modules.size(); ++i) {
    const Module& m = cfg.modules[i];
    if (i < enumerated.size() && enumerated[i] == 0) continue;
    const auto kind = rx ? m.card->output : m.card->input;
    if (!kind) continue;
    const uint32_t pdo_bits = io_layout(*kind, rx)->object_bits();
    if ((bits + pdo_bits + 7) / 8 > sm::kMaxProcessDataBytes) break;
    bits += pdo_bits;
    defaults.push_back(rx ? sm::rx_pdo_index(m.number) : sm::tx_pdo_index(m.number));
  }
  return defaults;
}

void add_communication_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  const ControlModule& cm = cfg.control;
  od.add(var(0x1000, "Device type",
             num(0, "Device type", DataType::Unsigned32, acc("ro"), kDeviceTypeMdp)));
  auto text_var = [&](uint16_t index, const char* name, const std::string& value) {
    od.add(var(
        index, name,
        str(0, name, static_cast<uint16_t>(std::max<size_t>(value.size(), 1)), acc("ro"), value)));
  };
  text_var(0x1008, "Manufacturer device name", cm.device_name);
  text_var(0x1009, "Manufacturer hardware version", cm.hardware_version);
  text_var(0x100A, "Manufacturer software version", cm.software_version);
  // Guide Appendix A: STRING(6), default "1.09.0".
  od.add(var(0x100B, "Manufacturer FW Bootloader Version",
             str(0, "Manufacturer FW Bootloader Version", 6, acc("ro"), cm.bootloader_version)));

  Object id(0x1018, ObjectCode::Record, "Identity", coe::record_type::kIdentity);
  id.add(sub0(4));
  id.add(num(1, "Vendor ID", DataType::Unsigned32, acc("ro"), cm.vendor_id));
  id.add(num(2, "Product code", DataType::Unsigned32, acc("ro"), cm.product_code));
  id.add(num(3, "Revision", DataType::Unsigned32, acc("ro"), cm.revision));
  id.add(num(4, "Serial number", DataType::Unsigned32, acc("ro"), cm.serial));
  od.add(std::move(id));

  for (const auto& m : cfg.modules) {
    if (m.card->output) od.add(mapping_object(m, *io_layout(*m.card->output, true)));
  }
  od.add(user_pdo(od, true));
  for (const auto& m : cfg.modules) {
    if (m.card->input) od.add(mapping_object(m, *io_layout(*m.card->input, false)));
  }
  od.add(user_pdo(od, false));

  Object smt(0x1C00, ObjectCode::Array, "Sync manager type",
             static_cast<uint16_t>(DataType::Unsigned8));
  smt.add(sub0(4));
  smt.add(num(1, "SM0 (mailbox out)", DataType::Unsigned8, acc("ro"), sm::kTypeMailboxOut));
  smt.add(num(2, "SM1 (mailbox in)", DataType::Unsigned8, acc("ro"), sm::kTypeMailboxIn));
  smt.add(num(3, "SM2 (outputs)", DataType::Unsigned8, acc("ro"), sm::kTypeOutputs));
  smt.add(num(4, "SM3 (inputs)", DataType::Unsigned8, acc("ro"), sm::kTypeInputs));
  od.add(std::move(smt));

  od.add(assignment_object(cfg, od, true));
  od.add(assignment_object(cfg, od, false));
  od.add(sync_parameter_object(true));
  od.add(sync_parameter_object(false));
}

void attach_communication_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device) {
  // 0x1C12/0x1C13: a new assignment recompiles the process image (mailbox path, PREOP only).
  // The user PDOs likewise: a new mapping of an assigned PDO changes the SM2/SM3 sizes the ESM
  // checks on PREOP->SAFEOP.
  for (uint16_t index : {uint16_t{0x1C12}, uint16_t{0x1C13}, sm::kUserRxPdo, sm::kUserTxPdo}) {
    od.find(index)->edit_hooks().after_write = [&device](Object&, int) {
      device.recompile_process_image();
    };
  }
  // 0x1C32/0x1C33: counters from the cyclic path; Get Cycle Time = 2 resets them.
  for (const bool outputs : {true, false}) {
    Object* o = od.find(outputs ? 0x1C32 : 0x1C33);
    o->edit_hooks().before_read = [&device, outputs](Object& obj, int) {
      const SyncStatistics& s = device.sync_statistics(outputs);
      obj.set_u(0x0B, s.sm_event_missed);
      obj.set_u(0x0C, s.cycle_time_too_small);
      obj.set_u(0x20, s.sync_error ? 1 : 0);
    };
    o->edit_hooks().after_write = [&device, outputs](Object& obj, int subindex) {
      if ((subindex == 0x08 || subindex == -1) && obj.get_u(0x08) == 2) {
        device.sync_statistics(outputs) = SyncStatistics{};
      }
    };
  }
}

}  // namespace rackcat::mdp
