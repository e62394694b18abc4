// The firmware alone, against a fake PDI port (no chip): the ESM transition table of
// ETG.1000.6 Table 8, every AL status code it produces (Table 11), the error flag and its
// acknowledge, local errors, and the mailbox rules of ETG.1000.4 §5.6/§6.7.3 (counter, double
// write, repeat, header checks, dispatch by type and state).
#include <gtest/gtest.h>

#include <memory>

#include "ecat/slave/firmware.hpp"
#include "tests/ecat/fake_pdi.hpp"
#include "tests/ecat/test_application.hpp"

namespace rackcat::ecat::test {
namespace {

struct FirmwareTest : ::testing::Test {
  FirmwareTest() { fw = std::make_unique<Firmware>(pdi, app); }

  // The master's SyncManager configuration, written as the ESC would hold it.
  void sm(int n, uint16_t start, uint16_t len, uint8_t control, bool enable = true) {
    const auto base = static_cast<uint16_t>(0x0800 + 8 * n);
    pdi.put16(base, start);
    pdi.put16(base + 2, len);
    pdi.mem[base + 4] = control;
    pdi.mem[base + 6] = enable ? 0x01 : 0x00;
    pdi.raise_event(0x0010);
  }
  void mailbox_sms() {
    sm(0, kMbxOutStart, kMbxSize, 0x26);
    sm(1, kMbxInStart, kMbxSize, 0x22);
  }
  void pd_sms() {
    sm(2, kOutputsStart, kOutputBytes, 0x64);
    sm(3, kInputsStart, kInputBytes, 0x20);
  }
  // AL control written by the master (AL event bit 0), one firmware pass; AL status back.
  uint16_t request(uint8_t control) {
    pdi.mem[0x0120] = control;
    pdi.raise_event(0x0001);
    fw->poll();
    return pdi.get16(0x0130);
  }
  uint16_t code() const { return pdi.get16(0x0134); }
  void to_preop() {
    mailbox_sms();
    ASSERT_EQ(request(0x02), 0x0002);
  }
  void to_safeop() {
    to_preop();
    pd_sms();
    ASSERT_EQ(request(0x04), 0x0004);
  }
  void to_op() {
    to_safeop();
    ASSERT_EQ(request(0x08), 0x0008);
  }
  void to_boot() {
    mailbox_sms();
    ASSERT_EQ(request(0x03), 0x0003);
  }
  void bootstrap_mailbox_in_sii() {
    auto put = [&](size_t word, uint16_t v) { le::put16(&app.sii[2 * word], v); };
    put(0x14, kMbxOutStart);
    put(0x15, kMbxSize);
    put(0x16, kMbxInStart);
    put(0x17, kMbxSize);
  }

