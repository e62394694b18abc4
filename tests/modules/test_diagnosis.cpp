// The rack's causes as 0x10F3 diagnosis messages (ETG.1020 ch. 13): channel diagnosis of the
// cards (PROFINET channel error types), exception-tree causes, appears/removed pairs, the
// Emergency that goes with each stored message, filters and DC time stamps.
#include <gtest/gtest.h>

#include "coe/diagnosis_history.hpp"
#include "mdp/diagnosis_catalogue.hpp"
#include "tests/modules/rack_fixture.hpp"

namespace rackcat::modules::testing {
namespace {

namespace text = mdp::diag::text;
using coe::diag::Message;
using coe::diag::Type;

class DiagnosisTest : public RackTest {
 protected:
  std::vector<Message> history() {
    std::vector<Message> out;
    const auto& h = device.diagnosis();
    for (size_t age = 0; age < h.count(); ++age) {
      auto m = coe::diag::decode(h.slot(h.subindex_of(age)));
      EXPECT_TRUE(m.has_value());
      if (m) out.push_back(*m);
    }
    return out;
  }
  Message newest() {
    auto all = history();
    EXPECT_FALSE(all.empty());
    return all.empty() ? Message{} : all.back();
  }
  static void expect_channel_message(const Message& m, uint16_t text_id, uint16_t module,
                                     uint8_t channel) {
    EXPECT_EQ(m.text_id, text_id) << std::hex << m.text_id;
    EXPECT_EQ(m.type, mdp::diag::type_of(text_id));
    EXPECT_EQ(m.parameter(1), module);
    EXPECT_EQ(m.parameter(2), channel);
    const auto* t = mdp::diag::find(text_id);
    ASSERT_NE(t, nullptr);
    EXPECT_EQ(m.diag_code, coe::diag::emergency_diag_code(t->emergency_code));
  }
};

TEST_F(DiagnosisTest, SensorBreakAppearsAndDisappearsWithItsChannel) {
  const uint16_t tc = at(1, 15).module().number;
  rack.set_sensor_open(tc, 2, true);
  cycle();
  expect_channel_message(newest(), text::kLineBreak, tc, 2);
  auto e = drain_emergencies();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].code, 0xFF06);
  EXPECT_EQ(e[0].data[1], tc);
  EXPECT_EQ(e[0].data[3], 1u << 2);
  cycle();
  EXPECT_TRUE(drain_emergencies().empty());  // reported once
  rack.set_sensor_open(tc, 2, false);
  cycle();
  const Message removed = newest();
  expect_channel_message(removed, mdp::diag::removed_text(text::kLineBreak), tc, 2);
  EXPECT_EQ(removed.type, Type::Info);
  e = drain_emergencies();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].code, 0x0000);
}

TEST_F(DiagnosisTest, AnalogInputOverrangeAndUnderrange) {
  const uint16_t ain = at(1, 12).module().number;
  rack.set_source(ain, 5, "constant", {{"value", "12"}});
  cycle();
  expect_channel_message(newest(), text::kUpperLimit, ain, 5);
  rack.set_source(ain, 5, "constant", {{"value", "-11"}});
  cycle();
  auto all = history();
  ASSERT_GE(all.size(), 2u);
  // The upper limit goes before the lower limit comes (cause bit order).
  expect_channel_message(all[all.size() - 2], mdp::diag::removed_text(text::kUpperLimit), ain, 5);
  expect_channel_message(all.back(), text::kLowerLimit, ain, 5);
}

TEST_F(DiagnosisTest, OutputOverloadAndOvertemperature) {
  const uint16_t aout = at(1, 11).module().number;
  rack.set_output_fault(aout, 4, true, false);
  rack.refresh();
  expect_channel_message(newest(), text::kOverload, aout, 4);
  rack.set_output_fault(aout, 4, true, true);
  rack.refresh();
  expect_channel_message(newest(), text::kOvertemperature, aout, 4);
  rack.set_output_fault(aout, 4, false, false);
  rack.refresh();
  auto all = history();
  expect_channel_message(all[all.size() - 2], mdp::diag::removed_text(text::kOverload), aout, 4);
  expect_channel_message(all.back(), mdp::diag::removed_text(text::kOvertemperature), aout, 4);
  EXPECT_THROW(rack.set_output_fault(at(1, 12).module().number, 0, true, false),
               std::invalid_argument);
}

TEST_F(DiagnosisTest, OutputFaultsOfSeveralModulesReportOnceInModuleOrder) {
  const uint16_t aout = at(1, 11).module().number;
  const uint16_t dout = at(2, 7).module().number;
  ASSERT_LT(aout, dout);
  rack.set_output_fault(dout, 1, true, false);
  rack.set_output_fault(aout, 4, true, false);
  rack.set_output_fault(dout, 1, true, false);  // the same fault again
  cycle();
  const auto all = history();
  ASSERT_GE(all.size(), 2u);
  expect_channel_message(all[all.size() - 2], text::kOverload, aout, 4);
  expect_channel_message(all.back(), text::kOverload, dout, 1);
  cycle();
  EXPECT_EQ(history().size(), all.size());
}

