// Logical datagrams through FMMUs that each map one whole SyncManager buffer (the cyclic process
// data) must behave exactly as the same bytes mapped piecewise (ETG.1000.4 §6.6, §6.7): the
// buffer opens on its first byte and completes on its last, with the same status 0x0805+8n,
// events 0x0210/0x0220, IRQ field, working counter and process-data watchdog. Two ESCs get the
// same SyncManagers; one maps each buffer with one FMMU, the other with two FMMUs of half a
// buffer each. Every step drives both the same way and compares what a master and the
// firmware can see. The one-FMMU chip takes each datagram either as process_datagram does
// or, as the segment hands over a logical datagram its logical-address map resolved, through
// process_logical_datagram (the way the cyclic LRW takes straight to the planned exchange of
// the input and output buffers).
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <vector>

#include "base/little_endian.hpp"
#include "ecat/frame.hpp"
#include "tests/ecat/chip_master.hpp"
#include "tests/support/fmmu_entry.hpp"

namespace rackcat::ecat::test {
namespace {

using rackcat::testing::fmmu_entry;

// SM0 mailbox the master writes, SM1 mailbox the master reads, SM2 outputs, SM3 inputs.
constexpr uint16_t kMbxOut = 0x1000;
constexpr uint16_t kMbxIn = 0x1080;
constexpr uint16_t kMbxLen = 8;
constexpr uint16_t kOut = 0x1100;
constexpr uint16_t kOutLen = 4;
constexpr uint16_t kIn = 0x1180;
constexpr uint16_t kInLen = 6;
// Logical layout: outputs at 0x10, inputs right after, the two mailboxes at 0x100 and 0x200.
constexpr uint32_t kLogOut = 0x10;
constexpr uint32_t kLogIn = kLogOut + kOutLen;
constexpr uint32_t kLogMbxOut = 0x100;
constexpr uint32_t kLogMbxIn = 0x200;

struct Chip : ChipMaster {
  explicit Chip(bool split_buffers, bool mapped = false) : split(split_buffers), by_map(mapped) {
    sm(0, kMbxOut, kMbxLen, 0x26);  // mailbox, ECAT writes, AL event
    sm(1, kMbxIn, kMbxLen, 0x22);   // mailbox, ECAT reads, AL event
    sm(2, kOut, kOutLen, 0x74);     // buffered, ECAT writes, ECAT + AL event, watchdog
    sm(3, kIn, kInLen, 0x30);       // buffered, ECAT reads, ECAT + AL event
    apwr(0x0200, {0xF0, 0x00});     // ECAT event mask: SM0-3 into the IRQ field
    struct Map {
      uint32_t logical;
      uint16_t physical;
      uint16_t len;
      uint8_t type;
    };
    const Map maps[] = {{kLogOut, kOut, kOutLen, 2},
                        {kLogIn, kIn, kInLen, 1},
                        {kLogMbxOut, kMbxOut, kMbxLen, 2},
                        {kLogMbxIn, kMbxIn, kMbxLen, 1}};
    uint16_t fmmu = 0x0600;
    for (const Map& m : maps) {
      if (!split) {
        apwr(fmmu, fmmu_entry(m.logical, m.len, 0, 7, m.physical, 0, m.type));
        fmmu += 16;
        continue;
      }
      const auto half = static_cast<uint16_t>(m.len / 2);
      apwr(fmmu, fmmu_entry(m.logical, half, 0, 7, m.physical, 0, m.type));
      apwr(static_cast<uint16_t>(fmmu + 16),
           fmmu_entry(m.logical + half, static_cast<uint16_t>(m.len - half), 0, 7,
                      static_cast<uint16_t>(m.physical + half), 0, m.type));
      fmmu += 32;
    }
  }
  bool split;
  bool by_map;  // logical datagrams through process_logical_datagram, every FMMU handed over
  // One logical datagram; returns the whole datagram as it leaves (header with the IRQ
  // field, data, working counter).
  std::vector<uint8_t> logical(Command cmd, uint32_t address, std::vector<uint8_t> data) {
    std::vector<uint8_t> d(kDatagramHeaderSize + data.size() + kWorkingCounterSize, 0);
    d[0] = static_cast<uint8_t>(cmd);
    le::put32(&d[2], address);
    le::put16(&d[6], static_cast<uint16_t>(data.size()));
    std::copy(data.begin(), data.end(), d.begin() + kDatagramHeaderSize);
    esc.begin_frame({clock.now_ns(), clock.now_ns()});
    if (by_map) {
      esc.process_logical_datagram(d.data(), static_cast<uint16_t>(data.size()), 0xFFFF);
    } else {
      esc.process_datagram(d.data(), static_cast<uint16_t>(data.size()));
    }
    return d;
  }
  // What the master and the firmware see: registers other than the FMMUs (which differ by
  // design), the process RAM of the buffers, the next timer event (watchdog), the IRQ line.
  std::vector<uint8_t> visible() const {
    std::vector<uint8_t> v;
    for (size_t a = 0; a < 0x1200; ++a) {
      if (a < 0x0600 || a >= 0x0700) v.push_back(esc.memory()[a]);
    }
    for (int i = 0; i < 8; ++i) v.push_back(static_cast<uint8_t>(esc.next_event_ns() >> 8 * i));
    v.push_back(esc.pdi_irq() ? 1 : 0);
    return v;
  }
};

std::vector<uint8_t> bytes(size_t n, uint8_t seed) {
  std::vector<uint8_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = static_cast<uint8_t>(seed + 17 * i);
  return v;
}

struct WholeBufferFmmu : ::testing::TestWithParam<bool> {
  Chip whole{false, GetParam()};
  Chip split{true};
  // Runs `step` on both chips and compares everything visible afterwards.
  void both(const char* what, const std::function<void(Chip&)>& step) {
    SCOPED_TRACE(what);
    step(whole);
    step(split);
    whole.clock.advance(1000);
    split.clock.advance(1000);
    EXPECT_EQ(whole.visible(), split.visible());
  }
  void logical(const char* what, Command cmd, uint32_t address, std::vector<uint8_t> data) {
    SCOPED_TRACE(what);
    const auto a = whole.logical(cmd, address, data);
    const auto b = split.logical(cmd, address, data);
    EXPECT_EQ(a, b);
    whole.clock.advance(1000);
    split.clock.advance(1000);
    EXPECT_EQ(whole.visible(), split.visible());
  }
};

TEST_P(WholeBufferFmmu, CyclicProcessDataAndFirmwareTurns) {
  for (uint8_t cycle = 0; cycle < 5; ++cycle) {
    logical("LRW", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, cycle));
    both("PDI reads the outputs", [](Chip& c) {
      std::vector<uint8_t> out(kOutLen);
      c.esc.pdi_read_buffer(2, kOut, out.data(), kOutLen);
    });
    if (cycle % 2 == 0) {
      both("PDI writes the inputs", [cycle](Chip& c) {
        const auto in = bytes(kInLen, static_cast<uint8_t>(0x40 + cycle));
        c.esc.pdi_write_buffer(3, kIn, in.data(), kInLen);
      });
    }
  }
  logical("LRD", Command::Lrd, kLogOut, bytes(kOutLen + kInLen, 0x90));
  logical("LWR", Command::Lwr, kLogOut, bytes(kOutLen + kInLen, 0xA0));
  logical("LRW over the inputs only", Command::Lrw, kLogIn, bytes(kInLen, 0xB0));
  logical("LRW with room around", Command::Lrw, kLogOut - 4, bytes(kOutLen + kInLen + 8, 0xC0));
  logical("LRW from the middle of the outputs", Command::Lrw, kLogOut + 2, bytes(8, 0xD0));
  logical("LRW up to the middle of the outputs", Command::Lrw, kLogOut, bytes(2, 0xE0));
  logical("LRW of the whole outputs", Command::Lrw, kLogOut, bytes(kOutLen, 0xF0));
}

TEST_P(WholeBufferFmmu, DeactivatedSyncManagerAndWriteProtection) {
  logical("LRW", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 1));
  both("PDI deactivates SM2", [](Chip& c) {
    const uint8_t deactivate = 0x01;
    c.esc.pdi_write(0x0817, &deactivate, 1);
  });
  logical("LRW, SM2 deactivated", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 2));
  both("PDI activates SM2", [](Chip& c) {
    const uint8_t activate = 0x00;
    c.esc.pdi_write(0x0817, &activate, 1);
  });
  both("ESC write protection on", [](Chip& c) { c.apwr(0x0031, {0x01}); });
  logical("LRW, ESC write protected", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 3));
  both("ESC write protection off", [](Chip& c) {
    c.apwr(0x0030, {0x01});
    c.apwr(0x0031, {0x00});
  });
  logical("LRW again", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 4));
}