  FakePdi pdi;
  TestApplication app;
  std::unique_ptr<Firmware> fw;
};

TEST_F(FirmwareTest, PowerOnDeactivatesEverySmAndUnmasksItsEvents) {
  EXPECT_EQ(pdi.get16(0x0130), 0x0001);
  for (int n = 0; n < 16; ++n) EXPECT_EQ(pdi.mem[0x0807 + 8 * n] & 0x01, 0x01) << n;
  const uint32_t mask = le::get32(&pdi.mem[0x0204]);
  // AL control, SYNC0/1, SM activation, watchdog, SM0, SM2, SM3; not SM1 (firmware.cpp).
  EXPECT_EQ(mask & 0x0F5Du, 0x0D5Du);
}

// ETG.1000.6 Table 8: which requested transitions are taken (the rest: 0x0011, state kept).
TEST_F(FirmwareTest, TransitionTable) {
  constexpr uint8_t kStates[5] = {0x01, 0x02, 0x03, 0x04, 0x08};
  // allowed[from][to] in the order INIT, PREOP, BOOT, SAFEOP, OP.
  constexpr bool kAllowed[5][5] = {{true, true, true, false, false},
                                   {true, true, false, true, false},
                                   {true, false, true, false, false},
                                   {true, true, false, true, true},
                                   {true, true, false, true, true}};
  for (int f = 0; f < 5; ++f) {
    for (int t = 0; t < 5; ++t) {
      FakePdi fresh;
      pdi.mem = fresh.mem;
      pdi.writes.clear();
      app = TestApplication();
      bootstrap_mailbox_in_sii();
      fw = std::make_unique<Firmware>(pdi, app);
      switch (kStates[f]) {
        case 0x02:
          to_preop();
          break;
        case 0x03:
          to_boot();
          break;
        case 0x04:
          to_safeop();
          break;
        case 0x08:
          to_op();
          break;
        default:
          mailbox_sms();
          break;
      }
      if (kStates[t] == 0x04 && kStates[f] != 0x04) pd_sms();
      const uint16_t status = request(kStates[t]);
      if (kAllowed[f][t]) {
        EXPECT_EQ(status, kStates[t]) << "from " << f << " to " << t;
        EXPECT_EQ(code(), 0) << "from " << f << " to " << t;
      } else {
        EXPECT_EQ(status, kStates[f] | 0x10) << "from " << f << " to " << t;
        EXPECT_EQ(code(), 0x0011) << "from " << f << " to " << t;
      }
    }
  }
}

TEST_F(FirmwareTest, UnknownState0x0012) {
  EXPECT_EQ(request(0x05), 0x0011);
  EXPECT_EQ(code(), 0x0012);
}

TEST_F(FirmwareTest, ErrorFlagNeedsAcknowledgeOrInit) {
  to_preop();
  EXPECT_EQ(request(0x08), 0x0012);  // PREOP -> OP invalid
  EXPECT_EQ(code(), 0x0011);
  pd_sms();
  EXPECT_EQ(request(0x04), 0x0012);  // not acknowledged: ignored
  EXPECT_EQ(code(), 0x0011);
  EXPECT_EQ(request(0x14), 0x0004);  // acknowledged: taken, code cleared
  EXPECT_EQ(code(), 0x0000);
  EXPECT_EQ(request(0x08), 0x0008);
  EXPECT_EQ(request(0x03), 0x0018);  // OP -> BOOT invalid
  EXPECT_EQ(request(0x01), 0x0001);  // INIT is always taken
  EXPECT_EQ(code(), 0x0000);
}

TEST_F(FirmwareTest, BootstrapNotSupported0x0013) {
  mailbox_sms();
  EXPECT_EQ(request(0x03), 0x0011);
  EXPECT_EQ(code(), 0x0013);
}

TEST_F(FirmwareTest, InvalidBootMailbox0x0015) {
  bootstrap_mailbox_in_sii();
  sm(0, 0x1200, kMbxSize, 0x26);
  sm(1, kMbxInStart, kMbxSize, 0x22);
  EXPECT_EQ(request(0x03), 0x0011);
  EXPECT_EQ(code(), 0x0015);
}

TEST_F(FirmwareTest, InvalidMailboxConfig0x0016) {
  sm(0, kMbxOutStart, 64, 0x26);  // shorter than the SII says
  sm(1, kMbxInStart, kMbxSize, 0x22);
  EXPECT_EQ(request(0x02), 0x0011);
  EXPECT_EQ(code(), 0x0016);
  // SM1 with the wrong direction.
  sm(0, kMbxOutStart, kMbxSize, 0x26);
  sm(1, kMbxInStart, kMbxSize, 0x26);
  EXPECT_EQ(request(0x12), 0x0011);
  EXPECT_EQ(code(), 0x0016);
}

TEST_F(FirmwareTest, MailboxSmChangedInPreopFallsToInit0x0016) {
  to_preop();
  sm(0, 0x1400, kMbxSize, 0x26);
  fw->poll();
  EXPECT_EQ(pdi.get16(0x0130), 0x0011);
  EXPECT_EQ(code(), 0x0016);
}

TEST_F(FirmwareTest, InvalidSmConfig0x0017) {
  to_preop();
  pd_sms();
  sm(4, 0x0F00, 8, 0x00);  // a SyncManager in the register area
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x0017);
  sm(4, 0x1100, 8, 0x00, true);  // overlapping SM2
  EXPECT_EQ(request(0x14), 0x0012);
  EXPECT_EQ(code(), 0x0017);
}

TEST_F(FirmwareTest, SmWatchdog0x001B) {
  to_op();
  pdi.mem[0x0440] = 0x00;  // expired
  pdi.raise_event(0x0040);
  fw->poll();
  EXPECT_EQ(pdi.get16(0x0130), 0x0014);
  EXPECT_EQ(code(), 0x001B);
  EXPECT_EQ(app.watchdog_expiries, 1);
}

TEST_F(FirmwareTest, InvalidOutputAndInputConfig0x001D0x001E) {
  to_preop();
  sm(2, kOutputsStart, kOutputBytes - 1, 0x64);
  sm(3, kInputsStart, kInputBytes, 0x20);
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x001D);
  sm(2, kOutputsStart, kOutputBytes, 0x64);
  sm(3, kInputsStart, kInputBytes, 0x24);  // wrong direction
  EXPECT_EQ(request(0x14), 0x0012);
  EXPECT_EQ(code(), 0x001E);
  // In SAFEOP, a master that disables SM2 sends the slave back to PREOP.
  sm(3, kInputsStart, kInputBytes, 0x20);
  EXPECT_EQ(request(0x14), 0x0004);
  sm(2, kOutputsStart, kOutputBytes, 0x64, false);
  fw->poll();
  EXPECT_EQ(pdi.get16(0x0130), 0x0012);
  EXPECT_EQ(code(), 0x001D);
}

