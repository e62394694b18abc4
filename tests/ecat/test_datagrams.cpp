// Golden frames for every datagram type and working-counter rule (ETG.1000.4 §5.3 frame
// structure, §5.4 commands, Table 14 command types, working counter increments), written
// byte by byte from the specification. The reply is the same frame at full length with bit
// 0x02 of the first source-MAC byte set.
#include <gtest/gtest.h>

#include "ecat/registers.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

std::vector<uint8_t> run(Line& line, std::vector<uint8_t> frame) {
  const size_t n = line.segment->process(frame);
  line.segment->after_frame();  // the firmware, once the reply is out
  EXPECT_EQ(n, frame.size());
  return frame;
}

TEST(Datagrams, BrdCountsSlavesAndOrsData) {
  Line line(1);
  // BRD ADO 0x0000 len 2: type 0x11 (ET1100), revision 0; ADP incremented, WKC 1.
  const auto reply = run(line, hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 0e 10"
                                   "07 01 00 00 00 00 02 00 00 00  00 00  00 00"));
  EXPECT_EQ(reply, hex("ff ff ff ff ff ff 02 00 00 00 00 01 88 a4 0e 10"
                       "07 01 01 00 00 00 02 00 00 00  11 00  01 00"));
}

TEST(Datagrams, AprdReadsIdentification) {
  Line line(1);
  // 0x0000-0x0009: type 0x11, revision 0, build 0x0002, 16 FMMUs, 16 SMs, 60 KiB RAM,
  // ports 0/1 MII (0x0F), features 0x010C (DC, 64-bit DC, enhanced SYNC activation).
  const auto reply =
      run(line, hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 16 10"
                    "01 02 00 00 00 00 0a 00 00 00  00 00 00 00 00 00 00 00 00 00  00 00"));
  EXPECT_EQ(reply, hex("ff ff ff ff ff ff 02 00 00 00 00 01 88 a4 16 10"
                       "01 02 01 00 00 00 0a 00 00 00  11 00 02 00 10 10 3c 0f 0c 01  01 00"));
}

TEST(Datagrams, PositionAddressMissesWhenNoSlaveAtThatPosition) {
  Line line(1);
  // APWR ADP 0xFFFF (position 1) to a single slave: nobody addressed, ADP wraps to 0, WKC 0.
  const auto reply = run(line, hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 0e 10"
                                   "02 03 ff ff 10 00 02 00 00 00  34 12  00 00"));
  EXPECT_EQ(reply, hex("ff ff ff ff ff ff 02 00 00 00 00 01 88 a4 0e 10"
                       "02 03 00 00 10 00 02 00 00 00  34 12  00 00"));
  EXPECT_EQ(line.esc(0).station_address(), 0);
}

TEST(Datagrams, ChainOfApwrFprdFprwNop) {
  Line line(1);
  // Four datagrams, "more follows" (bit 15 of the length field) on the first three.
  // APWR sets the station address, FPRD reads it back in the same frame, FPRW swaps user RAM
  // 0x0F80 (old value back, WKC 3), NOP is left alone.
  const auto reply = run(line, hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 38 10"
                                   "02 01 00 00 10 00 02 80 00 00  01 10  00 00"
                                   "04 02 01 10 10 00 02 80 00 00  00 00  00 00"
                                   "06 03 01 10 80 0f 02 80 00 00  aa bb  00 00"
                                   "00 04 00 00 00 00 02 00 00 00  55 66  00 00"));
  EXPECT_EQ(reply, hex("ff ff ff ff ff ff 02 00 00 00 00 01 88 a4 38 10"
                       "02 01 01 00 10 00 02 80 00 00  01 10  01 00"
                       "04 02 01 10 10 00 02 80 00 00  01 10  01 00"
                       "06 03 01 10 80 0f 02 80 00 00  00 00  03 00"
                       "00 04 00 00 00 00 02 00 00 00  55 66  00 00"));
  EXPECT_EQ(line.esc(0).read16(0x0F80), 0xBBAA);
}

TEST(Datagrams, GoldenArmwInTwoSlaveLine) {
  Line line(2);
  line.master->send(Command::Apwr, 0, 0x0F80, {0x5A});
  // ARMW ADP 0: slave 0 reads 0x5A into the datagram, slave 1 writes it; ADP +2, WKC 2.
  const auto reply = run(line, hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 0d 10"
                                   "0d 05 00 00 80 0f 01 00 00 00  00  00 00"));
  EXPECT_EQ(reply, hex("ff ff ff ff ff ff 02 00 00 00 00 01 88 a4 0d 10"
                       "0d 05 02 00 80 0f 01 00 00 00  5a  02 00"));
  EXPECT_EQ(line.esc(1).read8(0x0F80), 0x5A);
}

