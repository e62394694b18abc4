// The CiA 401 layout of a RIM's slot cards (0x6000/0x6200/0x6401/0x6411) and the PDO contents
// per card type, end to end: RIM node sources -> TPDO -> control-module values; control-module
// outputs -> RPDO -> RIM outputs.
#include <gtest/gtest.h>

#include "coe/bits.hpp"
#include "mdp/card_catalogue.hpp"
#include "mdp/rack_config.hpp"
#include "modules/canopen/virtual_bus.hpp"
#include "modules/rim/master.hpp"
#include "modules/rim/node.hpp"
#include "modules/rim/sources.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::canopen;

namespace {

mdp::RackConfig small_rack() {
  return mdp::parse_rack_config(R"(
rims:
  - rim: 3
    type: 12-slot
    part_number: FI-RM1200-00
    serial_number: FI-RM1200-00-0042
    slots:
      - {slot: 1, card: CDI-13}    # 8x DI
      - {slot: 2, card: CDI-10}    # 16x DI
      - {slot: 3, card: CAI-11}    # 8x AI
      - {slot: 4, card: CTP-11}    # 8x K thermocouple
      - {slot: 5, card: CDO-10}    # 16x DO
      - {slot: 6, card: CAO-15}    # 8x AO
      - {slot: 7, card: CUR-12}    # UART: no process data on CAN
)",
                                "small.yaml");
}

}  // namespace

TEST(CanopenProfile, Cia401LayoutPerCardType) {
  const auto rack = small_rack();
  const RimProfile p = rim_profile(rack, 3);
  // Digital inputs: 8 channels -> 1 byte, 16 -> 2 bytes, each card from a byte boundary.
  EXPECT_EQ(p.di_bytes, 3u);
  EXPECT_EQ(p.input(1, 7)->offset, 0u);
  EXPECT_EQ(p.input(1, 7)->bit, 7u);
  EXPECT_EQ(p.input(2, 0)->offset, 1u);
  EXPECT_EQ(p.input(2, 9)->offset, 2u);
  EXPECT_EQ(p.input(2, 9)->bit, 1u);
  // Analog inputs and temperatures: 16 words after the digital bytes padded to even.
  EXPECT_EQ(p.ai_words, 16u);
  EXPECT_EQ(p.input(3, 0)->offset, 4u);
  EXPECT_EQ(p.input(4, 0)->kind, ChannelKind::Temperature);
  EXPECT_EQ(p.tx_bytes, 4u + 32u);
  EXPECT_EQ(p.tpdo_count(), 5u);
  // Outputs: 16 DO bits, 8 AO words.
  EXPECT_EQ(p.do_bytes, 2u);
  EXPECT_EQ(p.ao_words, 8u);
  EXPECT_EQ(p.rx_bytes, 2u + 16u);
  EXPECT_EQ(p.rpdo_count(), 3u);
  EXPECT_EQ(p.identity.serial, 42u);
  EXPECT_EQ(p.card_list.size(), 7u * 4u);
  EXPECT_EQ(p.output(7, 0), nullptr);  // the UART card has none
}

TEST(CanopenProfile, MoreProcessDataThanTheCobIdSchemeCarriesIsRefused) {
  // 24 cards of 16 analog inputs: 768 bytes = 96 TPDOs, more than node-ID 1 has (64).
  const auto rack = mdp::parse_rack_config(R"(
rims:
  - rim: 1
    type: 24-slot
    slots:
      - {slot: 1, card: CAI-15}
      - {slot: 2, card: CAI-15}
      - {slot: 3, card: CAI-15}
      - {slot: 4, card: CAI-15}
      - {slot: 5, card: CAI-15}
      - {slot: 6, card: CAI-15}
      - {slot: 7, card: CAI-15}
      - {slot: 8, card: CAI-15}
      - {slot: 9, card: CAI-15}
      - {slot: 10, card: CAI-15}
      - {slot: 11, card: CAI-15}
      - {slot: 12, card: CAI-15}
      - {slot: 13, card: CAI-15}
      - {slot: 14, card: CAI-15}
      - {slot: 15, card: CAI-15}
      - {slot: 16, card: CAI-15}
      - {slot: 17, card: CAI-15}
      - {slot: 18, card: CAI-15}
      - {slot: 19, card: CAI-15}
      - {slot: 20, card: CAI-15}
      - {slot: 21, card: CAI-15}
      - {slot: 22, card: CAI-15}
      - {slot: 23, card: CAI-15}
      - {slot: 24, card: CAI-15}
)",
                                           "big.yaml");
  try {
    rim_profile(rack, 1);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("96 PDOs"), std::string::npos) << e.what();
  }
}