TEST_F(FirmwareTest, FatalSyncError0x002C) {
  to_preop();
  pd_sms();
  le::put32(&pdi.mem[0x09A0], 1'000'000);
  pdi.mem[0x0981] = 0x03;
  EXPECT_EQ(request(0x04), 0x0004);  // synchronised
  pdi.mem[0x0981] = 0x00;            // SYNC0 stopped
  fw->poll();
  EXPECT_EQ(pdi.get16(0x0130), 0x0014);
  EXPECT_EQ(code(), 0x002C);
}

TEST_F(FirmwareTest, InvalidDcSyncConfig0x0030) {
  to_preop();
  pd_sms();
  pdi.mem[0x0981] = 0x02;  // SYNC0 without the cyclic unit
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x0030);
  pdi.mem[0x0981] = 0x03;  // SYNC0 with cycle time 0
  EXPECT_EQ(request(0x14), 0x0012);
  EXPECT_EQ(code(), 0x0030);
}

TEST_F(FirmwareTest, DeviceVetoSetsItsCode) {
  app.veto_code = 0x0070;
  app.veto_to = EsmState::SafeOp;
  to_preop();
  pd_sms();
  EXPECT_EQ(request(0x04), 0x0012);
  EXPECT_EQ(code(), 0x0070);
}

TEST_F(FirmwareTest, LocalErrorOnlyStepsDown) {
  to_op();
  fw->application_error(EsmState::SafeOp, 0x0050);
  EXPECT_EQ(pdi.get16(0x0130), 0x0014);
  EXPECT_EQ(code(), 0x0050);
  fw->application_error(EsmState::Op, 0x0051);  // never rises
  EXPECT_EQ(pdi.get16(0x0130), 0x0014);
  EXPECT_EQ(code(), 0x0051);
  fw->application_restart();
  EXPECT_EQ(pdi.get16(0x0130), 0x0001);
  EXPECT_EQ(code(), 0x0000);
}

struct Recorder final : EsmObserver {
  void on_transition(EsmState from, EsmState to) override { transitions.emplace_back(from, to); }
  void on_al_error(EsmState from, EsmState state, EsmState requested, uint8_t al_control,
                   uint16_t code) override {
    errors.emplace_back(requested, code);
    error_states.emplace_back(from, state);
    controls.push_back(al_control);
  }
  std::vector<std::pair<EsmState, EsmState>> transitions;
  std::vector<std::pair<EsmState, uint16_t>> errors;
  std::vector<std::pair<EsmState, EsmState>> error_states;
  std::vector<uint8_t> controls;
};

TEST_F(FirmwareTest, ObserverHearsTransitionsAndCodes) {
  Recorder r;
  fw->set_observer(&r);
  to_preop();
  request(0x08);
  ASSERT_EQ(r.transitions.size(), 1u);
  EXPECT_EQ(r.transitions[0], std::make_pair(EsmState::Init, EsmState::PreOp));
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_EQ(r.errors[0], std::make_pair(EsmState::Op, uint16_t{0x0011}));
  EXPECT_EQ(r.error_states[0], std::make_pair(EsmState::PreOp, EsmState::PreOp));  // refused
  EXPECT_EQ(r.controls[0], 0x08);
}

