// A PDI port without a chip behind it, for testing the firmware alone: a plain 64 KiB memory
// the test writes as the master and the ESC would (SM registers, AL control, events), with
// only the PDI read side effects the firmware relies on (ETG.1000.4 §6.5, ESC datasheet):
// reading AL control 0x0120 clears AL event bit 0, reading an SM activation byte clears bit 4,
// reading SM0's first byte clears bit 8 and its last byte empties the mailbox, reading SM2's
// first byte clears bit 10, writing SM1's last byte fills it. Every PDI write is logged.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include "base/little_endian.hpp"
#include "ecat/pdi_port.hpp"

namespace rackcat::ecat::test {

class FakePdi final : public PdiPort {
 public:
  struct Write {
    uint16_t address;
    std::vector<uint8_t> data;
  };

  FakePdi() { mem.fill(0); }

  void read(uint16_t address, std::span<uint8_t> dst) override {
    std::memcpy(dst.data(), &mem[address], dst.size());
    const uint32_t end = address + static_cast<uint32_t>(dst.size());
    auto covers = [&](uint32_t a) { return address <= a && a < end; };
    if (covers(0x0120)) clear_event(0x0001);
    for (int n = 0; n < 4; ++n) {
      if (covers(0x0806u + 8u * n)) clear_event(0x0010);
    }
    const uint16_t sm2_start = le::get16(&mem[0x0810]);
    if (le::get16(&mem[0x0812]) != 0 && covers(sm2_start)) clear_event(0x0400);
    const uint16_t sm0_start = le::get16(&mem[0x0800]);
    const uint16_t sm0_len = le::get16(&mem[0x0802]);
    if (sm0_len != 0 && covers(sm0_start)) clear_event(0x0100);
    if (sm0_len != 0 && covers(sm0_start + sm0_len - 1u))
      mem[0x0805] &= static_cast<uint8_t>(~0x08);
  }
  void write(uint16_t address, std::span<const uint8_t> src) override {
    writes.push_back({address, std::vector<uint8_t>(src.begin(), src.end())});
    const uint16_t sm1_start = le::get16(&mem[0x0808]);
    const uint16_t sm1_len = le::get16(&mem[0x080A]);
    const uint32_t end = address + static_cast<uint32_t>(src.size());
    const bool sm1 = sm1_len != 0 && address < sm1_start + sm1_len && sm1_start < end;
    if (sm1 && (mem[0x080D] & 0x08)) return;  // full: the ESC refuses the write
    std::memcpy(&mem[address], src.data(), src.size());
    if (sm1 && end >= static_cast<uint32_t>(sm1_start + sm1_len)) mem[0x080D] |= 0x08;
  }
  bool irq() const override { return (le::get32(&mem[0x0220]) & le::get32(&mem[0x0204])) != 0; }

  void raise_event(uint32_t bits) { le::put32(&mem[0x0220], le::get32(&mem[0x0220]) | bits); }
  void clear_event(uint32_t bits) { le::put32(&mem[0x0220], le::get32(&mem[0x0220]) & ~bits); }
  uint16_t get16(uint16_t a) const { return le::get16(&mem[a]); }
  void put16(uint16_t a, uint16_t v) { le::put16(&mem[a], v); }

  std::array<uint8_t, 0x10000> mem{};
  std::vector<Write> writes;
};

}  // namespace rackcat::ecat::test
