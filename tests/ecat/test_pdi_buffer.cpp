// Block access to a whole SyncManager buffer through the PDI (PdiPort::read_buffer /
// write_buffer) and the buffer switch it makes (ETG.1000.4 §6.7.1 mailbox, §6.7.2 buffered
// mode; ESC datasheet 0x0805 SM status): reading the first byte of a buffer the master wrote
// opens it (status bit 0 "written" and AL event bit 8+n clear, bit 6 "read buffer open" while
// the access has not reached the last byte), reading its last byte completes it (bit 1 "read";
// a mailbox is emptied); writing the last byte of a buffer the master reads hands it over
// (bit 0, bits 5:4 = the buffer of the three that became the newest; a mailbox is full).
// The same access through the emulated ESC (EscPdi), byte by byte, and through a LAN9252's
// PRAM FIFOs over its SPI protocol (Lan9252Pdi + Lan9252Model) leaves the chip in the same
// state.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "ecat/esc/esc_pdi.hpp"
#include "ecat/esc/lan9252_model.hpp"
#include "ecat/lan9252/lan9252_pdi.hpp"
#include "tests/ecat/chip_master.hpp"

namespace rackcat::ecat::test {
namespace {

// SyncManager control bytes (ETG.1000.4 Table 58 / ESC datasheet 0x0804): mode bits 1:0
// (00 buffered, 10 mailbox), direction bits 3:2 (00 ECAT reads, 01 ECAT writes), bit 5 AL
// event, bit 6 watchdog trigger.
constexpr uint8_t kOutputsControl = 0x64;  // SM2: buffered, ECAT writes, AL event, watchdog
constexpr uint8_t kInputsControl = 0x20;   // SM3: buffered, ECAT reads, AL event
constexpr uint8_t kMbxOutControl = 0x26;   // SM0: mailbox, ECAT writes, AL event
constexpr uint8_t kMbxInControl = 0x22;    // SM1: mailbox, ECAT reads, AL event

constexpr uint16_t kSm0 = 0x1000, kSm1 = 0x1080, kSm2 = 0x1100, kSm3 = 0x1180;
constexpr uint16_t kMbxLen = 0x40;
constexpr uint16_t kOutLen = 6;
constexpr uint16_t kInLen = 5;

// Status bits of 0x0805+8n.
constexpr uint8_t kWritten = 0x01, kRead = 0x02, kFull = 0x08, kBufferBits = 0x30;
constexpr uint8_t kReadOpen = 0x40, kWriteOpen = 0x80;

// One chip, its SyncManagers 0-3 configured by the master and activated by the PDI.
struct Chip : ChipMaster {
  Chip() {
    sm(0, kSm0, kMbxLen, kMbxOutControl);
    sm(1, kSm1, kMbxLen, kMbxInControl);
    sm(2, kSm2, kOutLen, kOutputsControl);
    sm(3, kSm3, kInLen, kInputsControl);
  }