// ---- process data ----------------------------------------------------------------------

TEST_F(FirmwareTest, OutputsReachTheDeviceInOpAndInputsFollow) {
  to_safeop();
  // SAFEOP entry wrote the first inputs.
  EXPECT_EQ(std::vector<uint8_t>(&pdi.mem[kInputsStart], &pdi.mem[kInputsStart + kInputBytes]),
            app.inputs_value);
  pdi.mem[kOutputsStart] = 0xAB;
  pdi.raise_event(0x0400);
  fw->poll();
  EXPECT_EQ(app.outputs_count, 0);  // SAFEOP: outputs stay safe
  ASSERT_EQ(request(0x08), 0x0008);
  app.inputs_value = {1, 2, 3, 4, 5, 6};
  pdi.raise_event(0x0400);
  fw->poll();
  EXPECT_EQ(app.outputs_count, 1);
  EXPECT_EQ(app.last_outputs[0], 0xAB);
  EXPECT_EQ(std::vector<uint8_t>(&pdi.mem[kInputsStart], &pdi.mem[kInputsStart + kInputBytes]),
            app.inputs_value);
}

// The device's "unchanged" (Application::update_inputs returns false) spares the SM3 write:
// SM3 keeps serving the image it has (ETG.1000.4 §6.7.2).
struct InputsHandOverTest : FirmwareTest {
  int sm3_writes() const {
    int n = 0;
    for (const auto& w : pdi.writes) n += w.address == kInputsStart ? 1 : 0;
    return n;
  }
  std::vector<uint8_t> sm3() const {
    return {&pdi.mem[kInputsStart], &pdi.mem[kInputsStart + kInputBytes]};
  }
  void master_writes_outputs() {
    pdi.raise_event(0x0400);
    fw->poll();
  }
};

TEST_F(InputsHandOverTest, UnchangedImageIsNotWrittenAgain) {
  to_op();
  const int before = sm3_writes();
  const int asked = app.inputs_count;
  app.inputs_changed = false;
  master_writes_outputs();
  master_writes_outputs();
  EXPECT_EQ(app.inputs_count, asked + 2);  // the device is asked every cycle
  EXPECT_EQ(sm3_writes(), before);
  EXPECT_EQ(sm3(), app.inputs_value);  // SM3 still serves the last image
}

TEST_F(InputsHandOverTest, ChangedImageIsWritten) {
  to_op();
  app.inputs_changed = false;
  master_writes_outputs();
  const int before = sm3_writes();
  app.inputs_changed = true;
  app.inputs_value = {9, 8, 7, 6, 5, 4};
  master_writes_outputs();
  EXPECT_EQ(sm3_writes(), before + 1);
  EXPECT_EQ(sm3(), app.inputs_value);
}

TEST_F(InputsHandOverTest, FirstImageAfterSafeopAlwaysGoesOut) {
  app.inputs_changed = false;
  to_safeop();
  EXPECT_EQ(sm3_writes(), 1);
  // Back to PREOP and into SAFEOP again: the next pd_start hands over its first image too.
  ASSERT_EQ(request(0x02), 0x0002);
  ASSERT_EQ(request(0x04), 0x0004);
  EXPECT_EQ(sm3_writes(), 2);
  master_writes_outputs();
  EXPECT_EQ(sm3_writes(), 2);
}

// ---- mailbox ---------------------------------------------------------------------------