TEST(Datagrams, GoldenCyclicFrameInOp) {
  Line line(1);
  // The clock started at 1 s when the slave powered up: its local time is now 0x0102030405.
  line.clock.set(1'000'000'000 + 0x0102030405ull);
  line.to_op();
  // SOEM's cyclic frame: LRW over 4 output + 6 input bytes at logical 0, FRMW 0x0910 from
  // station 0x1001 (8 bytes). LRW WKC 3 (read + write), FRMW WKC 1 (the reference reads).
  const auto reply =
      run(line, hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 2a 10"
                    "0c 01 00 00 00 00 0a 80 00 00  de ad be ef 00 00 00 00 00 00  00 00"
                    "0e 02 01 10 10 09 08 00 00 00  00 00 00 00 00 00 00 00  00 00"));
  EXPECT_EQ(reply, hex("ff ff ff ff ff ff 02 00 00 00 00 01 88 a4 2a 10"
                       "0c 01 00 00 00 00 0a 80 00 00  de ad be ef 11 22 33 44 55 66  03 00"
                       "0e 02 01 10 10 09 08 00 00 00  05 04 03 02 01 00 00 00  01 00"));
  EXPECT_EQ(line.app(0).last_outputs, (std::vector<uint8_t>{0xDE, 0xAD, 0xBE, 0xEF}));
}

TEST(Datagrams, FpwrToOtherStationIsIgnored) {
  Line line(1);
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(0x1001));
  const auto r = line.master->fpwr(0x1002, 0x0F80, {0x77});
  EXPECT_EQ(r.wkc, 0);
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0);
  EXPECT_EQ(line.master->fpwr(0x1001, 0x0F80, {0x77}).wkc, 1);
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0x77);
}

TEST(Datagrams, BroadcastReadOrsAllSlavesAndIncrementsAdp) {
  Line line(2);
  line.master->send(Command::Apwr, 0x0000, 0x0010, bytes16(0x1001));
  line.master->send(Command::Apwr, 0xFFFF, 0x0010, bytes16(0x1002));
  const auto r = line.master->send(Command::Brd, 0x0000, 0x0010, {0, 0});
  EXPECT_EQ(get16(r.data, 0), 0x1003);  // 0x1001 | 0x1002
  EXPECT_EQ(r.wkc, 2);
  EXPECT_EQ(r.adp, 2);
}

TEST(Datagrams, BroadcastWriteCountsEverySlave) {
  Line line(3);
  const auto r = line.master->send(Command::Bwr, 0, 0x0F80, {0x42});
  EXPECT_EQ(r.wkc, 3);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(line.esc(i).read8(0x0F80), 0x42);
}

TEST(Datagrams, BroadcastReadWriteCountsThreePerSlave) {
  Line line(2);
  line.master->send(Command::Apwr, 0x0000, 0x0F80, {0x01});
  line.master->send(Command::Apwr, 0xFFFF, 0x0F80, {0x02});
  const auto r = line.master->send(Command::Brw, 0, 0x0F80, {0x80});
  // Each slave ORs its old byte into the datagram and writes the byte as it arrived.
  EXPECT_EQ(r.data[0], 0x83);
  EXPECT_EQ(r.wkc, 6);
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0x80);
  EXPECT_EQ(line.esc(1).read8(0x0F80), 0x81);
}

TEST(Datagrams, AprwReturnsOldValueAndWritesNew) {
  Line line(1);
  line.master->send(Command::Apwr, 0, 0x0F80, {0x10, 0x20});
  const auto r = line.master->send(Command::Aprw, 0, 0x0F80, {0x30, 0x40});
  EXPECT_EQ(r.data, (std::vector<uint8_t>{0x10, 0x20}));
  EXPECT_EQ(r.wkc, 3);
  EXPECT_EQ(line.esc(0).read16(0x0F80), 0x4030);
}

