// Test-side master: builds EtherCAT frames byte by byte (ETG.1000.4 §5.3), sends them through
// a Segment and decodes the reply. Independent of the ESC's own parser.
#pragma once

#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "ecat/frame.hpp"
#include "ecat/segment.hpp"
#include "tests/ecat/test_application.hpp"

namespace rackcat::ecat::test {

struct Reply {
  uint8_t command = 0;
  uint8_t index = 0;
  uint16_t adp = 0;
  uint16_t ado = 0;
  uint16_t irq = 0;
  std::vector<uint8_t> data;
  uint16_t wkc = 0;
};

class FrameBuilder {
 public:
  FrameBuilder& add(Command cmd, uint16_t adp, uint16_t ado, std::vector<uint8_t> data,
                    uint16_t wkc = 0);
  FrameBuilder& add_logical(Command cmd, uint32_t address, std::vector<uint8_t> data);
  // Destination broadcast, source 00:00:00:00:00:01 (bit 1 of the first byte clear, so the
  // ESC's marking is visible), padded to the 60-byte Ethernet minimum.
  std::vector<uint8_t> build() const;

 private:
  struct Item {
    uint8_t cmd;
    uint32_t address;
    std::vector<uint8_t> data;
    uint16_t wkc;
  };
  std::vector<Item> items_;
};

// Decodes the datagrams of a returned frame.
std::vector<Reply> decode(const std::vector<uint8_t>& frame);

class TestMaster {
 public:
  explicit TestMaster(Segment& segment) : segment_(segment) {}

  Reply send(Command cmd, uint16_t adp, uint16_t ado, std::vector<uint8_t> data);
  Reply send_logical(Command cmd, uint32_t address, std::vector<uint8_t> data);
  std::vector<Reply> send_frame(const FrameBuilder& frame);

  Reply fprd(uint16_t station, uint16_t ado, uint16_t len) {
    return send(Command::Fprd, station, ado, std::vector<uint8_t>(len, 0));
  }
  Reply fpwr(uint16_t station, uint16_t ado, std::vector<uint8_t> data) {
    return send(Command::Fpwr, station, ado, std::move(data));
  }
  uint16_t fpwr8(uint16_t station, uint16_t ado, uint8_t v) { return fpwr(station, ado, {v}).wkc; }
  uint16_t fpwr16(uint16_t station, uint16_t ado, uint16_t v) {
    return fpwr(station, ado, {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)}).wkc;
  }
  uint16_t fpwr32(uint16_t station, uint16_t ado, uint32_t v);
  uint16_t fpwr64(uint16_t station, uint16_t ado, uint64_t v);
  uint8_t fprd8(uint16_t station, uint16_t ado) { return fprd(station, ado, 1).data[0]; }
  uint16_t fprd16(uint16_t station, uint16_t ado);
  uint32_t fprd32(uint16_t station, uint16_t ado);
  uint64_t fprd64(uint16_t station, uint16_t ado);

  // SOEM's config_init steps 1-12  for every slave: stations 0x1001.., PREOP.
  void config_init();
  // SM0/SM1 as the SII says, then PREOP (state + ack); returns the AL status read back.
  uint16_t request_state(uint16_t station, uint8_t state);
  // Writes SM2/SM3 and FMMU0 (outputs at logical 0) / FMMU1 (inputs right after), per slave.
  void config_map();
  // SII read of one word through 0x0502/0x0504/0x0508.
  uint16_t sii_read_word(uint16_t station, uint32_t word);

  uint32_t logical_outputs_base = 0x00000000;

 private:
  Segment& segment_;
};

uint16_t get16(const std::vector<uint8_t>& v, size_t at);
uint32_t get32(const std::vector<uint8_t>& v, size_t at);
uint64_t get64(const std::vector<uint8_t>& v, size_t at);
std::vector<uint8_t> bytes16(uint16_t v);
std::vector<uint8_t> bytes32(uint32_t v);
std::vector<uint8_t> bytes64(uint64_t v);

// "ff ff 00 ..." -> bytes, padded with zeros to `pad_to` (the 60-byte Ethernet minimum).
std::vector<uint8_t> hex(std::string_view text, size_t pad_to = 60);

// A line of N test devices on a manual clock, with a master, and shortcuts to the states.
struct Line {
  // `time` replaces the manual clock (benchmarks run on SteadyClock).
  explicit Line(size_t n, SegmentOptions options = {}, const Clock* time = nullptr);
  Esc& esc(size_t i) { return segment->slave(i).esc(); }
  Firmware& fw(size_t i) { return segment->slave(i).firmware(); }
  TestApplication& app(size_t i) { return *apps.at(i); }
  static uint16_t station(size_t i) { return static_cast<uint16_t>(0x1001 + i); }
  void to_preop() { master->config_init(); }
  void to_safeop();
  void to_op();
  // One cyclic frame as SOEM sends it: LRW over all outputs and inputs, FRMW 0x0910 from
  // the first slave. Returns the two replies.
  std::vector<Reply> cycle(const std::vector<uint8_t>& outputs);

  ManualClock clock;
  std::vector<std::unique_ptr<TestApplication>> apps;
  std::unique_ptr<Segment> segment;
  std::unique_ptr<TestMaster> master;
};

}  // namespace rackcat::ecat::test