struct MailboxTest : FirmwareTest {
  MailboxTest() { to_preop(); }
  // The master writes SM0 (the ESC sets "full" and AL event bit 8); one firmware pass.
  void master_writes(std::vector<uint8_t> msg) {
    std::copy(msg.begin(), msg.end(), &pdi.mem[kMbxOutStart]);
    pdi.mem[0x0805] |= 0x08;
    pdi.raise_event(0x0100);
    fw->poll();
  }
  // The master reads SM1 if it is full (the ESC clears "full", AL event bit 9).
  std::vector<uint8_t> master_reads() {
    if ((pdi.mem[0x080D] & 0x08) == 0) return {};
    std::vector<uint8_t> v(&pdi.mem[kMbxInStart], &pdi.mem[kMbxInStart] + kMbxSize);
    pdi.mem[0x080D] &= static_cast<uint8_t>(~0x08);
    pdi.raise_event(0x0200);
    fw->poll();
    return v;
  }
  static std::vector<uint8_t> coe(uint8_t counter, uint8_t marker = 0, uint8_t type = 3) {
    return {4, 0, 0, 0, 0, static_cast<uint8_t>(counter << 4 | type), 0x00, 0x20, marker, 0};
  }
  static uint8_t counter_of(const std::vector<uint8_t>& m) { return (m[5] >> 4) & 7; }
};

TEST_F(MailboxTest, CounterCyclesOneToSevenOverEveryMessage) {
  std::vector<uint8_t> counters;
  for (int i = 0; i < 8; ++i) {
    master_writes(coe(static_cast<uint8_t>(i % 7 + 1)));
    counters.push_back(counter_of(master_reads()));
  }
  app.pending_emergency = {0x00, 0x10};
  fw->poll();
  counters.push_back(counter_of(master_reads()));
  EXPECT_EQ(counters, (std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 1, 2}));
}

TEST_F(MailboxTest, RepeatedCounterAndBytesIsADoubleWrite) {
  master_writes(coe(1));
  EXPECT_FALSE(master_reads().empty());
  master_writes(coe(1));  // same bytes, same counter: dropped
  EXPECT_TRUE(master_reads().empty());
  EXPECT_EQ(app.mailbox_requests, 1);
  master_writes(coe(1, 0x55));  // same counter, other bytes: a new request
  EXPECT_FALSE(master_reads().empty());
  master_writes(coe(0));  // counter 0 is not counted: always executed
  master_reads();
  master_writes(coe(0));
  master_reads();
  EXPECT_EQ(app.mailbox_requests, 4);
}

TEST_F(MailboxTest, RepeatRequestSendsTheLastMessageAgain) {
  master_writes(coe(1, 0x77));
  const auto first = master_reads();
  ASSERT_FALSE(first.empty());
  // The master toggles SM1's repeat request (0x080E bit 1).
  pdi.mem[0x080E] ^= 0x02;
  pdi.raise_event(0x0010);
  fw->poll();
  EXPECT_EQ(pdi.mem[0x080F] & 0x02, 0x02);  // acknowledged
  EXPECT_EQ(master_reads(), first);         // same bytes, same counter
  EXPECT_EQ(app.mailbox_requests, 1);
}

TEST_F(MailboxTest, HeaderChecksAnswerWithMailboxErrors) {
  auto detail = [](const std::vector<uint8_t>& m) {
    return std::make_pair(static_cast<int>(m[5] & 0x0F), le::get16(&m[8]));
  };
  master_writes(coe(1, 0, 5));  // SoE: not registered
  EXPECT_EQ(detail(master_reads()), std::make_pair(0, uint16_t{0x0002}));
  auto too_long = coe(2);
  too_long[0] = 200;  // longer than SM0
  master_writes(too_long);
  EXPECT_EQ(detail(master_reads()), std::make_pair(0, uint16_t{0x0008}));
  auto channel = coe(3);
  channel[4] = 0x01;
  master_writes(channel);
  EXPECT_EQ(detail(master_reads()), std::make_pair(0, uint16_t{0x0003}));
  EXPECT_EQ(app.mailbox_requests, 0);
}

// ETG.1000.6 §5.2.3: an EoE request (type 2) to a slave without EoE - the whole error reply:
// Length 4, Address of the request, type 0 with the slave's counter 1, service 0x0001,
// detail 0x0002.
TEST_F(MailboxTest, MailboxErrorGoldenBytes) {
  master_writes({0x04, 0x00, 0x34, 0x12, 0x00, 0x12, 0xAA, 0xBB, 0xCC, 0xDD});
  const auto reply = master_reads();
  ASSERT_GE(reply.size(), 10u);
  EXPECT_EQ(std::vector<uint8_t>(reply.begin(), reply.begin() + 10),
            (std::vector<uint8_t>{0x04, 0x00, 0x34, 0x12, 0x00, 0x10, 0x01, 0x00, 0x02, 0x00}));
}

