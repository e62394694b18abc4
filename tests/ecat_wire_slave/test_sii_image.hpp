// The SII EEPROM image of the wire test slave, built by hand from ETG.2010 so the link and
// the ESC can be tested against real masters before the device layer generates its own.
//
// What it describes (ETG.2010 Table 2 and the category tables):
//   - identity: TestSiiIdentity below (the serial number is the slave's position + 1);
//   - standard mailbox: SM0 receive at 0x1000 (128 bytes), SM1 send at 0x1080 (128 bytes),
//     mailbox protocols 0 (no CoE), so a master takes the PDO layout from the SII categories;
//   - categories: strings, general, FMMU (outputs, inputs), SM (four entries with type bytes),
//     RxPDO 0x1600 (4 bytes of outputs on SM2) and TxPDO 0x1A00 (4 bytes of inputs on SM3),
//     then the end marker.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rackcat::tests {

struct TestSiiIdentity {
  uint32_t vendor_id = 0x00000A5C;
  uint32_t product_code = 0x0000E7C1;
  uint32_t revision = 0x00010000;
  uint32_t serial = 1;
};

inline constexpr uint16_t kTestMailboxOut = 0x1000;  // SM0, master -> slave
inline constexpr uint16_t kTestMailboxIn = 0x1080;   // SM1, slave -> master
inline constexpr uint16_t kTestMailboxSize = 128;
inline constexpr uint16_t kTestOutputsAddr = 0x1100;  // SM2
inline constexpr uint16_t kTestInputsAddr = 0x1180;   // SM3
inline constexpr uint16_t kTestProcessDataBytes = 4;
inline constexpr const char* kTestSlaveName = "rackcat wire test slave";

// The whole EEPROM content, little-endian words, padded with 0xFF to kTestSiiBytes.
inline constexpr size_t kTestSiiBytes = 512;
std::vector<uint8_t> build_test_sii(const TestSiiIdentity& identity = {});

// CRC-8 of ETG.2010 §2.3 (polynomial x^8 + x^2 + x + 1, initial value 0xFF) over the first
// 14 bytes (words 0..6); stored in the low byte of word 7.
uint8_t sii_crc8(const uint8_t* data, size_t len);

}  // namespace rackcat::tests