TEST(CanopenProfile, PdoCobIdsFollowThePredefinedConnectionSet) {
  EXPECT_EQ(pdo_cob_id(true, 0, 3), 0x183u);
  EXPECT_EQ(pdo_cob_id(true, 3, 3), 0x483u);
  EXPECT_EQ(pdo_cob_id(false, 0, 3), 0x203u);
  EXPECT_EQ(pdo_cob_id(false, 1, 3), 0x303u);
  EXPECT_EQ(pdo_cob_id(true, 4, 3), 0x18Bu);  // TPDO5: node-ID + 8
  for (size_t k = 0; k < 12; ++k) {
    EXPECT_EQ(pdo_number(true, pdo_cob_id(true, k, 3), 3), static_cast<int>(k));
    EXPECT_EQ(pdo_number(false, pdo_cob_id(false, k, 3), 3), static_cast<int>(k));
    EXPECT_EQ(pdo_number(true, pdo_cob_id(true, k, 3), 4), -1);
  }
}

TEST(CanopenProfile, DictionaryHasIdentityIoAndMappingObjects) {
  const auto rack = small_rack();
  const RimProfile p = rim_profile(rack, 3);
  coe::ObjectDictionary od = rim_dictionary(p, 50);
  EXPECT_EQ(od.find(0x1000)->get_u(0), 401u | 0xF0000u);  // DI, DO, AI, AO present
  EXPECT_EQ(od.find(0x1017)->get_u(0), 50u);
  EXPECT_EQ(od.find(0x1018)->get_u(4), 42u);
  EXPECT_EQ(od.find(0x6000)->sub0(), 3u);
  EXPECT_EQ(od.find(0x6401)->sub0(), 16u);
  EXPECT_EQ(od.find(0x6200)->sub0(), 2u);
  EXPECT_EQ(od.find(0x6411)->sub0(), 8u);
  // TPDO1 mapping: 0x6000:01..03 (8 bits), the dummy byte 0x0005, 0x6401:01..02 (16 bits).
  const coe::Object* m = od.find(0x1A00);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->sub0(), 6u);
  EXPECT_EQ(m->get_u(1), 0x60000108u);
  EXPECT_EQ(m->get_u(4), 0x00050008u);
  EXPECT_EQ(m->get_u(5), 0x64010110u);
  EXPECT_EQ(od.find(0x1800)->get_u(1), 0x183u);
  EXPECT_EQ(od.find(0x1804)->get_u(1), 0x18Bu);
}

