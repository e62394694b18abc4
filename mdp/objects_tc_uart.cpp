// Thermocouple and UART objects: 0x5nn4 ohms (guide §2.6 Table 11), 0x5nn5 UART configuration
// (§2.7 Table 12 — titled "0x5nn1" in the guide, it is 0x5nn5), 0x5nn6 UART information (§2.8
// Table 13, Appendix A types), 0x5nn7..0x5nnA Tx data and 0x5nnB..0x5nnE Rx data, and the
// enumerations 0x0800..0x0805 (Appendix A). "DTxxxxENnn" names the enum's bit size nn, so one
// channel of 0x5nn5 packs 2+4+2+2+1+2 bits plus the guide's pad_3 into 16 bits.
#include "mdp/card_catalogue.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;

struct EnumSpec {
  uint16_t index;
  const char* name;
  uint16_t bits;
  std::vector<const char*> values;
};

// Appendix A values. Where §2.7 disagrees (parity 1 = even, "31200" baud, flow control order in
// the 0x5nn5 description) the enumeration wins: it is what a master reads through SDO
// information and the ESI.
const std::vector<EnumSpec>& enum_specs() {
  static const std::vector<EnumSpec> specs{
      {0x0800,
       "DT0800EN04",
       4,
       {"1200 Baud", "2400 Baud", "4800 Baud", "9600 Baud", "19200 Baud", "31250 Baud",
        "38400 Baud", "57600 Baud", "115200 Baud"}},
      {0x0801, "DT0801EN02", 2, {"No Parity", "Odd Parity", "Even Parity"}},
      {0x0802, "DT0802EN01", 1, {"1 Stop Bit", "2 Stop Bits"}},
      {0x0803, "DT0803EN02", 2, {"5 Bits", "6 Bits", "7 Bits", "8 Bits"}},
      {0x0804, "DT0804EN02", 2, {"RS-232", "RS-485", "RS-485 with Termination Resistor"}},
      {0x0805, "DT0805EN02", 2, {"None", "Xon-Xoff", "RTS/CTS"}},
  };
  return specs;
}

struct UartField {
  const char* name;
  uint16_t enum_index;
  uint16_t bits;
  uint8_t def;
};
constexpr UartField kUartFields[] = {
    {"Interface", 0x0804, 2, 0}, {"Baud Rate", 0x0800, 4, 3}, {"Parity Mode", 0x0801, 2, 0},
    {"Data Bits", 0x0803, 2, 3}, {"Stop Bits", 0x0802, 1, 0}, {"Flow Control", 0x0805, 2, 0},
};

// The enumeration as an object of the data type area (ETG.1000.6 §5.6.7.4.4, indices
// 0x0800..0x0FFF; structure ENUM 0x0028): subindex 0 the number of values, subindex k one value as
// OCTET_STRING: the value as 32-bit little-endian integer followed by its text (no terminator).
// The entry's name is the text too, so SDO Information lists it readably.
Object enum_object(const EnumSpec& spec) {
  Object o(spec.index, ObjectCode::Record, spec.name, coe::record_type::kEnum);
  o.add(sub0(static_cast<uint8_t>(spec.values.size())));
  for (size_t i = 0; i < spec.values.size(); ++i) {
    const std::string_view text = spec.values[i];
    std::vector<uint8_t> value = le_bytes(i, 4);
    value.insert(value.end(), text.begin(), text.end());
    o.add(octets(static_cast<uint8_t>(i + 1), std::string(text),
                 static_cast<uint16_t>(value.size()), acc("ro"), value));
  }
  o.finalize();
  return o;
}

Object uart_config(const Module& m) {
  Object o(m.index(0x5000, 5), ObjectCode::Record, "UART Config", 0);
  o.set_packed(true);
  o.add(sub0(0x1B));
  uint8_t sub = 1;
  for (int ch = 0; ch < 4; ++ch) {
    for (const auto& f : kUartFields) {
      o.add(enum_entry(sub++, "Channel " + std::to_string(ch) + " " + f.name, f.enum_index, f.bits,
                       acc("ro,wr_preop"), f.def));
    }
    if (ch < 3) o.add(pad(sub++, 3));
  }
  o.finalize();
  return o;
}