TEST_F(DiagnosisTest, WiringFaultsNameTheirChannel) {
  const uint16_t dout = at(1, 1).module().number;
  to_op();
  cycle();
  drain_emergencies();
  const size_t before = history().size();
  // Outputs low: a short to supply reads high = unsafe wiring fault on channels 3 and 9.
  rack.set_wiring_fault(dout, 3, WiringFault::ShortToSupply);
  rack.set_wiring_fault(dout, 9, WiringFault::ShortToSupply);
  cycle();
  auto all = history();
  std::vector<Message> wiring;
  for (size_t i = before; i < all.size(); ++i) {
    if (all[i].text_id == text::kUnsafeWiring) wiring.push_back(all[i]);
  }
  ASSERT_EQ(wiring.size(), 2u);
  EXPECT_EQ(wiring[0].parameter(2), 3u);
  EXPECT_EQ(wiring[1].parameter(2), 9u);
}

TEST_F(DiagnosisTest, RimOfflineAndBackArePairedAndNameTheRim) {
  rack.set_rim_state(2, RimState::Offline);
  rack.refresh();
  bool offline = false;
  for (const auto& m : history()) {
    if (m.text_id == text::kRimOffline && m.parameter(0) == 2) offline = true;
  }
  EXPECT_TRUE(offline);
  rack.set_rim_state(2, RimState::Online);
  rack.refresh();
  EXPECT_EQ(newest().text_id, mdp::diag::removed_text(text::kRimOffline));
  EXPECT_EQ(newest().parameter(0), 2u);
}

// ETG.1020 ch. 13: with Flags bit 0 every stored message goes out as Emergency and nothing
// else does; a filtered message is neither stored nor sent.
TEST_F(DiagnosisTest, EmergenciesAndHistoryNeverDisagree) {
  const uint16_t tc = at(1, 15).module().number;
  const uint16_t ain = at(1, 12).module().number;
  auto& h = const_cast<coe::diag::History&>(device.diagnosis());
  const size_t start = history().size();
  drain_emergencies();
  auto check_in_step = [&](size_t from) {
    const auto e = drain_emergencies();
    const auto all = history();
    ASSERT_EQ(all.size() - from, e.size());
    for (size_t i = 0; i < e.size(); ++i) {
      EXPECT_EQ(all[from + i].diag_code >> 16, e[i].code);
    }
  };
  rack.set_sensor_open(tc, 0, true);
  rack.set_source(ain, 0, "constant", {{"value", "15"}});
  rack.set_rim_state(2, RimState::Connected);
  rack.refresh();
  check_in_step(start);
  // Warnings disabled: the overrange removal (info) still comes, the RIM warning removal too,
  // a new overrange (warning) is neither stored nor sent.
  ASSERT_EQ(h.write_flags(coe::diag::kFlagEmergency | coe::diag::kFlagDisableWarning),
            coe::AbortCode::None);
  size_t mark = history().size();
  rack.set_source(ain, 0, "constant", {{"value", "0"}});
  rack.set_source(ain, 1, "constant", {{"value", "15"}});
  rack.refresh();
  check_in_step(mark);
  for (size_t i = mark; i < history().size(); ++i) EXPECT_NE(history()[i].type, Type::Warning);
  // Emergencies off: messages are stored, none is sent.
  ASSERT_EQ(h.write_flags(0), coe::AbortCode::None);
  mark = history().size();
  rack.set_sensor_open(tc, 0, false);
  rack.refresh();
  EXPECT_GT(history().size(), mark);
  EXPECT_TRUE(drain_emergencies().empty());
}

TEST_F(DiagnosisTest, TimeStampsAreDcTimeWhileSync0Runs) {
  const uint16_t tc = at(1, 15).module().number;
  const uint64_t t0 = 800'000'000'000'000'000ull;  // ns since 2000
  device.sync_event(0, t0);
  rack.set_sensor_open(tc, 1, true);
  cycle();
  device.sync_event(0, t0 + 1'000'000);
  rack.set_sensor_open(tc, 1, false);
  cycle();
  auto all = history();
  ASSERT_GE(all.size(), 2u);
  const Message& a = all[all.size() - 2];
  const Message& b = all.back();
  EXPECT_FALSE(a.local_time);
  EXPECT_FALSE(b.local_time);
  EXPECT_GE(a.time_ns, t0);
  EXPECT_GE(b.time_ns, t0 + 1'000'000);
  EXPECT_LT(b.time_ns, t0 + 1'000'000'000);
  EXPECT_GT(b.time_ns, a.time_ns);
}

TEST_F(DiagnosisTest, WithoutDcTheTimeStampIsLocal) {
  rack.set_sensor_open(at(1, 15).module().number, 1, true);
  cycle();
  EXPECT_TRUE(newest().local_time);
}

}  // namespace
}  // namespace rackcat::modules::testing

namespace rackcat::modules::testing {
namespace {

// ETG.1020 ch. 13: 0x10F3:04 is TxPDO-mappable; 0x1BFF maps it (bit 0 of its byte).
TEST_F(RackTest, NewMessagesAvailableReachesTheProcessData) {
  coe::Object& tx = obj(0x1C13);
  tx.set_u(0, 0);
  tx.set_u(1, 0x1BFF);
  tx.set_u(0, 1);
  tx.hooks().after_write(tx, -1);
  go(EsmState::Init, EsmState::PreOp);
  go(EsmState::PreOp, EsmState::SafeOp);
  ASSERT_EQ(device.input_bytes(), 1u);
  cycle();
  const uint8_t before = in[0];
  rack.set_sensor_open(at(1, 15).module().number, 0, true);
  cycle();
  EXPECT_EQ(in[0], 1) << "before " << int(before);
  auto& h = const_cast<coe::diag::History&>(device.diagnosis());
  h.on_read(h.newest_subindex());
  cycle();
  EXPECT_EQ(in[0], 0);
}

}  // namespace
}  // namespace rackcat::modules::testing