TEST(CanopenPdo, InputsAndOutputsCrossTheBus) {
  const auto rack = small_rack();
  VirtualCanBus bus;
  RimNode node(rack, 3, bus.attach());
  RimMaster master(rack, bus.attach());
  node.set_source(1, 2, std::make_unique<ConstantSource>(1.0));
  node.set_source(2, 15, std::make_unique<ConstantSource>(1.0));
  node.set_source(3, 0, std::make_unique<ConstantSource>(5.0));
  node.set_source(3, 7, std::make_unique<ConstantSource>(-2.5));
  node.set_source(4, 3, std::make_unique<ConstantSource>(123.4));
  double do5 = 1.0, ao3 = -7.5;
  ASSERT_TRUE(master.bind_output(3, 5, 12, &do5));
  ASSERT_TRUE(master.bind_output(3, 6, 3, &ao3));
  node.start(0);
  for (Micros t = 0; t <= 200'000; t += 1'000) {
    node.step(t);
    master.step(t);
  }
  ASSERT_EQ(master.state(3), RimState::Online) << master.reason(3);
  EXPECT_EQ(*master.input_ptr(3, 1, 2), 1.0);
  EXPECT_EQ(*master.input_ptr(3, 1, 3), 0.0);
  EXPECT_EQ(*master.input_ptr(3, 2, 15), 1.0);
  EXPECT_NEAR(*master.input_ptr(3, 3, 0), 5.0, 10.0 / 32767);
  EXPECT_NEAR(*master.input_ptr(3, 3, 7), -2.5, 10.0 / 32767);
  EXPECT_DOUBLE_EQ(*master.input_ptr(3, 4, 3), 123.4);  // 0.1 °C resolution
  EXPECT_EQ(node.output(5, 12), 1.0);
  EXPECT_EQ(node.output(5, 11), 0.0);
  EXPECT_NEAR(node.output(6, 3), -7.5, 10.0 / 32767);
  // The same values in the RIM's CiA 401 objects (what an SDO read returns).
  EXPECT_EQ(node.dictionary().find(0x6000)->get_u(1), 0x04u);
  EXPECT_EQ(node.dictionary().find(0x6000)->get_u(3), 0x80u);
  EXPECT_EQ(node.dictionary().find(0x6401)->get_i(1 + 8 + 3), 1234);
  EXPECT_EQ(node.dictionary().find(0x6200)->get_u(2), 0x10u);
  // TPDO1 on the wire: 0x183, 8 bytes: DI bytes 04 00 80, pad, AI[0] = 5 V code.
  bool seen = false;
  for (const CanFrame& f : bus.log()) {
    if (f.id == 0x183 && f.data[0] == 0x04) {
      seen = true;
      EXPECT_EQ(f.len, 8);
      EXPECT_EQ(f.data[2], 0x80);
      EXPECT_EQ(le::get16(&f.data[4]), 16384);  // round(5 * 32767 / 10)
    }
  }
  EXPECT_TRUE(seen);
  // Leaving OPERATIONAL de-energises the RIM's outputs.
  bus.attach().send(nmt_frame(NmtCommand::EnterPreOperational, 3));
  node.step(201'000);
  EXPECT_EQ(node.output(5, 12), 0.0);
  EXPECT_EQ(node.output(6, 3), 0.0);
}

TEST(CanopenRimSources, RackFileSourcesRunInTheRimProcess) {
  const auto rack = mdp::default_rack();
  VirtualCanBus bus;
  RimNode rim1(rack, 1, bus.attach());
  EXPECT_NO_THROW(apply_rack_sources(rim1, rack));
  RimNode rim2(rack, 2, bus.attach());
  EXPECT_NO_THROW(apply_rack_sources(rim2, rack));

  // A loopback to another RIM's output cannot be seen from a separate RIM process.
  const auto cross = mdp::parse_rack_config(R"(
rims:
  - rim: 1
    type: 12-slot
    slots:
      - {slot: 1, card: CDO-10}
  - rim: 2
    type: 12-slot
    slots:
      - slot: 1
        card: CDI-10
        channels:
          - {channel: 0, source: loopback, from: {rim: 1, slot: 1, channel: 0}}
)",
                                            "cross.yaml");
  RimNode node(cross, 2, bus.attach());
  try {
    apply_rack_sources(node, cross);
    FAIL() << "no error";
  } catch (const mdp::ConfigError& e) {
    EXPECT_EQ(e.file(), "cross.yaml");
    EXPECT_EQ(e.line(), 13);
    EXPECT_NE(e.problem().find("another RIM"), std::string::npos) << e.problem();
  }
}

TEST(CanopenProfile, DefaultRackPdoCountsAsDocumented) {
  // docs/CAN.md "Limits": the bus load of the default rack at a 1 ms PDO cycle.
  const auto rack = mdp::default_rack();
  const RimProfile r1 = rim_profile(rack, 1);
  const RimProfile r2 = rim_profile(rack, 2);
  EXPECT_EQ(r1.tpdo_count(), 14u);
  EXPECT_EQ(r1.rpdo_count(), 8u);
  EXPECT_EQ(r2.tpdo_count(), 7u);
  EXPECT_EQ(r2.rpdo_count(), 1u);
}
