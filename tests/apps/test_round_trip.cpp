// The round trip (docs/LINE.md "Round trip"): `rackcat esi` of a rack, fed back as an ESI
// device (device/esi_device.hpp), serves the same SII image and the same SDO information, byte
// for byte, as the native rack: every SDO Information service (ETG.1000.6 §5.6.3: Get OD List,
// Get Object Description, Get Entry Description with every value-info bit) answered by both.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "apps/rack_slave/rack_loading.hpp"
#include "apps/rack_slave/rack_slave.hpp"
#include "device/esi_device.hpp"
#include "device/generic_device.hpp"
#include "esi/rack.hpp"
#include "mdp/rack_config.hpp"
#include "tests/support/coe_frames.hpp"

namespace rackcat::apps {
namespace {

using testing::Bytes;
using testing::coe_message;

constexpr uint8_t kSdoInfo = 0x08;  // CoE service (ETG.1000.6 Table 29)

// One mailbox request to `app` and every fragment of its answer, the mailbox header's counter
// (byte 5 bits 4..6) cleared so two devices' answers compare.
Bytes ask(ecat::MailboxProtocol& coe, const Bytes& request) {
  Bytes all;
  std::vector<uint8_t> reply(1486);
  size_t n = coe.on_request(request, reply, EsmState::PreOp);
  while (n > 0) {
    reply[5] = static_cast<uint8_t>(reply[5] & 0x8F);
    all.insert(all.end(), reply.begin(), reply.begin() + static_cast<long>(n));
    n = coe.poll(reply);
  }
  return all;
}

void to_preop(ecat::Application& app) {
  ASSERT_EQ(app.on_state_request(EsmState::Init, EsmState::PreOp), 0);
  app.on_state_changed(EsmState::Init, EsmState::PreOp);
}

class RoundTripTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rackcat-round-trip-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

void round_trip(const mdp::RackConfig& config, const std::string& state_dir) {
  RackSlave native(config, state_dir, 0);
  const auto offline = offline_device(config);
  const coe::ObjectDictionary& native_od = offline->dictionary();
  const std::string xml = esi::write_esi(*offline);
  device::EsiDevice esi = device::parse_esi_device(xml, "rack.xml", {});
  // The serial number is the rack's position in the segment, not part of the ESI.
  esi.description.serial = config.control.serial;
  device::GenericDevice copy(std::move(esi));
  const coe::ObjectDictionary& copy_od = copy.esi().dictionary;
  size_t renamed = 0;

  const auto a = native.eeprom();
  const auto b = copy.eeprom();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i], b[i]) << "SII byte " << i << " (word 0x" << std::hex << i / 2 << ")";
  }
  EXPECT_EQ(native.process_data_sizes().outputs, copy.process_data_sizes().outputs);
  EXPECT_EQ(native.process_data_sizes().inputs, copy.process_data_sizes().inputs);

  to_preop(native);
  to_preop(copy);
  uint8_t counter = 0;
  auto next = [&] { return counter = static_cast<uint8_t>(counter % 7 + 1); };
  // Get OD List, all objects (list type 1).
  const Bytes list_req = coe_message(next(), kSdoInfo, {0x01, 0x00, 0x00, 0x00, 0x01, 0x00});
  const Bytes list = ask(native.coe_mailbox(), list_req);
  ASSERT_EQ(list, ask(copy.coe_mailbox(), list_req));
  ASSERT_GT(list.size(), 16u);
  // The indices of the list: after each fragment's 8-byte mailbox + 2-byte CoE + 4-byte info
  // header (+ 2 bytes list type in the first).
  std::vector<uint16_t> indices;
  for (size_t at = 0, first = 1; at < list.size(); first = 0) {
    const size_t len = static_cast<size_t>(list[at] | (list[at + 1] << 8));
    for (size_t k = at + 6 + 8 + (first ? 2 : 0); k + 1 < at + 6 + len; k += 2) {
      indices.push_back(static_cast<uint16_t>(list[k] | (list[k + 1] << 8)));
    }
    at += 6 + len;
  }
  ASSERT_GT(indices.size(), 10u);
  size_t entries = 0;
  for (const uint16_t index : indices) {
    const Bytes od_req = coe_message(
        next(), kSdoInfo,
        {0x03, 0x00, 0x00, 0x00, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8)});
    const Bytes od = ask(native.coe_mailbox(), od_req);
    ASSERT_EQ(od, ask(copy.coe_mailbox(), od_req)) << "object description 0x" << std::hex << index;
    // Max subindex: byte 8+2+4+2+2+1 = 19 of the answer.
    const uint8_t max_sub = od.size() > 19 ? od[19] : 0;
    for (int sub = 0; sub <= max_sub; ++sub) {
      for (const uint8_t info : {uint8_t{0x00}, uint8_t{0x78}}) {
        const Bytes e_req =
            coe_message(next(), kSdoInfo,
                        {0x05, 0x00, 0x00, 0x00, static_cast<uint8_t>(index),
                         static_cast<uint8_t>(index >> 8), static_cast<uint8_t>(sub), info});
        Bytes a = ask(native.coe_mailbox(), e_req);
        Bytes b = ask(copy.coe_mailbox(), e_req);
        const coe::Object* obj = copy_od.find(index);
        const coe::Object* native_obj = native_od.find(index);
        if (obj != nullptr && obj->code() == coe::ObjectCode::Array && sub >= 1 &&
            native_obj != nullptr && native_obj->entry(static_cast<uint8_t>(sub)) != nullptr &&
            obj->entry(static_cast<uint8_t>(sub)) != nullptr) {
          // An ESI names an array's elements only by the array type's one SubItem (ETG.2000
          // ArrayInfo): the names differ (docs/LINE.md "Round trip"); the rest is compared
          // with the mailbox length and the trailing names cut off.
          const coe::Entry* ea = native_obj->entry(static_cast<uint8_t>(sub));
          const coe::Entry* eb = obj->entry(static_cast<uint8_t>(sub));
          ASSERT_GE(a.size(), ea->name.size() + 2);
          ASSERT_GE(b.size(), eb->name.size() + 2);
          a = Bytes(a.begin() + 2, a.end() - static_cast<long>(ea->name.size()));
          b = Bytes(b.begin() + 2, b.end() - static_cast<long>(eb->name.size()));
          ++renamed;
        }
        ASSERT_EQ(a, b) << "entry description 0x" << std::hex << index << ":" << sub
                        << " value info 0x" << int(info);
        ++entries;
      }
    }
  }
  EXPECT_GT(entries, indices.size());
  std::printf(
      "round trip: %zu objects, %zu entry descriptions equal (%zu array elements but "
      "for their names)\n",
      indices.size(), entries, renamed);
}

TEST_F(RoundTripTest, TinyRack) {
  round_trip(mdp::load_rack_config(RACKCAT_SOURCE_DIR "/examples/tiny-rack.yaml"), dir_.string());
}

TEST_F(RoundTripTest, DefaultRack) {
  auto config = load_rack_or_report("");
  ASSERT_TRUE(config.has_value());
  round_trip(*config, dir_.string());
}

}  // namespace
}  // namespace rackcat::apps