  uint8_t status(int n) const { return esc.read8(static_cast<uint16_t>(0x0805 + 8 * n)); }
  uint32_t al_events() const { return esc.read32(0x0220); }
  // What the chip shows after an access: SM registers, AL and ECAT event requests.
  std::vector<uint8_t> state() const {
    std::vector<uint8_t> s;
    for (uint16_t a = 0x0800; a < 0x0820; ++a) s.push_back(esc.read8(a));
    for (uint16_t a = 0x0220; a < 0x0224; ++a) s.push_back(esc.read8(a));
    for (uint16_t a = 0x0210; a < 0x0212; ++a) s.push_back(esc.read8(a));
    return s;
  }
};

std::vector<uint8_t> pattern(size_t n, uint8_t seed) {
  std::vector<uint8_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = static_cast<uint8_t>(seed + 3 * i);
  return v;
}

TEST(PdiBuffer, OutputsReadInOneBlockAreTheMastersAndCompleteTheRead) {
  Chip c;
  EscPdi pdi(c.esc);
  const auto out = pattern(kOutLen, 0x10);
  ASSERT_EQ(c.apwr(kSm2, out), 1);
  // The master completed buffer 0: "written", bits 5:4 = 00, AL event bit 10.
  EXPECT_EQ(c.status(2) & (kWritten | kBufferBits), kWritten);
  EXPECT_NE(c.al_events() & 0x0400, 0u);
  std::vector<uint8_t> got(kOutLen);
  pdi.read_buffer(2, kSm2, got);
  EXPECT_EQ(got, out);
  EXPECT_EQ(c.status(2) & (kWritten | kRead | kReadOpen), kRead);
  EXPECT_EQ(c.al_events() & 0x0400, 0u);
}

TEST(PdiBuffer, ReadSwitchesOnTheLastByteNotBefore) {
  Chip c;
  ASSERT_EQ(c.apwr(kSm2, pattern(kOutLen, 0x20)), 1);
  uint8_t b[kOutLen];
  // The first byte opens the buffer: the event is taken, the buffer is in use by the PDI.
  c.esc.pdi_read(kSm2, b, 1);
  EXPECT_EQ(c.al_events() & 0x0400, 0u);
  EXPECT_EQ(c.status(2) & (kWritten | kRead | kReadOpen), kReadOpen);
  // Up to the last byte but one: still open, nothing completed.
  c.esc.pdi_read(kSm2 + 1, b + 1, kOutLen - 2);
  EXPECT_EQ(c.status(2) & (kRead | kReadOpen), kReadOpen);
  // The last byte completes the read and releases the buffer.
  c.esc.pdi_read(kSm2 + kOutLen - 1, b + kOutLen - 1, 1);
  EXPECT_EQ(c.status(2) & (kRead | kReadOpen), kRead);
}

// A register read without side effect is a plain copy (Esc::pdi_read), but only below every
// SyncManager buffer: a master may place a buffer among those registers (0x0122-0x043F; the
// bytes are registers still, so what it writes there is not kept), and reading it there still
// opens and completes it.
TEST(PdiBuffer, BufferPlacedAmongRegistersIsStillOneForThePdi) {
  ChipMaster c;
  constexpr uint16_t kLow = 0x0300;
  c.sm(2, kLow, kOutLen, kOutputsControl);
  const auto out = pattern(kOutLen, 0x40);
  ASSERT_EQ(c.apwr(kLow, out), 1);
  EXPECT_NE(c.esc.read32(0x0220) & 0x0400, 0u);
  std::vector<uint8_t> got(kOutLen);
  c.esc.pdi_read(kLow, got.data(), kOutLen);
  EXPECT_EQ(c.esc.read32(0x0220) & 0x0400, 0u);  // the event is taken
  EXPECT_EQ(c.esc.read8(0x0805 + 16) & (kWritten | kRead | kReadOpen), kRead);
  // The AL event request itself reads as it is, and reading it clears nothing.
  ASSERT_EQ(c.apwr(kLow, out), 1);
  uint8_t events[4];
  c.esc.pdi_read(0x0220, events, 4);
  EXPECT_NE(events[1] & 0x04, 0);
  EXPECT_NE(c.esc.read32(0x0220) & 0x0400, 0u);
}

TEST(PdiBuffer, PartialMailboxReadKeepsItFullForTheMaster) {
  Chip c;
  EscPdi pdi(c.esc);
  ASSERT_EQ(c.apwr(kSm0, pattern(kMbxLen, 1)), 1);
  EXPECT_EQ(c.status(0) & kFull, kFull);
  std::vector<uint8_t> head(kMbxLen - 1);
  pdi.read(kSm0, head);  // all but the last byte
  EXPECT_EQ(c.status(0) & kFull, kFull);
  EXPECT_EQ(c.apwr(kSm0, pattern(kMbxLen, 2)), 0);  // still full: the master's write is refused
  std::vector<uint8_t> all(kMbxLen);
  pdi.read_buffer(0, kSm0, all);  // the whole buffer: its last byte empties the mailbox
  EXPECT_EQ(all, pattern(kMbxLen, 1));
  EXPECT_EQ(c.status(0) & (kFull | kRead), kRead);
  EXPECT_EQ(c.apwr(kSm0, pattern(kMbxLen, 2)), 1);
}

TEST(PdiBuffer, InputsWrittenInOneBlockSwitchThroughTheThreeBuffers) {
  Chip c;
  EscPdi pdi(c.esc);
  EXPECT_EQ(c.status(3) & kBufferBits, kBufferBits);  // no buffer written yet
  for (uint8_t k = 0; k < 4; ++k) {
    const auto in = pattern(kInLen, static_cast<uint8_t>(0x40 + k));
    pdi.write_buffer(3, kSm3, in);
    // Each completed write makes the next of the three buffers the newest (bits 5:4).
    EXPECT_EQ(c.status(3) & (kWritten | kBufferBits | kWriteOpen), kWritten | ((k % 3) << 4))
        << "write " << int{k};
    const auto [data, wkc] = c.aprd(kSm3, kInLen);
    EXPECT_EQ(wkc, 1);
    EXPECT_EQ(data, in);
    EXPECT_EQ(c.status(3) & kRead, kRead);
    EXPECT_NE(c.al_events() & 0x0800, 0u);  // the master read it: AL event bit 11
  }
}

TEST(PdiBuffer, PartialInputWriteDoesNotSwitch) {
  Chip c;
  EscPdi pdi(c.esc);
  pdi.write_buffer(3, kSm3, pattern(kInLen, 0x50));
  const uint8_t before = c.status(3);
  ASSERT_EQ(before & (kWritten | kBufferBits), kWritten | 0x00);
  c.aprd(kSm3, kInLen);  // the master reads buffer 0 (status "read", AL event bit 11)
  const auto next = pattern(kInLen, 0x60);
  c.esc.pdi_write(kSm3, next.data(), kInLen - 1);  // all but the last byte
  // Opened (the master's "read" and the AL event are taken), not handed over: still buffer 0.
  EXPECT_EQ(c.status(3) & (kWritten | kRead | kBufferBits | kWriteOpen), kWriteOpen);
  EXPECT_EQ(c.al_events() & 0x0800, 0u);
  c.esc.pdi_write(kSm3 + kInLen - 1, &next[kInLen - 1], 1);
  EXPECT_EQ(c.status(3) & (kWritten | kBufferBits | kWriteOpen), kWritten | 0x10);
}

TEST(PdiBuffer, FullMailboxRefusesTheBlockWrite) {
  Chip c;
  EscPdi pdi(c.esc);
  pdi.write_buffer(1, kSm1, pattern(kMbxLen, 7));
  EXPECT_EQ(c.status(1) & (kFull | kWritten), kFull | kWritten);
  pdi.write_buffer(1, kSm1, pattern(kMbxLen, 9));  // the master has not read it yet
  EXPECT_EQ(c.aprd(kSm1, kMbxLen).first, pattern(kMbxLen, 7));
  EXPECT_EQ(c.status(1) & kFull, 0);
}

TEST(PdiBuffer, BlockAccessEqualsTheByteWiseAccess) {
  Chip block;
  Chip bytes;
  EscPdi pdi(block.esc);
  for (Chip* c : {&block, &bytes}) {
    c->apwr(kSm0, pattern(kMbxLen, 3));
    c->apwr(kSm2, pattern(kOutLen, 4));
  }
  std::vector<uint8_t> a(kMbxLen), b(kMbxLen);
  pdi.read_buffer(0, kSm0, a);
  for (uint16_t i = 0; i < kMbxLen; ++i) bytes.esc.pdi_read(kSm0 + i, &b[i], 1);
  EXPECT_EQ(a, b);
  EXPECT_EQ(block.state(), bytes.state());
  std::vector<uint8_t> o1(kOutLen), o2(kOutLen);
  pdi.read_buffer(2, kSm2, o1);
  for (uint16_t i = 0; i < kOutLen; ++i) bytes.esc.pdi_read(kSm2 + i, &o2[i], 1);
  EXPECT_EQ(o1, o2);
  EXPECT_EQ(block.state(), bytes.state());
  const auto in = pattern(kInLen, 5);
  pdi.write_buffer(3, kSm3, in);
  for (uint16_t i = 0; i < kInLen; ++i) bytes.esc.pdi_write(kSm3 + i, &in[i], 1);
  EXPECT_EQ(block.state(), bytes.state());
  const auto reply = pattern(kMbxLen, 6);
  pdi.write_buffer(1, kSm1, reply);
  for (uint16_t i = 0; i < kMbxLen; ++i) bytes.esc.pdi_write(kSm1 + i, &reply[i], 1);
  EXPECT_EQ(block.state(), bytes.state());
  EXPECT_EQ(block.aprd(kSm1, kMbxLen), bytes.aprd(kSm1, kMbxLen));
  EXPECT_EQ(block.aprd(kSm3, kInLen), bytes.aprd(kSm3, kInLen));
}

TEST(PdiBuffer, BlockAccessEqualsTheByteWiseAccessWhereTheRulesRefuseOrSkip) {
  Chip block;
  Chip bytes;
  EscPdi pdi(block.esc);
  for (Chip* c : {&block, &bytes}) c->apwr(kSm2, pattern(kOutLen, 4));
  // The PDI writes only buffers the master reads: a write into SM2's outputs changes nothing.
  const auto in = pattern(kOutLen, 9);
  pdi.write_buffer(2, kSm2, in);
  for (uint16_t i = 0; i < kOutLen; ++i) bytes.esc.pdi_write(kSm2 + i, &in[i], 1);
  EXPECT_EQ(block.state(), bytes.state());
  EXPECT_EQ(std::vector<uint8_t>(block.esc.memory().begin() + kSm2,
                                 block.esc.memory().begin() + kSm2 + kOutLen),
            pattern(kOutLen, 4));
  // SM2 deactivated by the PDI (0x0817 bit 0): the PDI still reads the memory, but nothing is
  // handed over.
  for (Chip* c : {&block, &bytes}) {
    const uint8_t deactivate = 0x01;
    c->esc.pdi_write(0x0817, &deactivate, 1);
  }
  std::vector<uint8_t> a(kOutLen), b(kOutLen);
  pdi.read_buffer(2, kSm2, a);
  for (uint16_t i = 0; i < kOutLen; ++i) bytes.esc.pdi_read(kSm2 + i, &b[i], 1);
  EXPECT_EQ(a, b);
  EXPECT_EQ(a, pattern(kOutLen, 4));
  EXPECT_EQ(block.state(), bytes.state());
}

TEST(PdiBuffer, BlockAccessNotMatchingTheSyncManagerIsAPlainAccess) {
  Chip block;
  Chip plain;
  EscPdi pdi(block.esc);
  EscPdi other(plain.esc);
  for (Chip* c : {&block, &plain}) c->apwr(kSm2, pattern(kOutLen, 8));
  // The wrong SM index, a shorter span: the ESC applies the byte rules of what is accessed.
  std::vector<uint8_t> a(kOutLen - 1), b(kOutLen - 1);
  pdi.read_buffer(3, kSm2, a);
  other.read(kSm2, b);
  EXPECT_EQ(a, b);
  EXPECT_EQ(block.state(), plain.state());
  EXPECT_EQ(block.status(2) & (kRead | kReadOpen), kReadOpen);
}

// The SPI path: the same SyncManager accesses through a LAN9252 (Lan9252Pdi over the chip
// model's host bus) and straight through EscPdi give the same bytes and leave the same state.
TEST(PdiBuffer, Lan9252BlockAccessEqualsTheEmulatedEsc) {
  Chip spi_chip;
  Chip direct_chip;
  Lan9252Model model(spi_chip.esc);
  Lan9252Pdi spi(model);
  ASSERT_TRUE(spi.start());
  EscPdi direct(direct_chip.esc);
  for (Chip* c : {&spi_chip, &direct_chip}) {
    c->apwr(kSm0, pattern(kMbxLen, 11));
    c->apwr(kSm2, pattern(kOutLen, 12));
  }
  std::vector<uint8_t> a(kMbxLen), b(kMbxLen);
  spi.read_buffer(0, kSm0, a);
  direct.read_buffer(0, kSm0, b);
  EXPECT_EQ(a, b);
  std::vector<uint8_t> o1(kOutLen), o2(kOutLen);
  spi.read_buffer(2, kSm2, o1);
  direct.read_buffer(2, kSm2, o2);
  EXPECT_EQ(o1, o2);
  EXPECT_EQ(spi_chip.state(), direct_chip.state());
  spi.write_buffer(3, kSm3, pattern(kInLen, 13));
  direct.write_buffer(3, kSm3, pattern(kInLen, 13));
  spi.write_buffer(1, kSm1, pattern(kMbxLen, 14));
  direct.write_buffer(1, kSm1, pattern(kMbxLen, 14));
  EXPECT_EQ(spi_chip.state(), direct_chip.state());
  EXPECT_EQ(spi_chip.aprd(kSm3, kInLen), direct_chip.aprd(kSm3, kInLen));
  EXPECT_EQ(spi_chip.aprd(kSm1, kMbxLen), direct_chip.aprd(kSm1, kMbxLen));
  EXPECT_EQ(spi_chip.state(), direct_chip.state());
}

// A LAN9252 bus that records every SPI instruction it carries, in front of the chip model.
class RecordingBus final : public Lan9252Bus {
 public:
  explicit RecordingBus(Lan9252Bus& chip) : chip_(chip) {}
  void read(uint16_t address, std::span<uint8_t> data) override {
    chip_.read(address, data);
    log.push_back(instruction(lan9252::kSpiRead, address, data));
  }
  void write(uint16_t address, std::span<const uint8_t> data) override {
    log.push_back(instruction(lan9252::kSpiWrite, address, data));
    chip_.write(address, data);
  }
  bool irq() const override { return chip_.irq(); }
  std::vector<std::vector<uint8_t>> log;