TEST(Datagrams, ArmwAddressedSlaveReadsOthersWrite) {
  Line line(3);
  line.master->send(Command::Apwr, 0x0000, 0x0F80, {0x5A});
  const auto r = line.master->send(Command::Armw, 0x0000, 0x0F80, {0x00});
  EXPECT_EQ(r.data[0], 0x5A);
  EXPECT_EQ(r.wkc, 3);  // one read + two writes
  EXPECT_EQ(r.adp, 3);
  EXPECT_EQ(line.esc(1).read8(0x0F80), 0x5A);
  EXPECT_EQ(line.esc(2).read8(0x0F80), 0x5A);
}

TEST(Datagrams, FrmwByStationAddress) {
  Line line(3);
  for (uint16_t k = 0; k < 3; ++k) {
    line.master->send(Command::Apwr, static_cast<uint16_t>(0 - k), 0x0010,
                      bytes16(Line::station(k)));
  }
  line.master->fpwr(Line::station(1), 0x0F80, {0xC3});
  const auto r = line.master->send(Command::Frmw, Line::station(1), 0x0F80, {0x00});
  EXPECT_EQ(r.data[0], 0xC3);
  EXPECT_EQ(r.wkc, 3);
  EXPECT_EQ(r.adp, Line::station(1));          // configured addressing leaves ADP alone
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0x00);  // slave 0 wrote the datagram before slave 1 read
  EXPECT_EQ(line.esc(2).read8(0x0F80), 0xC3);
}

TEST(Datagrams, AliasAddressingNeedsDlControlEnable) {
  Line line(1);
  // Alias 0x0000 comes from SII word 4; FPRD with ADP = alias only answers once 0x0103 bit 0
  // is set. Station address 0 also matches ADP 0, so use a non-zero station.
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(0x1001));
  EXPECT_EQ(line.master->fprd(0x0000, 0x0000, 1).wkc, 0);
  line.master->send(Command::Apwr, 0, 0x0103, {0x01});
  EXPECT_EQ(line.master->fprd(0x0000, 0x0000, 1).wkc, 1);
}

TEST(Datagrams, IrqFieldCarriesMaskedEcatEvents) {
  Line line(1);
  line.to_preop();
  // ECAT event mask bit 3: AL status change. The PREOP transition raised it; nobody has read
  // AL status since config_init's last read, so the next datagram carries it.
  line.master->fpwr16(0x1001, 0x0200, 0x0008);
  line.master->fpwr16(0x1001, 0x0120, 0x0001);  // back to INIT: AL status changes
  EXPECT_EQ(line.master->fprd(0x1001, 0x0F80, 1).irq & 0x0008, 0x0008);
  line.master->fprd16(0x1001, 0x0130);  // reading AL status clears the event
  EXPECT_EQ(line.master->fprd(0x1001, 0x0F80, 1).irq & 0x0008, 0);
}

TEST(Datagrams, LogicalCommandsThroughFmmus) {
  Line line(1);
  // FMMU0: logical 0x10000, 2 bytes -> physical 0x1100 (write); FMMU1: logical 0x10002,
  // 2 bytes -> physical 0x1200 (read). No SyncManagers: plain RAM.
  line.master->send(Command::Apwr, 0, 0x0600,
                    hex("00 00 01 00 02 00 00 07 00 11 00 02 01 00 00 00"
                        "02 00 01 00 02 00 00 07 00 12 00 01 01 00 00 00",
                        0));
  line.master->send(Command::Apwr, 0, 0x1200, {0xC0, 0xDE});
  // LRW: writes 11 22 to 0x1100, reads c0 de into bytes 2-3; WKC 1 (read) + 2 (write).
  const auto lrw = line.master->send_logical(Command::Lrw, 0x10000, {0x11, 0x22, 0x33, 0x44});
  EXPECT_EQ(lrw.data, (std::vector<uint8_t>{0x11, 0x22, 0xC0, 0xDE}));
  EXPECT_EQ(lrw.wkc, 3);
  EXPECT_EQ(line.esc(0).read16(0x1100), 0x2211);
  // LRD: only read FMMUs take part, WKC 1.
  const auto lrd = line.master->send_logical(Command::Lrd, 0x10000, {0, 0, 0, 0});
  EXPECT_EQ(lrd.data, (std::vector<uint8_t>{0, 0, 0xC0, 0xDE}));
  EXPECT_EQ(lrd.wkc, 1);
  // LWR: only write FMMUs, WKC 1; the read area is not touched.
  const auto lwr = line.master->send_logical(Command::Lwr, 0x10000, {0x55, 0x66, 0x77, 0x88});
  EXPECT_EQ(lwr.wkc, 1);
  EXPECT_EQ(line.esc(0).read16(0x1100), 0x6655);
  EXPECT_EQ(line.esc(0).read16(0x1200), 0xDEC0);
  // Outside every FMMU: no WKC.
  EXPECT_EQ(line.master->send_logical(Command::Lrw, 0x20000, {0, 0}).wkc, 0);
}

