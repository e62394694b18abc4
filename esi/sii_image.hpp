// The SII EEPROM image (ETG.2010 "SII specification"; ETG.1000.6 §5.4): the ESC configuration
// area (words 0..7), the identity and mailbox header (words 8..0x3F) and the categories from
// word 0x40 on. The running slave serves exactly these bytes to masters.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "base/little_endian.hpp"
#include "esi/device_description.hpp"

namespace rackcat::esi {

// Word addresses of the fixed header (ETG.2010 Table 2).
namespace sii {
inline constexpr uint16_t kPdiControl = 0x00;
inline constexpr uint16_t kPdiConfig = 0x01;
inline constexpr uint16_t kSyncImpulseLength = 0x02;
inline constexpr uint16_t kExtendedPdiConfig = 0x03;
inline constexpr uint16_t kStationAlias = 0x04;
inline constexpr uint16_t kChecksum = 0x07;
inline constexpr uint16_t kVendorId = 0x08;
inline constexpr uint16_t kProductCode = 0x0A;
inline constexpr uint16_t kRevision = 0x0C;
inline constexpr uint16_t kSerial = 0x0E;
inline constexpr uint16_t kBootstrapReceiveOffset = 0x14;
inline constexpr uint16_t kBootstrapReceiveSize = 0x15;
inline constexpr uint16_t kBootstrapSendOffset = 0x16;
inline constexpr uint16_t kBootstrapSendSize = 0x17;
inline constexpr uint16_t kStandardReceiveOffset = 0x18;
inline constexpr uint16_t kStandardReceiveSize = 0x19;
inline constexpr uint16_t kStandardSendOffset = 0x1A;
inline constexpr uint16_t kStandardSendSize = 0x1B;
inline constexpr uint16_t kMailboxProtocol = 0x1C;
inline constexpr uint16_t kSize = 0x3E;
inline constexpr uint16_t kVersion = 0x3F;
inline constexpr uint16_t kFirstCategory = 0x40;

// Mailbox protocol bits of word 0x1C (ETG.2010 Table 2).
inline constexpr uint16_t kProtoAoE = 0x0001;
inline constexpr uint16_t kProtoEoE = 0x0002;
inline constexpr uint16_t kProtoCoE = 0x0004;
inline constexpr uint16_t kProtoFoE = 0x0008;
inline constexpr uint16_t kProtoSoE = 0x0010;
inline constexpr uint16_t kProtoVoE = 0x0020;

// Category types (ETG.2010 Table 3).
inline constexpr uint16_t kCatStrings = 10;
inline constexpr uint16_t kCatDataTypes = 20;
inline constexpr uint16_t kCatGeneral = 30;
inline constexpr uint16_t kCatFmmu = 40;
inline constexpr uint16_t kCatSyncManager = 41;
inline constexpr uint16_t kCatTxPdo = 50;
inline constexpr uint16_t kCatRxPdo = 51;
inline constexpr uint16_t kCatDc = 60;
inline constexpr uint16_t kCatEnd = 0xFFFF;

// CoE details byte of the General category (ETG.2010 Table 6).
inline constexpr uint8_t kCoeSdo = 0x01;
inline constexpr uint8_t kCoeSdoInfo = 0x02;
inline constexpr uint8_t kCoePdoAssign = 0x04;
inline constexpr uint8_t kCoePdoConfig = 0x08;
inline constexpr uint8_t kCoeUploadAtStartup = 0x10;
inline constexpr uint8_t kCoeCompleteAccess = 0x20;

// PDO flags of the TxPDO/RxPDO categories (ETG.2010 Table 12).
inline constexpr uint16_t kPdoMandatory = 0x0001;
inline constexpr uint16_t kPdoDefault = 0x0002;
inline constexpr uint16_t kPdoFixedContent = 0x0010;

// The word address space of the SII interface (register 0x0504) used by masters is 16 bits;
// an image beyond 64 Ki words cannot be read.
inline constexpr size_t kMaxBytes = 0x20000;
// Smallest EEPROM we emit: 2 Kbit (256 bytes), the smallest device ETG.2010 names.
inline constexpr size_t kMinBytes = 256;
// The General category is 32 bytes; a string index is one byte (0 = none).
inline constexpr size_t kGeneralBytes = 32;
inline constexpr size_t kMaxStrings = 255;
}  // namespace sii

struct SiiImage {
  std::vector<uint8_t> bytes;  // padded with 0xFF (erased EEPROM) to a power-of-two size

  std::span<const uint8_t> span() const { return bytes; }
  size_t word_count() const { return bytes.size() / 2; }
  uint16_t word(uint16_t address) const { return le::get16(&bytes[2u * address]); }
};

class SiiEncodeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Words 0..7: the ESC configuration area with its CRC in word 7 (also the ESI ConfigData).
std::vector<uint8_t> encode_config_area(const EscConfigArea& config);

// The whole image. Only the PDOs currently assigned appear in the TxPDO/RxPDO categories, as
// the master finds them in 0x1C12/0x1C13. Throws SiiEncodeError when the image would exceed
// sii::kMaxBytes.
SiiImage encode_sii(const DeviceDescription& device);

}  // namespace rackcat::esi
