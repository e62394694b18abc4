#include "esi/sii_parser.hpp"

#include <fmt/format.h>

#include "base/little_endian.hpp"
#include "esi/sii_crc.hpp"
#include "esi/sii_image.hpp"

namespace rackcat::esi {
namespace {

using Bytes = std::span<const uint8_t>;

[[noreturn]] void fail(const std::string& message) {
  throw SiiParseError(message);
}

const char* category_name(uint16_t type) {
  switch (type) {
    case sii::kCatStrings:
      return "Strings";
    case sii::kCatDataTypes:
      return "DataTypes";
    case sii::kCatGeneral:
      return "General";
    case sii::kCatFmmu:
      return "FMMU";
    case sii::kCatSyncManager:
      return "SyncManager";
    case sii::kCatTxPdo:
      return "TxPDO";
    case sii::kCatRxPdo:
      return "RxPDO";
    case sii::kCatDc:
      return "DC";
    default:
      return "vendor/unknown";
  }
}

void parse_strings(Bytes body, uint16_t at, SiiInfo& info) {
  if (body.empty()) fail(fmt::format("Strings category at word 0x{:04X} is empty", at));
  size_t count = body[0];
  size_t pos = 1;
  for (size_t i = 0; i < count; ++i) {
    if (pos >= body.size() || pos + 1 + body[pos] > body.size()) {
      fail(
          fmt::format("Strings category at word 0x{:04X}: string {} of {} runs past the "
                      "category ({} bytes)",
                      at, i + 1, count, body.size()));
    }
    size_t len = body[pos];
    info.strings.emplace_back(reinterpret_cast<const char*>(body.data() + pos + 1), len);
    pos += 1 + len;
  }
}

void parse_general(Bytes body, uint16_t at, SiiInfo& info) {
  // Bytes 0..19 carry every field we read; older devices may omit the reserved tail.
  if (body.size() < 20) {
    fail(fmt::format("General category at word 0x{:04X} is {} bytes, needs at least 20", at,
                     body.size()));
  }
  auto& g = info.general;
  g.group_idx = body[0];
  g.image_idx = body[1];
  g.order_idx = body[2];
  g.name_idx = body[3];
  g.coe_details = body[5];
  g.foe_details = body[6];
  g.eoe_details = body[7];
  g.soe_channels = body[8];
  g.ds402_channels = body[9];
  g.sysman_class = body[10];
  g.flags = body[11];
  g.ebus_current_ma = static_cast<int16_t>(le::get16(&body[12]));
  g.physical_ports = le::get16(&body[16]);
  g.physical_memory_address = le::get16(&body[18]);
  info.has_general = true;
}

void parse_sms(Bytes body, uint16_t at, SiiInfo& info) {
  if (body.size() % 8) {
    fail(fmt::format("SyncManager category at word 0x{:04X} is {} bytes, not a multiple of 8", at,
                     body.size()));
  }
  for (size_t pos = 0; pos < body.size(); pos += 8) {
    SiiSyncManager sm;
    sm.start = le::get16(&body[pos]);
    sm.length = le::get16(&body[pos + 2]);
    sm.control = body[pos + 4];
    sm.status = body[pos + 5];
    sm.enable = body[pos + 6];
    sm.type = body[pos + 7];
    info.sms.push_back(sm);
  }
}

void parse_pdos(Bytes body, uint16_t at, uint16_t type, std::vector<SiiPdo>& out) {
  size_t pos = 0;
  // A category is padded to whole words; fewer than 8 bytes left cannot start a PDO.
  while (pos + 8 <= body.size()) {
    SiiPdo p;
    p.index = le::get16(&body[pos]);
    size_t n = body[pos + 2];
    p.sm = body[pos + 3];
    p.synchronization = body[pos + 4];
    p.name_idx = body[pos + 5];
    p.flags = le::get16(&body[pos + 6]);
    pos += 8;
    if (pos + 8 * n > body.size()) {
      fail(
          fmt::format("{} category at word 0x{:04X}: PDO 0x{:04X} declares {} entries, which "
                      "run past the category ({} bytes)",
                      category_name(type), at, p.index, n, body.size()));
    }
    for (size_t i = 0; i < n; ++i, pos += 8) {
      SiiPdoEntry e;
      e.index = le::get16(&body[pos]);
      e.subindex = body[pos + 2];
      e.name_idx = body[pos + 3];
      e.data_type = body[pos + 4];
      e.bit_length = body[pos + 5];
      e.flags = le::get16(&body[pos + 6]);
      p.entries.push_back(e);
    }
    out.push_back(std::move(p));
  }
  if (pos != body.size()) {
    fail(fmt::format("{} category at word 0x{:04X}: {} trailing bytes after the last PDO",
                     category_name(type), at, body.size() - pos));
  }
}

void parse_dc(Bytes body, uint16_t at, SiiInfo& info) {
  if (body.size() % 24) {
    fail(fmt::format("DC category at word 0x{:04X} is {} bytes, not a multiple of 24", at,
                     body.size()));
  }
  for (size_t pos = 0; pos < body.size(); pos += 24) {
    SiiDcMode m;
    m.cycle_time_sync0 = le::get32(&body[pos]);
    m.shift_time_sync0 = static_cast<int32_t>(le::get32(&body[pos + 4]));
    m.shift_time_sync1 = static_cast<int32_t>(le::get32(&body[pos + 8]));
    m.cycle_time_sync1_factor = static_cast<int16_t>(le::get16(&body[pos + 12]));
    m.assign_activate = le::get16(&body[pos + 14]);
    m.cycle_time_sync0_factor = static_cast<int16_t>(le::get16(&body[pos + 16]));
    m.name_idx = body[pos + 18];
    m.description_idx = body[pos + 19];
    info.dc_modes.push_back(m);
  }
}

}  // namespace

std::string SiiInfo::string(uint8_t idx) const {
  if (idx == 0 || idx > strings.size()) return {};
  return strings[idx - 1u];
}

SiiInfo parse_sii(std::span<const uint8_t> image) {
  constexpr size_t kHeaderBytes = sii::kFirstCategory * 2u;
  if (image.size() > sii::kMaxBytes) {
    fail(
        fmt::format("image is {} bytes, more than the {} bytes (64 Ki words) the SII address "
                    "space holds",
                    image.size(), sii::kMaxBytes));
  }
  if (image.size() % 2) fail(fmt::format("image is {} bytes, not whole words", image.size()));
  if (image.size() < kHeaderBytes) {
    fail(fmt::format("image is {} bytes; words 0x00-0x3F alone need {}", image.size(),
                     kHeaderBytes));
  }
  SiiInfo info;
  auto w = [&](uint16_t address) { return le::get16(&image[2u * address]); };
  auto dw = [&](uint16_t address) { return le::get32(&image[2u * address]); };
  info.pdi_control = w(sii::kPdiControl);
  info.pdi_config = w(sii::kPdiConfig);
  info.sync_impulse_length = w(sii::kSyncImpulseLength);
  info.extended_pdi_config = w(sii::kExtendedPdiConfig);
  info.station_alias = w(sii::kStationAlias);
  info.checksum = static_cast<uint8_t>(w(sii::kChecksum));
  uint8_t expected = sii_crc8(image.first(14));
  if (info.checksum != expected) {
    fail(
        fmt::format("configuration area CRC mismatch: word 0x0007 holds 0x{:02X}, CRC-8 of "
                    "words 0x00-0x06 is 0x{:02X}",
                    info.checksum, expected));
  }
  info.vendor_id = dw(sii::kVendorId);
  info.product_code = dw(sii::kProductCode);
  info.revision = dw(sii::kRevision);
  info.serial = dw(sii::kSerial);
  info.bootstrap_receive_offset = w(sii::kBootstrapReceiveOffset);
  info.bootstrap_receive_size = w(sii::kBootstrapReceiveSize);
  info.bootstrap_send_offset = w(sii::kBootstrapSendOffset);
  info.bootstrap_send_size = w(sii::kBootstrapSendSize);
  info.standard_receive_offset = w(sii::kStandardReceiveOffset);
  info.standard_receive_size = w(sii::kStandardReceiveSize);
  info.standard_send_offset = w(sii::kStandardSendOffset);
  info.standard_send_size = w(sii::kStandardSendSize);
  info.mailbox_protocol = w(sii::kMailboxProtocol);
  info.size_kbit_minus_one = w(sii::kSize);
  info.version = w(sii::kVersion);

  const size_t words = image.size() / 2;
  size_t at = sii::kFirstCategory;
  for (;;) {
    if (at + 1 > words) {
      fail(
          fmt::format("no End category (0xFFFF): the category list runs to the end of the "
                      "image at word 0x{:04X}",
                      words));
    }
    uint16_t type = w(static_cast<uint16_t>(at));
    if (type == sii::kCatEnd) break;
    if (at + 2 > words) {
      fail(
          fmt::format("category {} header at word 0x{:04X} runs past the end of the image "
                      "({} words)",
                      type, at, words));
    }
    uint16_t length = w(static_cast<uint16_t>(at + 1));
    if (at + 2 + length > words) {
      fail(
          fmt::format("{} category (type {}) at word 0x{:04X} declares {} words and runs past "
                      "the end of the image ({} words)",
                      category_name(type), type, at, length, words));
    }
    auto header_at = static_cast<uint16_t>(at);
    info.categories.push_back({type, header_at, length});
    Bytes body = image.subspan(2 * (at + 2), 2u * length);
    switch (type) {
      case sii::kCatStrings:
        parse_strings(body, header_at, info);
        break;
      case sii::kCatGeneral:
        parse_general(body, header_at, info);
        break;
      case sii::kCatFmmu:
        info.fmmus.assign(body.begin(), body.end());
        break;
      case sii::kCatSyncManager:
        parse_sms(body, header_at, info);
        break;
      case sii::kCatTxPdo:
        parse_pdos(body, header_at, type, info.tx_pdos);
        break;
      case sii::kCatRxPdo:
        parse_pdos(body, header_at, type, info.rx_pdos);
        break;
      case sii::kCatDc:
        parse_dc(body, header_at, info);
        break;
      default:
        break;  // vendor-specific or unknown categories are skipped, as masters do
    }
    at += 2u + length;
  }
  return info;
}

namespace {

const char* sm_type_name(uint8_t t) {
  switch (t) {
    case 1:
      return "mailbox out";
    case 2:
      return "mailbox in";
    case 3:
      return "process data out";
    case 4:
      return "process data in";
    default:
      return "unused";
  }
}

const char* fmmu_name(uint8_t f) {
  switch (f) {
    case 1:
      return "outputs";
    case 2:
      return "inputs";
    case 3:
      return "SM status";
    default:
      return "unused";
  }
}

void format_pdos(std::string& out, const char* title, const std::vector<SiiPdo>& pdos,
                 const SiiInfo& info) {
  for (const auto& p : pdos) {
    out += fmt::format("{} 0x{:04X} \"{}\" SM{} flags 0x{:04X}, {} entries\n", title, p.index,
                       info.string(p.name_idx), p.sm, p.flags, p.entries.size());
    for (const auto& e : p.entries) {
      out += fmt::format("    0x{:04X}:{:02X} {:>2} bit type 0x{:02X} \"{}\"\n", e.index,
                         e.subindex, e.bit_length, e.data_type, info.string(e.name_idx));
    }
  }
}

}  // namespace

std::string format_sii(const SiiInfo& s) {
  std::string out;
  out += fmt::format("ESC configuration area (words 0x00-0x07)\n");
  out += fmt::format("  PDI control        0x{:04X}\n", s.pdi_control);
  out += fmt::format("  PDI configuration  0x{:04X}\n", s.pdi_config);
  out += fmt::format("  SYNC impulse       {} x 10 ns\n", s.sync_impulse_length);
  out += fmt::format("  extended PDI conf  0x{:04X}\n", s.extended_pdi_config);
  out += fmt::format("  station alias      0x{:04X}\n", s.station_alias);
  out += fmt::format("  checksum           0x{:02X} (valid)\n", s.checksum);
  out += fmt::format(
      "Identity\n  vendor 0x{:08X} product 0x{:08X} revision 0x{:08X} serial "
      "0x{:08X}\n",
      s.vendor_id, s.product_code, s.revision, s.serial);
  out += fmt::format("Mailbox\n  bootstrap receive 0x{:04X}/{} send 0x{:04X}/{}\n",
                     s.bootstrap_receive_offset, s.bootstrap_receive_size, s.bootstrap_send_offset,
                     s.bootstrap_send_size);
  out +=
      fmt::format("  standard  receive 0x{:04X}/{} send 0x{:04X}/{}\n", s.standard_receive_offset,
                  s.standard_receive_size, s.standard_send_offset, s.standard_send_size);
  std::string protocols;
  static constexpr std::pair<uint16_t, const char*> kProtocols[] = {
      {sii::kProtoAoE, "AoE"}, {sii::kProtoEoE, "EoE"}, {sii::kProtoCoE, "CoE"},
      {sii::kProtoFoE, "FoE"}, {sii::kProtoSoE, "SoE"}, {sii::kProtoVoE, "VoE"}};
  for (auto [bit, name] : kProtocols)
    if (s.mailbox_protocol & bit) protocols += std::string(protocols.empty() ? "" : " ") + name;
  out += fmt::format("  protocols 0x{:04X} ({})\n", s.mailbox_protocol, protocols);
  out += fmt::format("EEPROM size {} Kbit, SII version {}\n", s.size_kbit_minus_one + 1, s.version);
  out += "Categories\n";
  for (const auto& c : s.categories) {
    out += fmt::format("  word 0x{:04X} {:<12} (type {:>2}) {} words\n", c.word_address,
                       category_name(c.type), c.type, c.length_words);
  }
  out += fmt::format("Strings ({})\n", s.strings.size());
  for (size_t i = 0; i < s.strings.size(); ++i)
    out += fmt::format("  {:>3} \"{}\"\n", i + 1, s.strings[i]);
  if (s.has_general) {
    const auto& g = s.general;
    out += "General\n";
    out += fmt::format("  group \"{}\" order \"{}\" name \"{}\"\n", s.string(g.group_idx),
                       s.string(g.order_idx), s.string(g.name_idx));
    out += fmt::format(
        "  CoE details 0x{:02X} (SDO {} SDO info {} PDO assign {} PDO config {} complete "
        "access {})\n",
        g.coe_details, (g.coe_details & sii::kCoeSdo) ? 1 : 0,
        (g.coe_details & sii::kCoeSdoInfo) ? 1 : 0, (g.coe_details & sii::kCoePdoAssign) ? 1 : 0,
        (g.coe_details & sii::kCoePdoConfig) ? 1 : 0,
        (g.coe_details & sii::kCoeCompleteAccess) ? 1 : 0);
    out += fmt::format("  flags 0x{:02X} current {} mA physical ports 0x{:04X}\n", g.flags,
                       g.ebus_current_ma, g.physical_ports);
  }
  out += "FMMU\n";
  for (size_t i = 0; i < s.fmmus.size(); ++i)
    out += fmt::format("  FMMU{} {}\n", i, fmmu_name(s.fmmus[i]));
  out += "SyncManager\n";
  for (size_t i = 0; i < s.sms.size(); ++i) {
    const auto& sm = s.sms[i];
    out += fmt::format("  SM{} start 0x{:04X} length {} control 0x{:02X} enable 0x{:02X} {}\n", i,
                       sm.start, sm.length, sm.control, sm.enable, sm_type_name(sm.type));
  }
  format_pdos(out, "TxPDO", s.tx_pdos, s);
  format_pdos(out, "RxPDO", s.rx_pdos, s);
  for (const auto& m : s.dc_modes) {
    out +=
        fmt::format("DC mode \"{}\" assign activate 0x{:04X} sync0 cycle {} factor {} shift {}\n",
                    s.string(m.name_idx), m.assign_activate, m.cycle_time_sync0,
                    m.cycle_time_sync0_factor, m.shift_time_sync0);
  }
  return out;
}

}  // namespace rackcat::esi
