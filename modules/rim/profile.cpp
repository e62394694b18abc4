#include "modules/rim/profile.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "coe/bits.hpp"
#include "mdp/card_catalogue.hpp"
#include "modules/canopen/frame.hpp"
#include "modules/cards/analog_scale.hpp"

namespace rackcat::modules::canopen {

namespace {

using mdp::Signal;

// Temperatures travel as INTEGER16 in 0.1 °C (-3276.7 .. +3276.7 °C covers type R's 1768 °C).
constexpr double kTemperatureScale = 10.0;

// "...-0007" -> 7; the RIM number when the serial has no trailing digits.
uint32_t serial_of(const mdp::Rim& r) {
  const std::string& s = r.serial_number;
  size_t i = s.size();
  while (i > 0 && s[i - 1] >= '0' && s[i - 1] <= '9') {
    --i;
  }
  if (i == s.size() || s.size() - i > 9) {
    return r.number;
  }
  return static_cast<uint32_t>(std::stoul(s.substr(i)));
}

void add_channels(std::vector<RimChannel>& list, uint8_t slot, uint8_t count, ChannelKind kind,
                  const mdp::CardType& card) {
  for (uint8_t ch = 0; ch < count; ++ch) {
    RimChannel c;
    c.slot = slot;
    c.channel = ch;
    c.kind = kind;
    c.min_v = card.min_voltage;
    c.max_v = card.max_voltage;
    list.push_back(c);
  }
}

// Lays out digital channels first (each card from a byte boundary), then the words.
void lay_out(std::vector<RimChannel>& list, size_t& bytes, size_t& words, size_t& total) {
  std::stable_partition(list.begin(), list.end(), [](const RimChannel& c) {
    return c.kind == ChannelKind::DigitalIn || c.kind == ChannelKind::DigitalOut;
  });
  size_t offset = 0;
  uint8_t last_slot = 0;
  bool open = false;
  for (RimChannel& c : list) {
    if (c.kind != ChannelKind::DigitalIn && c.kind != ChannelKind::DigitalOut) {
      continue;
    }
    if (open && (c.slot != last_slot || c.channel % 8 == 0)) {
      ++offset;  // a new card or the next 8 channels start a new byte
    }
    c.offset = static_cast<uint16_t>(offset);
    c.bit = static_cast<uint8_t>(c.channel % 8);
    last_slot = c.slot;
    open = true;
  }
  bytes = open ? offset + 1 : 0;
  size_t word_offset = (bytes + 1) & ~size_t{1};
  words = 0;
  for (RimChannel& c : list) {
    if (c.kind == ChannelKind::DigitalIn || c.kind == ChannelKind::DigitalOut) {
      continue;
    }
    c.offset = static_cast<uint16_t>(word_offset);
    word_offset += 2;
    ++words;
  }
  total = words ? word_offset : bytes;
}

coe::Object& add_array(coe::ObjectDictionary& od, uint16_t index, const char* name,
                       coe::DataType type, uint16_t bits, size_t count, uint16_t access) {
  coe::Object obj(index, coe::ObjectCode::Array, name, static_cast<uint16_t>(type));
  obj.add(coe::make_entry(0, "Number of entries", coe::DataType::Unsigned8, 8, coe::access::kRo,
                          std::vector<uint8_t>{static_cast<uint8_t>(count)}));
  for (size_t i = 1; i <= count; ++i) {
    obj.add(coe::make_entry(static_cast<uint8_t>(i), std::string(name) + " " + std::to_string(i),
                            type, bits, access));
  }
  obj.finalize();
  return od.add(std::move(obj));
}

void add_var(coe::ObjectDictionary& od, uint16_t index, const char* name, coe::DataType type,
             uint16_t bits, uint16_t access, std::vector<uint8_t> value) {
  coe::Object obj(index, coe::ObjectCode::Var, name, static_cast<uint16_t>(type));
  obj.add(coe::make_entry(0, name, type, bits, access, std::move(value)));
  obj.finalize();
  od.add(std::move(obj));
}

std::vector<uint8_t> le32(uint32_t v) {
  std::vector<uint8_t> b(4);
  le::put32(b.data(), v);
  return b;
}

// PDO communication (0x1400/0x1800 + k) and mapping (0x1600/0x1A00 + k) of one stream: the
// mapping lists the stream's objects in order, dummy UNSIGNED8 (0x0005) for the pad byte.
void add_pdo_objects(coe::ObjectDictionary& od, const RimProfile& p, bool transmit) {
  const size_t count = transmit ? p.tpdo_count() : p.rpdo_count();
  const size_t bytes = transmit ? p.di_bytes : p.do_bytes;
  const size_t words = transmit ? p.ai_words : p.ao_words;
  const uint16_t byte_index = transmit ? 0x6000 : 0x6200;
  const uint16_t word_index = transmit ? 0x6401 : 0x6411;
  // The stream as (index, subindex, bits) in order.
  std::vector<uint32_t> map;
  for (size_t i = 0; i < bytes; ++i) {
    map.push_back((uint32_t{byte_index} << 16) | ((i + 1) << 8) | 8);
  }
  if (words && (bytes & 1)) {
    map.push_back((uint32_t{0x0005} << 16) | 8);
  }
  for (size_t i = 0; i < words; ++i) {
    map.push_back((uint32_t{word_index} << 16) | ((i + 1) << 8) | 16);
  }
  size_t m = 0;
  for (size_t k = 0; k < count; ++k) {
    coe::Object comm(
        static_cast<uint16_t>((transmit ? 0x1800 : 0x1400) + k), coe::ObjectCode::Record,
        transmit ? "TPDO communication parameter" : "RPDO communication parameter", 0x0020);
    comm.add(coe::make_entry(0, "Highest sub-index supported", coe::DataType::Unsigned8, 8,
                             coe::access::kRo, std::vector<uint8_t>{2}));
    comm.add(coe::make_entry(1, "COB-ID", coe::DataType::Unsigned32, 32, coe::access::kRo,
                             le32(pdo_cob_id(transmit, k, p.rim))));
    comm.add(coe::make_entry(
        2, "Transmission type", coe::DataType::Unsigned8, 8, coe::access::kRo,
        std::vector<uint8_t>{0xFE}));  // event-driven (manufacturer-specific): cyclic here
    comm.finalize();
    od.add(std::move(comm));

    std::vector<uint32_t> entries;
    size_t bits = 0;
    while (m < map.size() && bits + (map[m] & 0xFF) <= kPdoBytes * 8) {
      bits += map[m] & 0xFF;
      entries.push_back(map[m++]);
    }
    coe::Object mapping(static_cast<uint16_t>((transmit ? 0x1A00 : 0x1600) + k),
                        coe::ObjectCode::Record,
                        transmit ? "TPDO mapping parameter" : "RPDO mapping parameter", 0x0021);
    mapping.add(coe::make_entry(0, "Number of mapped objects", coe::DataType::Unsigned8, 8,
                                coe::access::kRo,
                                std::vector<uint8_t>{static_cast<uint8_t>(entries.size())}));
    for (size_t i = 0; i < entries.size(); ++i) {
      mapping.add(
          coe::make_entry(static_cast<uint8_t>(i + 1), "Mapped object " + std::to_string(i + 1),
                          coe::DataType::Unsigned32, 32, coe::access::kRo, le32(entries[i])));
    }
    mapping.finalize();
    od.add(std::move(mapping));
  }
}

}  // namespace

const RimChannel* RimProfile::input(uint8_t slot, uint8_t channel) const {
  for (const RimChannel& c : inputs) {
    if (c.slot == slot && c.channel == channel) return &c;
  }
  return nullptr;
}

const RimChannel* RimProfile::output(uint8_t slot, uint8_t channel) const {
  for (const RimChannel& c : outputs) {
    if (c.slot == slot && c.channel == channel) return &c;
  }
  return nullptr;
}

RimProfile rim_profile(const mdp::RackConfig& rack, uint8_t rim) {
  const mdp::Rim* r = rack.rim(rim);
  if (!r) {
    throw std::invalid_argument("the rack file " + rack.source + " has no RIM " +
                                std::to_string(rim));
  }
  RimProfile p;
  p.rim = rim;
  p.identity.vendor_id = rack.control.vendor_id;
  // "FR" + RIM type: one product per RIM hardware variant.
  p.identity.product_code = 0x00465200u | static_cast<uint32_t>(r->type);
  p.identity.revision = rack.control.revision;
  p.identity.serial = serial_of(*r);
  p.device_name = r->part_number;
  p.software_version = r->firmware_version;
  for (const mdp::SlotCard& s : r->slots) {
    const mdp::CardType& card = *s.card;
    switch (card.signal) {
      case Signal::DigitalIn:
      case Signal::DigitalInInverted:
        add_channels(p.inputs, s.slot, card.channels, ChannelKind::DigitalIn, card);
        break;
      case Signal::DigitalOutSource:
      case Signal::DigitalOutSink:
      case Signal::DigitalOutOpto:
      case Signal::Relay:
      case Signal::RelayForceGuided:
        add_channels(p.outputs, s.slot, card.channels, ChannelKind::DigitalOut, card);
        break;
      case Signal::DigitalInOut:
        add_channels(p.inputs, s.slot, card.channels, ChannelKind::DigitalIn, card);
        add_channels(p.outputs, s.slot, card.channels, ChannelKind::DigitalOut, card);
        break;
      case Signal::AnalogIn:
        add_channels(p.inputs, s.slot, card.channels, ChannelKind::AnalogIn, card);
        break;
      case Signal::AnalogOut:
        add_channels(p.outputs, s.slot, card.channels, ChannelKind::AnalogOut, card);
        break;
      case Signal::Thermocouple:
      case Signal::Rtd:
        add_channels(p.inputs, s.slot, card.channels, ChannelKind::Temperature, card);
        break;
      case Signal::Uart:
      case Signal::Encoder:  // no CiA 401 channel kind: the encoder is not carried on the CAN link
        break;
    }
    const size_t at = p.card_list.size();
    p.card_list.resize(at + 4);
    le::put16(&p.card_list[at], s.slot);
    le::put16(&p.card_list[at + 2], card.card_id);
  }
  lay_out(p.inputs, p.di_bytes, p.ai_words, p.tx_bytes);
  lay_out(p.outputs, p.do_bytes, p.ao_words, p.rx_bytes);
  // PDO k >= 4 borrows the node-ID + 8 * (k / 4): it must stay a 7-bit node-ID.
  const size_t most = std::max(p.tpdo_count(), p.rpdo_count());
  if (rim > 7 || (most > 4 && rim + 8 * ((most - 1) / 4) > 127)) {
    throw std::invalid_argument(fmt::format(
        "RIM {} needs {} PDOs in one direction: the CAN RIM link carries at most {} for it", rim,
        most, rim > 7 ? 4 : 4 * ((127 - rim) / 8 + 1)));
  }
  return p;
}

uint32_t pdo_cob_id(bool transmit, size_t k, uint8_t node) {
  const auto& base = transmit ? cob::kTpdo : cob::kRpdo;
  return base[k % 4] + node + 8 * static_cast<uint32_t>(k / 4);
}

int pdo_number(bool transmit, uint32_t cob_id, uint8_t node) {
  const auto& base = transmit ? cob::kTpdo : cob::kRpdo;
  for (size_t i = 0; i < 4; ++i) {
    if (cob::function(cob_id) == base[i] || (cob_id >= base[i] && cob_id < base[i] + 0x80)) {
      const int rel = static_cast<int>(cob_id - base[i]) - node;
      if (rel >= 0 && rel % 8 == 0) {
        return static_cast<int>(i) + 4 * (rel / 8);
      }
      return -1;
    }
  }
  return -1;
}

uint16_t encode_channel(const RimChannel& c, double value) {
  switch (c.kind) {
    case ChannelKind::DigitalIn:
    case ChannelKind::DigitalOut:
      return value >= 0.5 ? 1 : 0;
    case ChannelKind::AnalogIn:
    case ChannelKind::AnalogOut:
      return AnalogScale{c.min_v, c.max_v}.to_code(value);
    case ChannelKind::Temperature: {
      if (std::isnan(value)) return 0;
      const double x = std::clamp(value * kTemperatureScale, -32767.0, 32767.0);
      return static_cast<uint16_t>(static_cast<int16_t>(x >= 0 ? x + 0.5 : x - 0.5));
    }
  }
  return 0;
}

double decode_channel(const RimChannel& c, uint16_t raw) {
  switch (c.kind) {
    case ChannelKind::DigitalIn:
    case ChannelKind::DigitalOut:
      return raw ? 1.0 : 0.0;
    case ChannelKind::AnalogIn:
    case ChannelKind::AnalogOut:
      return AnalogScale{c.min_v, c.max_v}.to_volts(raw);
    case ChannelKind::Temperature:
      return static_cast<int16_t>(raw) / kTemperatureScale;
  }
  return 0.0;
}

void put_channel(std::span<uint8_t> stream, const RimChannel& c, double value) {
  const uint16_t raw = encode_channel(c, value);
  if (c.kind == ChannelKind::DigitalIn || c.kind == ChannelKind::DigitalOut) {
    const auto mask = static_cast<uint8_t>(1u << c.bit);
    stream[c.offset] =
        static_cast<uint8_t>(raw ? (stream[c.offset] | mask) : (stream[c.offset] & ~mask));
  } else {
    le::put16(&stream[c.offset], raw);
  }
}

double get_channel(std::span<const uint8_t> stream, const RimChannel& c) {
  if (c.kind == ChannelKind::DigitalIn || c.kind == ChannelKind::DigitalOut) {
    return decode_channel(c, (stream[c.offset] >> c.bit) & 1);
  }
  return decode_channel(c, le::get16(&stream[c.offset]));
}

coe::ObjectDictionary rim_dictionary(const RimProfile& p, uint16_t heartbeat_ms,
                                     uint16_t consumer_ms) {
  using coe::DataType;
  namespace access = coe::access;
  coe::ObjectDictionary od;
  // CiA 401 device type: profile 401 in the low word, I/O functionality bits in the high word
  // (bit 16 digital inputs, 17 digital outputs, 18 analog inputs, 19 analog outputs).
  uint32_t device_type = 401;
  if (p.di_bytes) device_type |= 1u << 16;
  if (p.do_bytes) device_type |= 1u << 17;
  if (p.ai_words) device_type |= 1u << 18;
  if (p.ao_words) device_type |= 1u << 19;
  add_var(od, 0x1000, "Device type", DataType::Unsigned32, 32, access::kRo, le32(device_type));
  add_var(od, 0x1001, "Error register", DataType::Unsigned8, 8, access::kRo, {0});
  const std::string name = p.device_name.empty() ? "rackcat RIM" : p.device_name;
  add_var(od, 0x1008, "Manufacturer device name", DataType::VisibleString,
          static_cast<uint16_t>(8 * name.size()), access::kRo,
          std::vector<uint8_t>(name.begin(), name.end()));
  const std::string sw = p.software_version.empty() ? "1" : p.software_version;
  add_var(od, 0x100A, "Manufacturer software version", DataType::VisibleString,
          static_cast<uint16_t>(8 * sw.size()), access::kRo,
          std::vector<uint8_t>(sw.begin(), sw.end()));
  // 0x1016:01 consumer heartbeat time: bits 23..16 node-ID, 15..0 time in ms (CiA 301 §7.5.2.31).
  {
    coe::Object obj(0x1016, coe::ObjectCode::Array, "Consumer heartbeat time",
                    static_cast<uint16_t>(DataType::Unsigned32));
    obj.add(coe::make_entry(0, "Highest sub-index supported", DataType::Unsigned8, 8, access::kRo,
                            std::vector<uint8_t>{1}));
    obj.add(coe::make_entry(
        1, "Consumer heartbeat time 1", DataType::Unsigned32, 32, access::kRo,
        le32(consumer_ms ? (uint32_t{kControlModuleNode} << 16) | consumer_ms : 0)));
    obj.finalize();
    od.add(std::move(obj));
  }
  std::vector<uint8_t> hb(2);
  le::put16(hb.data(), heartbeat_ms);
  add_var(od, 0x1017, "Producer heartbeat time", DataType::Unsigned16, 16, access::kRw, hb);

  coe::Object id(0x1018, coe::ObjectCode::Record, "Identity object", 0x0023);
  id.add(coe::make_entry(0, "Highest sub-index supported", DataType::Unsigned8, 8, access::kRo,
                         std::vector<uint8_t>{4}));
  const uint32_t values[4] = {p.identity.vendor_id, p.identity.product_code, p.identity.revision,
                              p.identity.serial};
  const char* names[4] = {"Vendor-ID", "Product code", "Revision number", "Serial number"};
  for (uint8_t i = 0; i < 4; ++i) {
    id.add(coe::make_entry(static_cast<uint8_t>(i + 1), names[i], DataType::Unsigned32, 32,
                           access::kRo, le32(values[i])));
  }
  id.finalize();
  od.add(std::move(id));

  add_pdo_objects(od, p, false);
  add_pdo_objects(od, p, true);
  if (!p.card_list.empty()) {
    add_var(od, kCardListIndex, "Slot card list", DataType::OctetString,
            static_cast<uint16_t>(8 * p.card_list.size()), access::kRo, p.card_list);
  }
  if (p.di_bytes) {
    add_array(od, 0x6000, "Read input 8-bit", DataType::Unsigned8, 8, p.di_bytes,
              access::kRo | access::kTxPdoMappable);
  }
  if (p.do_bytes) {
    add_array(od, 0x6200, "Write output 8-bit", DataType::Unsigned8, 8, p.do_bytes,
              access::kRw | access::kRxPdoMappable);
  }
  if (p.ai_words) {
    add_array(od, 0x6401, "Read analog input 16-bit", DataType::Integer16, 16, p.ai_words,
              access::kRo | access::kTxPdoMappable);
  }
  if (p.ao_words) {
    add_array(od, 0x6411, "Write analog output 16-bit", DataType::Integer16, 16, p.ao_words,
              access::kRw | access::kRxPdoMappable);
  }
  return od;
}

void stream_to_objects(coe::ObjectDictionary& od, const RimProfile& p, bool transmit,
                       std::span<const uint8_t> stream) {
  const size_t bytes = transmit ? p.di_bytes : p.do_bytes;
  const size_t words = transmit ? p.ai_words : p.ao_words;
  if (coe::Object* o = bytes ? od.find(transmit ? 0x6000 : 0x6200) : nullptr) {
    for (size_t i = 0; i < bytes; ++i) {
      o->set_u(static_cast<uint8_t>(i + 1), stream[i]);
    }
  }
  if (coe::Object* o = words ? od.find(transmit ? 0x6401 : 0x6411) : nullptr) {
    const size_t base = (bytes + 1) & ~size_t{1};
    for (size_t i = 0; i < words; ++i) {
      o->set_u(static_cast<uint8_t>(i + 1), le::get16(&stream[base + 2 * i]));
    }
  }
}

}  // namespace rackcat::modules::canopen
