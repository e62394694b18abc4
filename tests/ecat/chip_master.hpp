// One ESC alone for the chip tests (no Segment, no firmware): the test SII
// (test_application.hpp), a manual clock, and the master's side one datagram at a time straight
// into Esc::process_datagram, plus the PDI's activation of a SyncManager the master configured.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "base/little_endian.hpp"
#include "ecat/clock.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/frame.hpp"
#include "tests/ecat/test_application.hpp"

namespace rackcat::ecat::test {

struct TestEeprom final : SiiEeprom {
  std::span<const uint8_t> image() const override { return sii; }
  std::vector<uint8_t> sii = make_test_sii();
};

struct ChipMaster {
  ChipMaster() : esc(eeprom, clock) {}

  // One datagram through the ESC as the master sends it (ETG.1000.4 §5.4: header, data,
  // working counter), at the clock's time; returns {data, wkc}.
  std::pair<std::vector<uint8_t>, uint16_t> datagram(Command cmd, uint16_t adp, uint16_t ado,
                                                     std::vector<uint8_t> data) {
    std::vector<uint8_t> d(kDatagramHeaderSize + data.size() + kWorkingCounterSize, 0);
    d[0] = static_cast<uint8_t>(cmd);
    le::put16(&d[2], adp);
    le::put16(&d[4], ado);
    le::put16(&d[6], static_cast<uint16_t>(data.size()));
    std::copy(data.begin(), data.end(), d.begin() + kDatagramHeaderSize);
    esc.begin_frame({clock.now_ns(), clock.now_ns()});
    esc.process_datagram(d.data(), static_cast<uint16_t>(data.size()));
    return {std::vector<uint8_t>(d.begin() + kDatagramHeaderSize, d.end() - 2),
            le::get16(&d[d.size() - 2])};
  }
  uint16_t apwr(uint16_t ado, std::vector<uint8_t> data) {
    return datagram(Command::Apwr, 0, ado, std::move(data)).second;
  }
  std::pair<std::vector<uint8_t>, uint16_t> aprd(uint16_t ado, uint16_t len) {
    return datagram(Command::Aprd, 0, ado, std::vector<uint8_t>(len, 0));
  }
  // SM n configured and enabled by the master (0x0800+8n, ETG.1000.4 §6.7); the PDI activates
  // it (0x0807+8n bit 0 = 0).
  void sm(int n, uint16_t start, uint16_t len, uint8_t control) {
    std::vector<uint8_t> r(8, 0);
    le::put16(&r[0], start);
    le::put16(&r[2], len);
    r[4] = control;
    r[6] = 0x01;
    apwr(static_cast<uint16_t>(0x0800 + 8 * n), r);
    const uint8_t activate = 0x00;
    esc.pdi_write(static_cast<uint16_t>(0x0807 + 8 * n), &activate, 1);
  }

  ManualClock clock;
  TestEeprom eeprom;
  Esc esc;
};

}  // namespace rackcat::ecat::test