TEST(Datagrams, AccessCrossingEndOfAddressSpaceIsIgnored) {
  Line line(1);
  line.master->send(Command::Apwr, 0, 0x0010, bytes16(0x1001));
  EXPECT_EQ(line.master->fprd(0x1001, 0xFFFF, 2).wkc, 0);
  EXPECT_EQ(line.master->fpwr(0x1001, 0xFFFE, {1, 2, 3}).wkc, 0);
  EXPECT_EQ(line.master->fprd(0x1001, 0xFFFE, 2).wkc, 1);
}

TEST(Frames, NonEtherCatFramesAreNotAnswered) {
  Line line(1);
  auto ip = hex("ff ff ff ff ff ff 00 00 00 00 00 01 08 00 45 00");
  EXPECT_EQ(line.segment->process(ip), 0u);
  std::vector<uint8_t> runt = {0xff, 0xff, 0xff};
  EXPECT_EQ(line.segment->process(runt), 0u);
}

TEST(Frames, OtherEtherCatTypesPassUnchanged) {
  Line line(1);
  // EtherCAT header type 4 (network variables): the ESC forwards the frame untouched.
  auto frame = hex(
      "ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 0e 40 07 01 00 00 00 00 02 00 00 00 00 00 00 00");
  auto expected = frame;
  expected[6] |= 0x02;
  EXPECT_EQ(line.segment->process(frame), frame.size());
  EXPECT_EQ(frame, expected);
}

TEST(Frames, VlanTaggedFrameIsProcessed) {
  Line line(1);
  auto frame =
      hex("ff ff ff ff ff ff 00 00 00 00 00 01 81 00 00 05 88 a4 0e 10"
          "07 01 00 00 00 00 02 00 00 00 00 00 00 00");
  line.segment->process(frame);
  EXPECT_EQ(frame[30], 0x11);  // BRD data: ESC type
  EXPECT_EQ(frame[32], 0x01);  // WKC
}

TEST(Frames, DatagramRunningPastTheEndIsIgnoredAndCounted) {
  Line line(1);
  // Length field says 100 data bytes but the frame ends after 60: nothing is processed, the
  // frame comes back unchanged (but for the source-MAC mark), the error counters count it.
  auto frame =
      hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 70 10 02 01 00 00 80 0f 64 00 00 00 ee");
  auto expected = frame;
  expected[6] |= 0x02;
  EXPECT_EQ(line.segment->process(frame), frame.size());
  EXPECT_EQ(frame, expected);
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0);
  EXPECT_EQ(line.esc(0).read8(reg::kProcessingUnitError), 1);
  EXPECT_EQ(line.esc(0).read8(reg::kRxErrorCounter), 1);
}

TEST(Frames, ChainRunningPastTheEndProcessesOnlyCompleteDatagrams) {
  Line line(1);
  // First datagram complete (BWR 0x0F80 = 0x99) with "more follows"; the second header is cut.
  auto frame =
      hex("ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 1a 10"
          "08 01 00 00 80 0f 01 80 00 00 99 00 00"
          "08 02 00 00 81 0f",
          0);
  EXPECT_EQ(line.segment->process(frame), frame.size());
  EXPECT_EQ(line.esc(0).read8(0x0F80), 0x99);
  EXPECT_EQ(frame[27], 0x01);  // WKC of the complete datagram
  EXPECT_EQ(line.esc(0).read8(reg::kProcessingUnitError), 1);
}

TEST(Frames, EtherCatLengthPastTheEndIsCounted) {
  Line line(1);
  // Header length 0x7FF, far beyond the frame; the datagram inside is complete.
  auto frame = hex(
      "ff ff ff ff ff ff 00 00 00 00 00 01 88 a4 ff 17 07 01 00 00 00 00 02 00 00 00 00 00 00 00");
  line.segment->process(frame);
  EXPECT_EQ(line.esc(0).read8(reg::kProcessingUnitError), 1);
  // Writing the counter clears it (ESC datasheet 0x030C).
  line.master->send(Command::Bwr, 0, 0x030C, {0x00});
  EXPECT_EQ(line.esc(0).read8(reg::kProcessingUnitError), 0);
}

}  // namespace
}  // namespace rackcat::ecat::test