TEST_P(WholeBufferFmmu, MailboxesThroughFmmus) {
  logical("LRD of the empty mailbox", Command::Lrd, kLogMbxIn, bytes(kMbxLen, 0));
  both("PDI writes a reply", [](Chip& c) {
    const auto reply = bytes(kMbxLen, 0x21);
    c.esc.pdi_write(kMbxIn, reply.data(), kMbxLen);
  });
  logical("LRD of the reply", Command::Lrd, kLogMbxIn, bytes(kMbxLen, 0));
  logical("LRD once more", Command::Lrd, kLogMbxIn, bytes(kMbxLen, 0));
  logical("LWR of a request", Command::Lwr, kLogMbxOut, bytes(kMbxLen, 0x31));
  logical("LWR into the full mailbox", Command::Lwr, kLogMbxOut, bytes(kMbxLen, 0x41));
  both("PDI reads the request", [](Chip& c) {
    std::vector<uint8_t> request(kMbxLen);
    c.esc.pdi_read(kMbxOut, request.data(), kMbxLen);
  });
  logical("LWR of the next request", Command::Lwr, kLogMbxOut, bytes(kMbxLen, 0x51));
}

TEST_P(WholeBufferFmmu, ReadAndWriteOfTheSameBytes) {
  // A read FMMU over the outputs' logical bytes as well: the LRW returns the old outputs while
  // writing the new ones (ETG.1000.4 §5.4.3).
  both("read FMMU over the outputs",
       [](Chip& c) { c.apwr(0x06F0, fmmu_entry(kLogOut, kOutLen, 0, 7, kOut, 0, 1)); });
  logical("LRW", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 5));
  logical("LRW", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 6));
}

