#include "tests/esi/sample_dictionary.hpp"

#include <string>

#include "coe/access.hpp"
#include "coe/data_type.hpp"

namespace rackcat::esi::testing {
namespace {

using coe::DataType;
using coe::Entry;
using coe::Object;
using coe::ObjectCode;
namespace access = coe::access;

std::vector<uint8_t> le(uint64_t v, size_t n) {
  std::vector<uint8_t> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = static_cast<uint8_t>(v >> (8 * i));
  return out;
}

Entry entry(uint8_t sub, std::string name, DataType t, uint16_t acc, uint64_t value = 0,
            uint16_t bits = 0) {
  Entry e;
  e.subindex = sub;
  e.name = std::move(name);
  e.data_type = static_cast<uint16_t>(t);
  e.access = acc;
  e.bit_length = bits;
  uint16_t size = bits ? bits : coe::fixed_bit_size(t).value_or(8);
  e.default_value = le(value, (size + 7u) / 8u);
  return e;
}

Entry sub0(uint8_t count, uint16_t acc = access::kRo) {
  return entry(0, "SubIndex 000", DataType::Unsigned8, acc, count);
}

void mapping(coe::ObjectDictionary& od, uint16_t index, const char* name,
             std::vector<uint32_t> entries) {
  Object o(index, ObjectCode::Record, name);
  o.add(sub0(static_cast<uint8_t>(entries.size()), access::kRoWrPreOp));
  uint8_t sub = 1;
  for (uint32_t v : entries) {
    o.add(
        entry(sub, "SubIndex " + std::to_string(sub), DataType::Unsigned32, access::kRoWrPreOp, v));
    ++sub;
  }
  od.add(std::move(o));
}

}  // namespace

coe::ObjectDictionary sample_dictionary() {
  coe::ObjectDictionary od;
  {
    Object o(0x1000, ObjectCode::Var, "Device type", static_cast<uint16_t>(DataType::Unsigned32));
    o.add(entry(0, "Device type", DataType::Unsigned32, access::kRo, 0x00001389));
    od.add(std::move(o));
  }
  {
    Object o(0x1008, ObjectCode::Var, "Device name",
             static_cast<uint16_t>(DataType::VisibleString));
    Entry e;
    e.name = "Device name";
    e.data_type = static_cast<uint16_t>(DataType::VisibleString);
    e.access = access::kRo;
    std::string text = "Sample rack";
    e.default_value.assign(text.begin(), text.end());
    e.default_value.resize(16, 0);
    e.bit_length = 128;
    o.add(std::move(e));
    od.add(std::move(o));
  }
  {
    Object o(0x1018, ObjectCode::Record, "Identity");
    o.add(sub0(4));
    o.add(entry(1, "Vendor ID", DataType::Unsigned32, access::kRo, kVendor));
    o.add(entry(2, "Product code", DataType::Unsigned32, access::kRo, kProduct));
    o.add(entry(3, "Revision", DataType::Unsigned32, access::kRo, kRevision));
    o.add(entry(4, "Serial number", DataType::Unsigned32, access::kRo, kSerial));
    od.add(std::move(o));
  }
  // Module 1: 16 digital outputs (RxPDO 0x1600) and 8 analog inputs + status (TxPDO 0x1A00);
  // module 2: a packed BIT4 input with a 4-bit padding gap (TxPDO 0x1A01, not assigned).
  mapping(od, 0x1600, "RxPDO Mapping (DOUTx16)", {0x70000110});
  mapping(od, 0x1A00, "TxPDO Mapping (AINx8)",
          {0x60020110, 0x60020210, 0x60020310, 0x60020410, 0x00000008});
  mapping(od, 0x1A01, "TxPDO Mapping (DINx4)", {0x601B0104, 0x601B0204, 0x00000008});
  {
    Object o(0x1C12, ObjectCode::Array, "Sync manager 2 PDO assignment",
             static_cast<uint16_t>(DataType::Unsigned16));
    o.add(sub0(1, access::kRoWrPreOp));
    o.add(entry(1, "SubIndex 001", DataType::Unsigned16, access::kRoWrPreOp, 0x1600));
    od.add(std::move(o));
  }
  {
    Object o(0x1C13, ObjectCode::Array, "Sync manager 3 PDO assignment",
             static_cast<uint16_t>(DataType::Unsigned16));
    o.add(sub0(1, access::kRoWrPreOp));
    o.add(entry(1, "SubIndex 001", DataType::Unsigned16, access::kRoWrPreOp, 0x1A00));
    o.add(entry(2, "SubIndex 002", DataType::Unsigned16, access::kRoWrPreOp, 0x1A01));
    o.finalize();
    o.image()[0] = 1;  // one of two slots in use
    od.add(std::move(o));
  }
  od.add_enum({0x0800, "DT0800EN02", 8, {{0, "RS-232"}, {1, "RS-485"}}});
  {
    Object o(0x5004, ObjectCode::Var, "Interface", 0x0800);
    Entry e;
    e.name = "Interface";
    e.data_type = 0x0800;
    e.bit_length = 8;
    e.access = access::kRoWrPreOp;
    e.default_value = {1};
    o.add(std::move(e));
    od.add(std::move(o));
  }
  {
    Object o(0x6002, ObjectCode::Array, "AINx8", static_cast<uint16_t>(DataType::Integer16));
    o.add(sub0(4));
    for (uint8_t s = 1; s <= 4; ++s)
      o.add(entry(s, "AIN[" + std::to_string(s) + "]", DataType::Integer16,
                  access::kRo | access::kTxPdoMappable, 100u * s));
    od.add(std::move(o));
  }
  {
    Object o(0x601B, ObjectCode::Record, "DINx4");
    o.set_packed(true);
    o.add(sub0(2));
    o.add(entry(1, "DIN[1..0]", DataType::Bit4, access::kRo | access::kTxPdoMappable, 0x5));
    o.add(entry(2, "DIN[3..2]", DataType::Bit4, access::kRo | access::kTxPdoMappable, 0xA));
    Entry pad = entry(3, "Padding", DataType::Bit8, access::kRo, 0);
    pad.padding = true;
    o.add(std::move(pad));
    od.add(std::move(o));
  }
  {
    Object o(0x7000, ObjectCode::Var, "DOUTx16", static_cast<uint16_t>(DataType::Unsigned16));
    // Readable in SAFEOP and OP only, written by the master in OP only.
    o.add(entry(0, "DOUT[15..0]", DataType::Unsigned16,
                access::kReadSafeOp | access::kReadOp | access::kWriteOp | access::kRxPdoMappable));
    od.add(std::move(o));
  }
  {
    Object o(0x2000, ObjectCode::Record, "Control module");
    o.add(sub0(2));
    Entry ip;
    ip.subindex = 1;
    ip.name = "IP address";
    ip.data_type = static_cast<uint16_t>(DataType::VisibleString);
    ip.bit_length = 16 * 8;
    ip.access = access::kRw | access::kBackup;
    std::string text = "192.168.9.50";
    ip.default_value.assign(text.begin(), text.end());
    ip.default_value.resize(16, 0);
    o.add(std::move(ip));
    o.add(entry(2, "Command", DataType::Unsigned8, access::kWo, 0));
    od.add(std::move(o));
  }
  return od;
}

DeviceTexts sample_texts() {
  return {"rackcat test vendor", "FI-CM0100-00", "FusionIO", "Fusion.IO racks"};
}

}  // namespace rackcat::esi::testing