 private:
  static std::vector<uint8_t> instruction(uint8_t code, uint16_t address,
                                          std::span<const uint8_t> data) {
    std::vector<uint8_t> v{code, static_cast<uint8_t>(address >> 8), static_cast<uint8_t>(address)};
    v.insert(v.end(), data.begin(), data.end());
    return v;
  }
  Lan9252Bus& chip_;
};

// Golden SPI instructions of a block read of SM2 (6 bytes at 0x1100), written from the LAN9252
// datasheet (§5 SPI: instruction 0x03 read / 0x02 write, 16-bit address big-endian, data
// little-endian; ECAT_PRAM_RD_ADDR_LEN 0x308 = length 31:16 | address 15:0; ECAT_PRAM_RD_CMD
// 0x30C: bit 30 abort, bit 31 busy, bits 12:8 DWORDs available, bit 0 available; read FIFO
// 0x000): one PRAM transfer for the whole buffer, two DWORDs out of the FIFO.
TEST(PdiBuffer, Lan9252BlockReadIsOnePramTransferGolden) {
  Chip c;
  Lan9252Model model(c.esc);
  RecordingBus bus(model);
  Lan9252Pdi spi(bus);
  ASSERT_TRUE(spi.start());
  c.apwr(kSm2, {0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6});
  bus.log.clear();
  std::vector<uint8_t> got(kOutLen);
  spi.read_buffer(2, kSm2, got);
  EXPECT_EQ(got, (std::vector<uint8_t>{0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6}));
  const std::vector<std::vector<uint8_t>> want{
      {0x02, 0x03, 0x0C, 0x00, 0x00, 0x00, 0x40},  // abort a pending PRAM read
      {0x02, 0x03, 0x08, 0x00, 0x11, 0x06, 0x00},  // address 0x1100, length 6
      {0x02, 0x03, 0x0C, 0x00, 0x00, 0x00, 0x80},  // busy: start
      {0x03, 0x03, 0x0C, 0x01, 0x02, 0x00, 0x80},  // busy, 2 DWORDs available
      {0x03, 0x00, 0x00, 0xA1, 0xA2, 0xA3, 0xA4},  // FIFO DWORD 1
      {0x03, 0x00, 0x00, 0xA5, 0xA6, 0x00, 0x00},  // FIFO DWORD 2 (bytes 5, 6)
  };
  EXPECT_EQ(bus.log, want);
  EXPECT_EQ(c.status(2) & (kWritten | kRead), kRead);  // the whole buffer read: completed
}

// Every SyncManager has its own event bits (ESC datasheet 0x0210, 0x0220): ECAT event request
// bit 4+n (SMs 0-7, ECAT event enabled: control bit 4), AL event request bit 8+n (all 16, AL
// event enabled: control bit 5). A hand-over sets or clears SM n's bits and no other bit, in
// whichever byte of the register they are.
TEST(PdiBuffer, EachSyncManagerRaisesItsOwnEventBits) {
  constexpr uint8_t kOutputsWithEvents = 0x34;  // buffered, ECAT writes, ECAT and AL event
  for (int n = 0; n < 16; ++n) {
    ChipMaster chip;
    const auto start = static_cast<uint16_t>(0x1000 + 0x10 * n);
    chip.sm(n, start, 4, kOutputsWithEvents);
    const uint32_t al_before = chip.esc.read32(reg::kAlEventRequest);
    const uint16_t ecat_before = chip.esc.read16(reg::kEcatEventRequest);
    ASSERT_EQ(chip.apwr(start, {1, 2, 3, 4}), 1) << n;
    // Written by the master: AL event bit 8+n for the firmware, nothing else moves.
    EXPECT_EQ(chip.esc.read32(reg::kAlEventRequest), al_before | (1u << (8 + n))) << n;
    EXPECT_EQ(chip.esc.read16(reg::kEcatEventRequest), ecat_before) << n;
    uint8_t buffer[4] = {};
    chip.esc.pdi_read_buffer(static_cast<uint8_t>(n), start, buffer, 4);
    // Read by the PDI: the AL bit clears; the ECAT event bit 4+n tells the master (SMs 0-7).
    EXPECT_EQ(chip.esc.read32(reg::kAlEventRequest), al_before) << n;
    const uint16_t ecat_read = n < 8 ? static_cast<uint16_t>(1u << (4 + n)) : 0;
    EXPECT_EQ(chip.esc.read16(reg::kEcatEventRequest), ecat_before | ecat_read) << n;
    ASSERT_EQ(chip.apwr(start, {5, 6, 7, 8}), 1) << n;
    // The master's next write clears "read" (and its ECAT bit) and raises the AL bit again.
    EXPECT_EQ(chip.esc.read16(reg::kEcatEventRequest), ecat_before) << n;
    EXPECT_EQ(chip.esc.read32(reg::kAlEventRequest), al_before | (1u << (8 + n))) << n;
  }
}

}  // namespace
}  // namespace rackcat::ecat::test
