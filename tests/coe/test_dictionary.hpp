// The object dictionary every coe test runs against: standard objects (ETG.1000.6 §5.6.7.4)
// plus objects exercising each check of the SDO server.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "coe/object_dictionary.hpp"

namespace rackcat::coe::test {

inline std::vector<uint8_t> le(uint64_t v, size_t n) {
  std::vector<uint8_t> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = static_cast<uint8_t>(v >> (8 * i));
  return out;
}

inline Entry entry(uint8_t sub, std::string name, DataType type, uint16_t bits, uint16_t acc,
                   std::vector<uint8_t> def = {}) {
  return make_entry(sub, std::move(name), type, bits, acc, std::move(def));
}

inline Object var(uint16_t index, std::string name, DataType type, uint16_t bits, uint16_t acc,
                  std::vector<uint8_t> def = {}) {
  Object o(index, ObjectCode::Var, name, static_cast<uint16_t>(type));
  o.add(entry(0, name, type, bits, acc, std::move(def)));
  o.finalize();
  return o;
}

// An ARRAY of `n` entries of `type`, subindex 0 access `sub0_acc`, entries `acc`.
inline Object array(uint16_t index, std::string name, DataType type, uint16_t bits, uint8_t n,
                    uint16_t sub0_acc, uint16_t acc, const std::vector<uint64_t>& values,
                    uint8_t in_use) {
  Object o(index, ObjectCode::Array, name, static_cast<uint16_t>(type));
  o.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, sub0_acc, {in_use}));
  for (uint8_t i = 1; i <= n; ++i) {
    const uint64_t v = i <= values.size() ? values[i - 1] : 0;
    o.add(entry(i, "SubIndex " + std::to_string(i), type, bits, acc, le(v, (bits + 7) / 8)));
  }
  o.finalize();
  return o;
}