Object uart_information(const Module& m) {
  Object o(m.index(0x5000, 6), ObjectCode::Record, "UART Information", 0);
  o.add(sub0(0x0C));
  for (uint8_t ch = 0; ch < 4; ++ch) {
    // Bit 0 transmit hold, bit 1 flush (Appendix A); other bits answer 0x06090031.
    o.add(ranged(static_cast<uint8_t>(0x01 + ch), "UART Control Channel " + std::to_string(ch),
                 DataType::Unsigned8, acc("rw"), 0, 0, 3));
  }
  for (uint8_t ch = 0; ch < 4; ++ch) {
    o.add(num(static_cast<uint8_t>(0x05 + ch), "UART Status Channel " + std::to_string(ch),
              DataType::Unsigned16, acc("ro") | kTx));
  }
  for (uint8_t ch = 0; ch < 4; ++ch) {
    o.add(num(static_cast<uint8_t>(0x09 + ch), "UART Error Details Channel " + std::to_string(ch),
              DataType::Unsigned8, acc("ro") | kTx));
  }
  o.finalize();
  return o;
}

// 0x5nn7..0x5nnE: ARRAY [1..255] OF USINT; subindex 0 is the number of bytes in the buffer.
// Tx data is written by the master (the driver sends subindex 1..n after a write); Rx data is
// filled by the driver before a read. The guide marks the Rx entries "rw" under an "ro" object;
// they are read-only here (received data is not written by the master).
Object uart_data(const Module& m, uint8_t nibble, bool tx, int channel) {
  const std::string name =
      std::string(tx ? "UART Tx Data Channel " : "UART Rx Data Channel ") + std::to_string(channel);
  Object o(m.index(0x5000, nibble), ObjectCode::Array, name,
           static_cast<uint16_t>(DataType::Unsigned8));
  const uint16_t a = tx ? acc("rw") : acc("ro");
  o.add(sub0(0, a));
  for (uint16_t s = 1; s <= 255; ++s) {
    o.add(
        num(static_cast<uint8_t>(s), tx ? "UART Tx Data" : "UART Rx Data", DataType::Unsigned8, a));
  }
  o.finalize();
  return o;
}

}  // namespace

void add_tc_uart_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  for (const auto& m : cfg.modules) {
    if (m.card->thermocouple_ohms) {
      Object o(m.index(0x5000, 4), ObjectCode::Array, "Thermocouple Info",
               static_cast<uint16_t>(DataType::Unsigned16));
      o.add(sub0(m.card->channels));
      for (uint8_t c = 1; c <= m.card->channels; ++c) {
        // Guide §2.6: "The value reported is in Ohms".
        o.add(with_unit(
            num(c, "Ohms[" + std::to_string(c) + "]", DataType::Unsigned16, acc("ro") | kTx),
            coe::unit::kOhms));
      }
      od.add(std::move(o));
    }
    if (m.card->uart) {
      od.add(uart_config(m));
      od.add(uart_information(m));
      for (int ch = 0; ch < 4; ++ch) od.add(uart_data(m, static_cast<uint8_t>(7 + ch), true, ch));
      for (int ch = 0; ch < 4; ++ch)
        od.add(uart_data(m, static_cast<uint8_t>(0xB + ch), false, ch));
    }
  }
  // The enumerations are always described, so the ESI of any rack can carry the UART module.
  for (const auto& spec : enum_specs()) {
    coe::EnumType t;
    t.index = spec.index;
    t.name = spec.name;
    t.bit_size = spec.bits;
    for (size_t i = 0; i < spec.values.size(); ++i) {
      t.values.push_back({static_cast<int64_t>(i), spec.values[i]});
    }
    od.add_enum(std::move(t));
    od.add(enum_object(spec));
  }
}

}  // namespace rackcat::mdp