TEST_P(WholeBufferFmmu, ReconfiguredFmmuIsFollowed) {
  logical("LRW", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 7));
  both("outputs moved to logical 0x40", [](Chip& c) {
    c.apwr(0x0600, {0x40});
    if (c.split) c.apwr(0x0610, {0x40 + kOutLen / 2});  // the second half of the outputs
  });
  logical("LRW at the old place", Command::Lrw, kLogOut, bytes(kOutLen + kInLen, 8));
  logical("LWR at the new place", Command::Lwr, 0x40, bytes(kOutLen, 9));
}

// An image in two datagrams (a master that cuts it where a frame ends: here the outputs in one
// LRW, the inputs in the next), every cycle: the ESC keeps a plan for each. A third datagram
// replaces one of them, and a reconfigured FMMU drops both.
TEST_P(WholeBufferFmmu, ImageInTwoDatagramsEveryCycle) {
  for (uint8_t cycle = 0; cycle < 4; ++cycle) {
    logical("LRW of the outputs", Command::Lrw, kLogOut, bytes(kOutLen, cycle));
    logical("LRW of the inputs", Command::Lrw, kLogIn, bytes(kInLen, 0x10 + cycle));
    both("PDI turn", [cycle](Chip& c) {
      std::vector<uint8_t> out(kOutLen);
      c.esc.pdi_read_buffer(2, kOut, out.data(), kOutLen);
      const auto in = bytes(kInLen, static_cast<uint8_t>(0x60 + cycle));
      c.esc.pdi_write_buffer(3, kIn, in.data(), kInLen);
    });
    if (cycle == 1) logical("LRD of both, once", Command::Lrd, kLogOut, bytes(kOutLen + kInLen, 0));
  }
  both("outputs moved to logical 0x40", [](Chip& c) {
    c.apwr(0x0600, {0x40});
    if (c.split) c.apwr(0x0610, {0x40 + kOutLen / 2});
  });
  logical("LRW at the outputs' old place", Command::Lrw, kLogOut, bytes(kOutLen, 0x20));
  logical("LRW of the inputs", Command::Lrw, kLogIn, bytes(kInLen, 0x21));
  logical("LRW at the outputs' new place", Command::Lrw, 0x40, bytes(kOutLen, 0x22));
  logical("LRW of the inputs again", Command::Lrw, kLogIn, bytes(kInLen, 0x23));
}

INSTANTIATE_TEST_SUITE_P(Datagram, WholeBufferFmmu, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "ThroughTheLogicalMap" : "AsProcessDatagram";
                         });

}  // namespace
}  // namespace rackcat::ecat::test
