#include "esi/describe_dictionary.hpp"

#include <fmt/format.h>
#include <algorithm>

#include "coe/access.hpp"

namespace rackcat::esi {
namespace {

// PDO mapping and assignment areas (ETG.1000.6 §5.6.7.4.7/8).
constexpr uint16_t kRxMappingFirst = 0x1600, kRxMappingLast = 0x17FF;
constexpr uint16_t kTxMappingFirst = 0x1A00, kTxMappingLast = 0x1BFF;
constexpr uint16_t kRxAssign = 0x1C12, kTxAssign = 0x1C13;

std::vector<uint16_t> assignment(const coe::ObjectDictionary& od, uint16_t index) {
  std::vector<uint16_t> out;
  const auto* obj = od.find(index);
  if (!obj) return out;
  for (uint8_t sub = 1; sub <= obj->sub0(); ++sub) {
    if (!obj->entry(sub)) break;
    out.push_back(static_cast<uint16_t>(obj->get_u(sub)));
  }
  return out;
}

std::vector<PdoDescription> describe_direction(const coe::ObjectDictionary& od, uint16_t first,
                                               uint16_t last, uint16_t assign_index, uint8_t sm) {
  auto assigned = assignment(od, assign_index);
  std::vector<PdoDescription> in_order;
  std::vector<PdoDescription> rest;
  for (uint16_t pdo : assigned) {
    const auto* mapping = od.find(pdo);
    if (!mapping || pdo < first || pdo > last) {
      throw DescribeError(
          fmt::format("0x{:04X} assigns PDO 0x{:04X}, which is not a mapping "
                      "object of the dictionary",
                      assign_index, pdo));
    }
    in_order.push_back(describe_pdo(od, *mapping, sm));
  }
  for (size_t pos = od.lower_bound(first); pos < od.size() && od.at(pos).index() <= last; ++pos) {
    const auto& mapping = od.at(pos);
    if (std::find(assigned.begin(), assigned.end(), mapping.index()) != assigned.end()) continue;
    auto p = describe_pdo(od, mapping, sm);
    p.assigned = false;
    rest.push_back(std::move(p));
  }
  in_order.insert(in_order.end(), std::make_move_iterator(rest.begin()),
                  std::make_move_iterator(rest.end()));
  return in_order;
}

}  // namespace

PdoDescription describe_pdo(const coe::ObjectDictionary& od, const coe::Object& mapping,
                            uint8_t sm) {
  PdoDescription p;
  p.index = mapping.index();
  p.name = mapping.name();
  p.sm = sm;
  const auto* sub0 = mapping.entry(0);
  p.fixed = !sub0 || (sub0->access & coe::access::kWriteAll) == 0;
  for (uint8_t sub = 1; sub <= mapping.sub0(); ++sub) {
    if (!mapping.entry(sub)) break;
    auto value = static_cast<uint32_t>(mapping.get_u(sub));
    PdoEntryDescription e;
    e.index = static_cast<uint16_t>(value >> 16);
    e.subindex = static_cast<uint8_t>(value >> 8);
    e.bit_length = static_cast<uint8_t>(value);
    if (const auto* obj = od.find(e.index)) {
      if (const auto* entry = obj->entry(e.subindex)) {
        e.name = entry->name;
        e.data_type = entry->data_type;
      }
    } else if (e.index != 0 && e.index < 0x1000) {
      // A dummy-mapping gap (ETG.1000.6 §5.6.7.4.7): the index is the data type.
      e.data_type = e.index;
    }
    p.entries.push_back(std::move(e));
  }
  return p;
}

uint16_t pdo_bytes(const std::vector<PdoDescription>& pdos) {
  size_t bits = 0;
  for (const auto& p : pdos) {
    if (!p.assigned) continue;
    for (const auto& e : p.entries) bits += e.bit_length;
  }
  return static_cast<uint16_t>((bits + 7) / 8);
}

DeviceDescription describe_dictionary(const coe::ObjectDictionary& od, const DeviceTexts& texts,
                                      const SmPlan& plan) {
  DeviceDescription d;
  const auto* identity = od.find(0x1018);
  if (!identity) throw DescribeError("the dictionary has no identity object 0x1018");
  auto sub_u32 = [&](uint8_t sub) -> uint32_t {
    return identity->entry(sub) ? static_cast<uint32_t>(identity->get_u(sub)) : 0;
  };
  d.vendor_id = sub_u32(1);
  d.product_code = sub_u32(2);
  d.revision = sub_u32(3);
  d.serial = sub_u32(4);
  if (const auto* name = od.find(0x1008)) d.device_name = name->get_string(0);
  d.vendor_name = texts.vendor_name;
  d.order_code = texts.order_code;
  d.group_type = texts.group_type;
  d.group_name = texts.group_name;

  d.rx_pdos = describe_direction(od, kRxMappingFirst, kRxMappingLast, kRxAssign, 2);
  d.tx_pdos = describe_direction(od, kTxMappingFirst, kTxMappingLast, kTxAssign, 3);
  uint16_t out_bytes = pdo_bytes(d.rx_pdos);
  uint16_t in_bytes = pdo_bytes(d.tx_pdos);

  // SM0..SM3 in the fixed order masters expect (ETG.1000.6 §5.6.7.4.9, 0x1C00). A process-data
  // SM without data stays disabled, as the ESM then expects it.
  d.sms = {
      {SmType::MailboxOut, plan.mailbox_out_start, plan.mailbox_out_size, plan.mailbox_out_size,
       plan.mailbox_out_size, plan.mailbox_out_control, true},
      {SmType::MailboxIn, plan.mailbox_in_start, plan.mailbox_in_size, plan.mailbox_in_size,
       plan.mailbox_in_size, plan.mailbox_in_control, true},
      {SmType::ProcessOut, plan.outputs_start, out_bytes, 0, plan.max_process_data_bytes,
       plan.outputs_control, out_bytes > 0},
      {SmType::ProcessIn, plan.inputs_start, in_bytes, 0, plan.max_process_data_bytes,
       plan.inputs_control, in_bytes > 0},
  };
  d.foe = plan.foe;
  d.bootstrap = {plan.boot_out_start, plan.boot_out_size, plan.boot_in_start, plan.boot_in_size};
  // FMMU0 outputs, FMMU1 inputs, FMMU2 mailbox status (SOEM 2.x maps 0x080D with it).
  d.fmmus = {FmmuUsage::Outputs, FmmuUsage::Inputs, FmmuUsage::SmStatus};
  // The three synchronisation modes of 0x1C32:04 (ETG.1020 §8): free run, SM2 event, SYNC0.
  d.dc_modes = {
      {"FreeRun", "Free run (no synchronisation)", 0x0000, 0, 0, 0, 0, 0},
      {"SM-Synchron", "Synchronous with SM2 event", 0x0000, 0, 0, 0, 0, 0},
      {"DC", "DC SYNC0 synchronous", 0x0300, 0, 1, 0, 0, 0},
  };
  return d;
}

}  // namespace rackcat::esi
