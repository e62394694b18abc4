#include "esi/sii_image.hpp"

#include <bit>
#include <map>
#include <string>

#include "base/little_endian.hpp"
#include "esi/sii_crc.hpp"

namespace rackcat::esi {
namespace {

// Appends to the image being built: room for `n` bytes at its end, written by rackcat::le
// (ETG.2010 §2: words little-endian).
uint8_t* grow(std::vector<uint8_t>& out, size_t n) {
  out.resize(out.size() + n);
  return &out[out.size() - n];
}

// The Strings category (ETG.2010 §2.3): one count byte, then length-prefixed strings numbered
// from 1. Index 0 means "no string". Names repeat a lot across modules ("Input 1"), so equal
// texts share an index; once 255 distinct texts are used the rest get index 0 (no name):
// masters use the names for display only.
class StringTable {
 public:
  uint8_t intern(const std::string& text) {
    if (text.empty()) return 0;
    if (auto it = index_.find(text); it != index_.end()) return it->second;
    if (texts_.size() >= sii::kMaxStrings) return 0;
    // A length byte limits one string to 255 characters.
    texts_.push_back(text.size() > 255 ? text.substr(0, 255) : text);
    auto idx = static_cast<uint8_t>(texts_.size());
    index_.emplace(text, idx);
    return idx;
  }
  std::vector<uint8_t> encode() const {
    std::vector<uint8_t> out;
    out.push_back(static_cast<uint8_t>(texts_.size()));
    for (const auto& t : texts_) {
      out.push_back(static_cast<uint8_t>(t.size()));
      out.insert(out.end(), t.begin(), t.end());
    }
    return out;
  }