inline ObjectDictionary make_test_dictionary() {
  using namespace access;
  ObjectDictionary od;
  od.add(var(0x1000, "Device type", DataType::Unsigned32, 32, kRo, le(0x00001389, 4)));
  od.add(var(0x1001, "Error register", DataType::Unsigned8, 8, kRo));
  {
    std::vector<uint8_t> name(16, 0);
    std::string text = "rackcat";
    std::copy(text.begin(), text.end(), name.begin());
    od.add(var(0x1008, "Manufacturer device name", DataType::VisibleString, 128, kRo, name));
  }
  {
    Object o(0x1018, ObjectCode::Record, "Identity", 0x0023);
    o.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, kRo, {4}));
    o.add(entry(1, "Vendor ID", DataType::Unsigned32, 32, kRo, le(0x00000A0B, 4)));
    o.add(entry(2, "Product code", DataType::Unsigned32, 32, kRo, le(0x12345678, 4)));
    o.add(entry(3, "Revision", DataType::Unsigned32, 32, kRo, le(0x00010002, 4)));
    o.add(entry(4, "Serial number", DataType::Unsigned32, 32, kRo, le(0xCAFEBABE, 4)));
    od.add(std::move(o));
  }
  // PDO mapping and assignment (ETG.1000.6 §5.6.7.4.7 - .9).
  {
    Object o = array(0x1600, "RxPDO 1", DataType::Unsigned32, 32, 4, kRoWrPreOp, kRoWrPreOp,
                     {0x70000110, 0x70000208}, 2);
    od.add(std::move(o));
  }
  od.add(array(0x1A00, "TxPDO 1", DataType::Unsigned32, 32, 4, kRoWrPreOp, kRoWrPreOp,
               {0x60000101, 0x60000201, 0x00000006, 0x60000410}, 4));
  od.add(array(0x1C12, "RxPDO assign", DataType::Unsigned16, 16, 4, kRoWrPreOp, kRoWrPreOp,
               {0x1600}, 1));
  od.add(array(0x1C13, "TxPDO assign", DataType::Unsigned16, 16, 4, kRoWrPreOp, kRoWrPreOp,
               {0x1A00}, 1));
  // Application objects.
  {
    Object o(0x2000, ObjectCode::Var, "Percent", static_cast<uint16_t>(DataType::Unsigned8));
    Entry e = entry(0, "Percent", DataType::Unsigned8, 8, kRw, {50});
    e.min = 1;
    e.max = 100;
    o.add(e);
    od.add(std::move(o));
  }
  {
    Object o(0x2001, ObjectCode::Var, "Signed limited", static_cast<uint16_t>(DataType::Integer16));
    Entry e = entry(0, "Signed limited", DataType::Integer16, 16, kRw, le(0, 2));
    e.min = -100;
    e.max = 100;
    o.add(e);
    od.add(std::move(o));
  }
  {
    std::vector<uint8_t> text(255);
    for (size_t i = 0; i < text.size(); ++i) text[i] = static_cast<uint8_t>('A' + i % 26);
    od.add(var(0x2002, "Long text", DataType::VisibleString, 255 * 8, kRw, text));
  }
  od.add(var(0x2003, "Written in OP", DataType::Unsigned32, 32, kRoWrOp));
  od.add(var(0x2004, "Write only", DataType::Unsigned16, 16, kWo));
  {
    EnumType baud{0x0800, "DT0800EN04", 8, {}};
    const char* names[] = {"1200 Baud",  "2400 Baud",  "4800 Baud",  "9600 Baud",  "19200 Baud",
                           "31250 Baud", "38400 Baud", "57600 Baud", "115200 Baud"};
    for (int i = 0; i < 9; ++i) baud.values.push_back({i, names[i]});
    od.add_enum(baud);
    Object o(0x2005, ObjectCode::Var, "Baud rate", 0x0800);
    Entry e = entry(0, "Baud rate", DataType::Unsigned8, 8, kRoWrPreOp, {3});
    e.data_type = 0x0800;
    o.add(e);
    od.add(std::move(o));
  }
  {
    // A RECORD with gaps: two BOOLs packed at bits 16/17, a padding entry (bits 18..23), an
    // unused byte (bits 24..31, an explicit offset) and a UINT16 at bit 32.
    Object o(0x6000, ObjectCode::Record, "Inputs");
    o.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, kRo, {4}));
    o.add(entry(1, "Input 1", DataType::Boolean, 1, kRo | kTxPdoMappable));
    o.add(entry(2, "Input 2", DataType::Boolean, 1, kRo | kTxPdoMappable));
    Entry pad = entry(3, "", DataType::Bit6, 6, 0);
    pad.padding = true;
    o.add(pad);
    Entry value = entry(4, "Counter", DataType::Unsigned16, 16, kRo | kTxPdoMappable);
    value.bit_offset = 32;
    o.add(value);
    o.finalize();
    od.add(std::move(o));
  }
  {
    Object o(0x7000, ObjectCode::Record, "Outputs");
    o.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, kRo, {2}));
    o.add(entry(1, "Output word", DataType::Unsigned16, 16, kRw | kRxPdoMappable));
    o.add(entry(2, "Output byte", DataType::Unsigned8, 8, kRw | kRxPdoMappable));
    od.add(std::move(o));
  }
  {
    // Paired limits (0x06090036): subindex 1 is the minimum of subindex 2.
    Object o(0x2008, ObjectCode::Record, "Limits");
    o.add(entry(0, "SubIndex 000", DataType::Unsigned8, 8, kRo, {2}));
    Entry lo = entry(1, "Low", DataType::Integer16, 16, kRw, le(10, 2));
    lo.min_of = 2;
    Entry hi = entry(2, "High", DataType::Integer16, 16, kRw, le(20, 2));
    hi.max_of = 1;
    o.add(lo);
    o.add(hi);
    od.add(std::move(o));
  }
  od.add(var(0x2009, "Hooked", DataType::Unsigned8, 8, kRw));
  od.add(var(0x200A, "Preop only", DataType::Unsigned32, 32, kRoWrPreOp));
  {
    // 100 x UDINT: 402 bytes in a complete access, segmented both ways.
    std::vector<uint64_t> values;
    for (uint64_t i = 0; i < 100; ++i) values.push_back(0x01000000u + i);
    od.add(array(0x8000, "Table", DataType::Unsigned32, 32, 100, kRw, kRw, values, 100));
  }
  od.add(var(0x2010, "Flag", DataType::Boolean, 1, kRw));
  {
    Object o(0x200B, ObjectCode::Var, "Settings value",
             static_cast<uint16_t>(DataType::Unsigned16));
    o.add(entry(0, "Settings value", DataType::Unsigned16, 16, kRw | kBackup | kSettings));
    od.add(std::move(o));
  }
  return od;
}

}  // namespace rackcat::coe::test