// A protocol sees only the mailbox data and answers a header problem of its own with an error
// code; the server frames both kinds of answer.
struct ErrorProtocol final : MailboxProtocol {
  mailbox::Answer on_request(const MailboxRequest& r, std::span<uint8_t> reply) override {
    seen.assign(r.data.begin(), r.data.end());
    address = r.address;
    priority = r.priority;
    capacity = r.capacity;
    if (r.data.size() < 2) return {0, mailbox::Error::SizeTooShort};
    reply[0] = 0xA5;
    return {1, mailbox::Error::None};
  }
  std::vector<uint8_t> seen;
  uint16_t address = 0;
  uint8_t priority = 0;
  size_t capacity = 0;
};

TEST_F(MailboxTest, ProtocolsGetTheDataAndTheServerFramesTheirAnswers) {
  ErrorProtocol eoe;
  fw->mailbox().add(mailbox::Type::EoE, eoe);
  // Length 3, address 0x1001, priority 2, EoE with counter 1.
  master_writes({0x03, 0x00, 0x01, 0x10, 0x80, 0x12, 0x01, 0x02, 0x03});
  EXPECT_EQ(eoe.seen, (std::vector<uint8_t>{0x01, 0x02, 0x03}));
  EXPECT_EQ(eoe.address, 0x1001);
  EXPECT_EQ(eoe.priority, 2);
  EXPECT_EQ(eoe.capacity, kMbxSize - 6u);
  auto reply = master_reads();
  EXPECT_EQ(std::vector<uint8_t>(reply.begin(), reply.begin() + 7),
            (std::vector<uint8_t>{0x01, 0x00, 0x00, 0x00, 0x00, 0x12, 0xA5}));
  // Too short for the protocol's own header: mailbox error 0x0006 from the server.
  master_writes({0x01, 0x00, 0x01, 0x10, 0x00, 0x22, 0x01});
  reply = master_reads();
  EXPECT_EQ(std::vector<uint8_t>(reply.begin(), reply.begin() + 10),
            (std::vector<uint8_t>{0x04, 0x00, 0x01, 0x10, 0x00, 0x20, 0x01, 0x00, 0x06, 0x00}));
}

TEST_F(MailboxTest, RequestWaitsWhileSm1IsFull) {
  master_writes(coe(1));
  pdi.mem[0x0805] |= 0x08;  // a second request before the master read the first reply
  std::copy_n(coe(2).begin(), 10, &pdi.mem[kMbxOutStart]);
  pdi.raise_event(0x0100);
  fw->poll();
  EXPECT_EQ(app.mailbox_requests, 1);
  master_reads();  // SM1 free: the waiting request is served
  EXPECT_EQ(app.mailbox_requests, 2);
}

struct BootProtocol final : MailboxProtocol {
  mailbox::Answer on_request(const MailboxRequest&, std::span<uint8_t> reply) override {
    ++requests;
    std::fill_n(reply.begin(), 2, uint8_t{0});
    return {2, mailbox::Error::None};
  }
  void reset() override { ++resets; }
  int requests = 0;
  int resets = 0;
};

TEST_F(MailboxTest, ProtocolsServeTheStatesTheyRegisteredFor) {
  BootProtocol foe;
  fw->mailbox().add(mailbox::Type::FoE, foe, MailboxServer::kBoot);
  master_writes(coe(
      1, 0, static_cast<uint8_t>(mailbox::Type::FoE)));  // PREOP: FoE is a bootstrap protocol here
  EXPECT_EQ(le::get16(&master_reads()[8]), 0x0002);
  EXPECT_EQ(foe.requests, 0);
  ASSERT_EQ(request(0x01), 0x0001);
  EXPECT_EQ(foe.resets, 1);  // the mailbox closed
  bootstrap_mailbox_in_sii();
  ASSERT_EQ(request(0x03), 0x0003);
  master_writes(coe(2, 0, static_cast<uint8_t>(mailbox::Type::FoE)));
  EXPECT_EQ(master_reads()[5] & 0x0F, static_cast<uint8_t>(mailbox::Type::FoE));
  EXPECT_EQ(foe.requests, 1);
}

}  // namespace
}  // namespace rackcat::ecat::test