 private:
  std::vector<std::string> texts_;
  std::map<std::string, uint8_t> index_;
};

void append_category(std::vector<uint8_t>& image, uint16_t type, std::vector<uint8_t> data) {
  if (data.size() % 2) data.push_back(0);  // categories are whole words
  if (data.size() / 2 > 0xFFFF) {
    throw SiiEncodeError("SII category " + std::to_string(type) + " needs " +
                         std::to_string(data.size() / 2) + " words, more than 65535");
  }
  le::put16(grow(image, 2), type);
  le::put16(grow(image, 2), static_cast<uint16_t>(data.size() / 2));
  image.insert(image.end(), data.begin(), data.end());
}

uint8_t coe_details_byte(const CoeDetails& c) {
  uint8_t b = 0;
  if (c.sdo) b |= sii::kCoeSdo;
  if (c.sdo_info) b |= sii::kCoeSdoInfo;
  if (c.pdo_assign) b |= sii::kCoePdoAssign;
  if (c.pdo_config) b |= sii::kCoePdoConfig;
  if (c.upload_at_startup) b |= sii::kCoeUploadAtStartup;
  if (c.complete_access) b |= sii::kCoeCompleteAccess;
  return b;
}

// General category, 32 bytes (ETG.2010 §2.4 Table 6).
std::vector<uint8_t> encode_general(const DeviceDescription& d, StringTable& strings) {
  std::vector<uint8_t> g(sii::kGeneralBytes, 0);
  g[0] = strings.intern(d.group_type);   // GroupIdx
  g[1] = 0;                              // ImgIdx: no image
  g[2] = strings.intern(d.order_code);   // OrderIdx
  g[3] = strings.intern(d.device_name);  // NameIdx
  g[5] = coe_details_byte(d.coe);
  g[6] = 0;   // FoE details
  g[7] = 0;   // EoE details
  g[8] = 0;   // SoE channels
  g[9] = 0;   // DS402 channels
  g[10] = 0;  // SysmanClass
  g[11] = 0;  // Flags: SafeOp/NotLRW/MBoxDataLinkLayer/IdentALSts/IdentPhyM all off
  le::put16(&g[12], static_cast<uint16_t>(d.ebus_current_ma));
  g[14] = g[0];  // GroupIdx repeated for compatibility
  le::put16(&g[16], d.physical_ports);
  le::put16(&g[18], 0);  // physical memory address of the identification value
  return g;
}

std::vector<uint8_t> encode_fmmus(const DeviceDescription& d) {
  std::vector<uint8_t> out;
  for (auto f : d.fmmus) out.push_back(static_cast<uint8_t>(f));
  if (out.size() % 2) out.push_back(static_cast<uint8_t>(FmmuUsage::Unused));
  return out;
}

// SyncManager category: 8 bytes per SM (ETG.2010 §2.6 Table 10).
std::vector<uint8_t> encode_sms(const DeviceDescription& d) {
  std::vector<uint8_t> out;
  for (const auto& sm : d.sms) {
    le::put16(grow(out, 2), sm.start);
    le::put16(grow(out, 2), sm.default_size);
    out.push_back(sm.control);
    out.push_back(0);  // status register: don't care
    out.push_back(sm.enable ? 0x01 : 0x00);
    out.push_back(static_cast<uint8_t>(sm.type));
  }
  return out;
}

// The bit-size type code of a PDO entry: the CoE data type index fits a byte for basic types;
// a device enumeration is carried as the unsigned type of its size.
uint8_t entry_type_byte(const PdoEntryDescription& e) {
  if (e.data_type <= 0xFF) return static_cast<uint8_t>(e.data_type);
  switch (e.bit_length) {
    case 8:
      return 0x05;
    case 16:
      return 0x06;
    case 32:
      return 0x07;
    default:
      return 0;
  }
}

// TxPDO/RxPDO category (ETG.2010 §2.7 Table 11/12): 8-byte PDO header, 8 bytes per entry.
std::vector<uint8_t> encode_pdos(const std::vector<PdoDescription>& pdos, StringTable& strings) {
  std::vector<uint8_t> out;
  for (const auto& p : pdos) {
    if (!p.assigned) continue;
    if (p.entries.size() > 255) {
      throw SiiEncodeError("PDO " + std::to_string(p.index) + " has more than 255 entries");
    }
    le::put16(grow(out, 2), p.index);
    out.push_back(static_cast<uint8_t>(p.entries.size()));
    out.push_back(p.sm);
    out.push_back(0);  // Synchronization: not used
    out.push_back(strings.intern(p.name));
    uint16_t flags = sii::kPdoDefault;
    if (p.mandatory) flags |= sii::kPdoMandatory;
    if (p.fixed) flags |= sii::kPdoFixedContent;
    le::put16(grow(out, 2), flags);
    for (const auto& e : p.entries) {
      le::put16(grow(out, 2), e.index);
      out.push_back(e.subindex);
      out.push_back(e.index == 0 ? 0 : strings.intern(e.name));
      out.push_back(e.index == 0 ? 0 : entry_type_byte(e));
      out.push_back(e.bit_length);
      le::put16(grow(out, 2), 0);  // flags: reserved
    }
  }
  return out;
}

// DC category: 24 bytes per op mode (ETG.2010 §2.8 Table 13).
std::vector<uint8_t> encode_dc(const DeviceDescription& d, StringTable& strings) {
  std::vector<uint8_t> out;
  for (const auto& m : d.dc_modes) {
    le::put32(grow(out, 4), m.cycle_time_sync0);
    le::put32(grow(out, 4), static_cast<uint32_t>(m.shift_time_sync0));
    le::put32(grow(out, 4), static_cast<uint32_t>(m.shift_time_sync1));
    le::put16(grow(out, 2), static_cast<uint16_t>(m.cycle_time_sync1_factor));
    le::put16(grow(out, 2), m.assign_activate);
    le::put16(grow(out, 2), static_cast<uint16_t>(m.cycle_time_sync0_factor));
    out.push_back(strings.intern(m.name));
    out.push_back(strings.intern(m.description));
    le::put32(grow(out, 4), 0);  // reserved
  }
  return out;
}

const SyncManagerDescription* find_sm(const DeviceDescription& d, SmType type) {
  for (const auto& sm : d.sms)
    if (sm.type == type) return &sm;
  return nullptr;
}

}  // namespace

std::vector<uint8_t> encode_config_area(const EscConfigArea& c) {
  std::vector<uint8_t> out;
  out.reserve(16);
  le::put16(grow(out, 2), c.pdi_control);
  le::put16(grow(out, 2), c.pdi_config);
  le::put16(grow(out, 2), c.sync_impulse_length);
  le::put16(grow(out, 2), c.extended_pdi_config);
  le::put16(grow(out, 2), c.station_alias);
  le::put16(grow(out, 2), 0);  // reserved
  le::put16(grow(out, 2), 0);  // reserved
  // Word 7: CRC in the low byte, high byte 0 (ETG.2010 Table 2).
  le::put16(grow(out, 2), sii_crc8(std::span<const uint8_t>(out.data(), 14)));
  return out;
}

SiiImage encode_sii(const DeviceDescription& d) {
  std::vector<uint8_t> image = encode_config_area(d.config);
  image.resize(sii::kFirstCategory * 2u, 0);

  auto word = [&](uint16_t address, uint16_t value) { le::put16(&image[2u * address], value); };
  auto dword = [&](uint16_t address, uint32_t value) { le::put32(&image[2u * address], value); };
  dword(sii::kVendorId, d.vendor_id);
  dword(sii::kProductCode, d.product_code);
  dword(sii::kRevision, d.revision);
  dword(sii::kSerial, d.serial);

  // The standard mailbox words come from the SMs typed as mailboxes; the bootstrap words from
  // the device's bootstrap mailbox (all 0 without BOOT: the ESM then refuses BOOT with 0x0013).
  word(sii::kBootstrapReceiveOffset, d.bootstrap.receive_offset);
  word(sii::kBootstrapReceiveSize, d.bootstrap.receive_size);
  word(sii::kBootstrapSendOffset, d.bootstrap.send_offset);
  word(sii::kBootstrapSendSize, d.bootstrap.send_size);
  const auto* rx = find_sm(d, SmType::MailboxOut);
  const auto* tx = find_sm(d, SmType::MailboxIn);
  if (rx && tx) {
    word(sii::kStandardReceiveOffset, rx->start);
    word(sii::kStandardReceiveSize, rx->default_size);
    word(sii::kStandardSendOffset, tx->start);
    word(sii::kStandardSendSize, tx->default_size);
    word(sii::kMailboxProtocol,
         static_cast<uint16_t>((d.coe.sdo ? sii::kProtoCoE : 0) | (d.foe ? sii::kProtoFoE : 0)));
  }
  word(sii::kVersion, 1);

  StringTable strings;
  // Intern in display order so the device's own names get the first indices.
  strings.intern(d.device_name);
  auto general = encode_general(d, strings);
  auto fmmu = encode_fmmus(d);
  auto sm = encode_sms(d);
  auto dc = encode_dc(d, strings);
  auto txpdo = encode_pdos(d.tx_pdos, strings);
  auto rxpdo = encode_pdos(d.rx_pdos, strings);

  // Masters walk the categories from word 0x40 and SOEM caches only the first 4 KiB of the
  // EEPROM (EC_MAXEEPBUF; bytes beyond read as 0xFF, i.e. "End"). The categories a master
  // needs to configure the slave therefore come first, before the Strings category, which
  // grows with the rack (ETG.2010 does not fix the order of the categories).
  append_category(image, sii::kCatGeneral, std::move(general));
  if (!fmmu.empty()) append_category(image, sii::kCatFmmu, std::move(fmmu));
  if (!sm.empty()) append_category(image, sii::kCatSyncManager, std::move(sm));
  if (!dc.empty()) append_category(image, sii::kCatDc, std::move(dc));
  append_category(image, sii::kCatStrings, strings.encode());
  if (!txpdo.empty()) append_category(image, sii::kCatTxPdo, std::move(txpdo));
  if (!rxpdo.empty()) append_category(image, sii::kCatRxPdo, std::move(rxpdo));
  le::put16(grow(image, 2), sii::kCatEnd);

  if (image.size() > sii::kMaxBytes) {
    throw SiiEncodeError("SII image needs " + std::to_string(image.size()) +
                         " bytes, more than the " + std::to_string(sii::kMaxBytes) +
                         " bytes a master can address");
  }
  // Round up to an EEPROM size (a power of two), erased cells read 0xFF. Word 0x3E holds the
  // size in Kbit minus one (ETG.2010 Table 2: 0 = 1 Kbit ... 15 = 16 Kbit).
  size_t size = std::max(sii::kMinBytes, std::bit_ceil(image.size()));
  image.resize(size, 0xFF);
  word(sii::kSize, static_cast<uint16_t>(size * 8 / 1024 - 1));
  return SiiImage{std::move(image)};
}

}  // namespace rackcat::esi
