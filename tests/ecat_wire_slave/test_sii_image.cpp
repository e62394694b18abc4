#include "tests/ecat_wire_slave/test_sii_image.hpp"

#include <cstring>

namespace rackcat::tests {
namespace {

// SII category types (ETG.2010 Table 4).
constexpr uint16_t kCatStrings = 10;
constexpr uint16_t kCatGeneral = 30;
constexpr uint16_t kCatFmmu = 40;
constexpr uint16_t kCatSyncManager = 41;
constexpr uint16_t kCatTxPdo = 50;
constexpr uint16_t kCatRxPdo = 51;
constexpr uint16_t kCatEnd = 0xFFFF;

// SyncManager control bytes (register 0x0804, ETG.1000.4 Table 59): bits 1..0 mode
// (00 buffered, 10 mailbox), bits 3..2 direction (00 ECAT reads, 01 ECAT writes),
// bit 5 PDI interrupt, bit 6 watchdog trigger.
constexpr uint8_t kCtrlMailboxWrite = 0x26;
constexpr uint8_t kCtrlMailboxRead = 0x22;
constexpr uint8_t kCtrlBufferedWrite = 0x64;
constexpr uint8_t kCtrlBufferedRead = 0x20;

// SII SM category type byte (ETG.2010 Table 10): 1 mailbox out, 2 mailbox in, 3 outputs, 4 inputs.
enum SmType : uint8_t { kMbxOut = 1, kMbxIn = 2, kPdOut = 3, kPdIn = 4 };

class Writer {
 public:
  void u8(uint8_t v) { bytes.push_back(v); }
  void u16(uint16_t v) {
    u8(static_cast<uint8_t>(v));
    u8(static_cast<uint8_t>(v >> 8));
  }
  void u32(uint32_t v) {
    u16(static_cast<uint16_t>(v));
    u16(static_cast<uint16_t>(v >> 16));
  }
  void pad_to_word() {
    if (bytes.size() % 2) u8(0);
  }
  std::vector<uint8_t> bytes;
};

// Appends a category header {type, length in words} and its (word-padded) data.
void category(Writer& out, uint16_t type, Writer data) {
  data.pad_to_word();
  out.u16(type);
  out.u16(static_cast<uint16_t>(data.bytes.size() / 2));
  out.bytes.insert(out.bytes.end(), data.bytes.begin(), data.bytes.end());
}

// One PDO with one entry (ETG.2010 Table 13/14): PDO header 8 bytes, entries 8 bytes each.
Writer pdo(uint16_t pdo_index, uint8_t sm, uint16_t entry_index, uint8_t entry_sub,
           uint8_t name_idx, uint8_t data_type, uint8_t bits) {
  Writer w;
  w.u16(pdo_index);
  w.u8(1);  // number of entries
  w.u8(sm);
  w.u8(0);         // synchronization
  w.u8(name_idx);  // name (string index)
  w.u16(0x0001);   // flags: PdoMandatory
  w.u16(entry_index);
  w.u8(entry_sub);
  w.u8(name_idx);
  w.u8(data_type);
  w.u8(bits);
  w.u16(0);  // flags
  return w;
}

}  // namespace

uint8_t sii_crc8(const uint8_t* data, size_t len) {
  uint8_t crc = 0xFF;
  for (size_t i = 0; i < len; ++i) {
    crc ^= data[i];
    for (int b = 0; b < 8; ++b) {
      crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : crc << 1);
    }
  }
  return crc;
}

std::vector<uint8_t> build_test_sii(const TestSiiIdentity& id) {
  Writer w;
  // Words 0x00..0x07: ESC configuration area (ETG.2010 Table 2).
  w.u16(0x0C08);  // 0x00 PDI control: 0x08 = SPI (a real ESC's typical value; PDI unused here)
  w.u16(0x0000);  // 0x01 PDI configuration
  w.u16(0x0000);  // 0x02 SyncImpulseLen
  w.u16(0x0000);  // 0x03 PDI configuration 2
  w.u16(0x0000);  // 0x04 configured station alias
  w.u16(0x0000);  // 0x05 reserved
  w.u16(0x0000);  // 0x06 reserved
  w.u16(sii_crc8(w.bytes.data(), 14));         // 0x07 checksum
  w.u32(id.vendor_id);                         // 0x08
  w.u32(id.product_code);                      // 0x0A
  w.u32(id.revision);                          // 0x0C
  w.u32(id.serial);                            // 0x0E
  for (int i = 0x10; i < 0x14; ++i) w.u16(0);  // execution delay, port delays, reserved
  w.u16(0);                 // 0x14 bootstrap receive mailbox offset (no bootstrap mailbox)
  w.u16(0);                 // 0x15 size
  w.u16(0);                 // 0x16 bootstrap send mailbox offset
  w.u16(0);                 // 0x17 size
  w.u16(kTestMailboxOut);   // 0x18 standard receive mailbox offset
  w.u16(kTestMailboxSize);  // 0x19 size
  w.u16(kTestMailboxIn);    // 0x1A standard send mailbox offset
  w.u16(kTestMailboxSize);  // 0x1B size
  w.u16(0x0000);            // 0x1C mailbox protocols: none (no CoE: PDOs come from the SII)
  while (w.bytes.size() < 0x3E * 2) w.u16(0);                  // 0x1D..0x3D reserved
  w.u16(static_cast<uint16_t>(kTestSiiBytes * 8 / 1024 - 1));  // 0x3E size in KiBit - 1
  w.u16(0x0001);                                               // 0x3F version

  // Strings: 1 = device name, 2 = group, 3 = "Outputs", 4 = "Inputs".
  {
    Writer s;
    const char* strings[] = {kTestSlaveName, "rackcat", "Outputs", "Inputs"};
    s.u8(static_cast<uint8_t>(sizeof(strings) / sizeof(strings[0])));
    for (const char* str : strings) {
      const size_t n = std::strlen(str);
      s.u8(static_cast<uint8_t>(n));
      for (size_t i = 0; i < n; ++i) s.u8(static_cast<uint8_t>(str[i]));
    }
    category(w, kCatStrings, s);
  }
  // General (ETG.2010 Table 7): group 2, image 0, order 1, name 1, CoE/FoE/EoE details 0,
  // no SoE/DS402 channels, flags 0, E-bus current 0, physical ports 0x0011 (two MII ports).
  {
    Writer g;
    g.u8(2);        // group idx
    g.u8(0);        // image idx
    g.u8(1);        // order idx
    g.u8(1);        // name idx
    g.u8(0);        // reserved
    g.u8(0);        // CoE details
    g.u8(0);        // FoE details
    g.u8(0);        // EoE details
    g.u8(0);        // SoE channels
    g.u8(0);        // DS402 channels
    g.u8(0);        // SysmanClass
    g.u8(0);        // flags
    g.u16(0);       // current on E-bus (mA)
    g.u8(2);        // group idx (copy)
    g.u8(0);        // reserved
    g.u16(0x0011);  // physical ports: port 0 and 1 = MII
    g.u16(0);       // physical memory address
    while (g.bytes.size() < 32) g.u8(0);
    category(w, kCatGeneral, g);
  }
  // FMMU usage (ETG.2010 Table 9): FMMU0 outputs (1), FMMU1 inputs (2).
  {
    Writer f;
    f.u8(1);
    f.u8(2);
    category(w, kCatFmmu, f);
  }
  // SyncManagers (ETG.2010 Table 10): start, length, control, status, enable, type.
  {
    Writer m;
    auto sm = [&](uint16_t start, uint16_t len, uint8_t ctrl, uint8_t type) {
      m.u16(start);
      m.u16(len);
      m.u8(ctrl);
      m.u8(0);  // status (don't care)
      m.u8(1);  // enable
      m.u8(type);
    };
    sm(kTestMailboxOut, kTestMailboxSize, kCtrlMailboxWrite, kMbxOut);
    sm(kTestMailboxIn, kTestMailboxSize, kCtrlMailboxRead, kMbxIn);
    sm(kTestOutputsAddr, kTestProcessDataBytes, kCtrlBufferedWrite, kPdOut);
    sm(kTestInputsAddr, kTestProcessDataBytes, kCtrlBufferedRead, kPdIn);
    category(w, kCatSyncManager, m);
  }
  // TxPDO 0x1A00 on SM3: 0x6000:01 UDINT (data type 0x0007), 32 bits; name "Inputs" (4).
  category(w, kCatTxPdo, pdo(0x1A00, 3, 0x6000, 0x01, 4, 0x07, 32));
  // RxPDO 0x1600 on SM2: 0x7000:01 UDINT, 32 bits; name "Outputs" (3).
  category(w, kCatRxPdo, pdo(0x1600, 2, 0x7000, 0x01, 3, 0x07, 32));
  w.u16(kCatEnd);

  w.bytes.resize(kTestSiiBytes, 0xFF);
  return w.bytes;
}

}  // namespace rackcat::tests
