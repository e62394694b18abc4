// The round trip (docs/LINE.md "Round trip"): `rackcat esi` of a rack, fed back as an ESI
// device (device/esi_device.hpp), serves the same SII image and the same SDO information, byte
// for byte, as the native rack: every SDO Information service (ETG.1000.6 §5.6.3: Get OD List,
// Get Object Description, Get Entry Description with every value-info bit) answered by both.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "apps/rack_slave/rack_loading.hpp"
#include "apps/rack_slave/rack_slave.hpp"
#include "base/mailbox_header.hpp"
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

// One mailbox request (header included) to `coe` and every fragment of its answer, each behind
// a length-only mailbox header (the firmware frames them; the frame carries nothing of the
// device's).
Bytes ask(ecat::MailboxProtocol& coe, const Bytes& request) {
  Bytes all;
  std::vector<uint8_t> reply(1480);
  ecat::MailboxRequest r;
  r.data = std::span(request).subspan(6, static_cast<size_t>(request[0] | request[1] << 8));
  r.capacity = 1480;
  r.state = EsmState::PreOp;
  const mailbox::Answer answer = coe.on_request(r, reply);
  EXPECT_EQ(answer.error, mailbox::Error::None);
  size_t n = answer.length;
  while (n > 0) {
    // Each fragment behind a mailbox header that carries only its length (ETG.1000.4 §5.6;
    // counter 0 so two devices' answers compare), walked fragment by fragment as on SM1.
    mailbox::Header header;
    header.length = static_cast<uint16_t>(n);
    all.resize(all.size() + mailbox::Header::kSize);
    EXPECT_TRUE(header.encode(std::span(all).last(mailbox::Header::kSize)));
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

// With `choose_modules`, the ESI is read with the rack's own module list (ETG.5001 Slots filled
// from <Modules>, docs/LINE.md "Modular devices"): same SII and SDO information. Without, as
// its device-level description: same SII and process data sizes.
void round_trip(const mdp::RackConfig& config, const std::string& state_dir,
                bool choose_modules = false) {
  RackSlave native(config, state_dir, 0);
  const auto offline = offline_device(config);
  const coe::ObjectDictionary& native_od = offline->dictionary();
  const std::string xml = esi::write_esi(*offline);
  device::DeviceSelector selector;
  if (choose_modules) {
    selector.modules.emplace();
    for (const auto& m : config.modules) {
      char ident[16];
      std::snprintf(ident, sizeof ident, "0x%08X", m.card->module_ident);
      selector.modules->push_back({ident, "rack.yaml", 1});
    }
  }
  device::EsiDevice esi = device::parse_esi_device(xml, "rack.xml", selector);
  if (choose_modules) {
    ASSERT_EQ(esi.module_idents.size(), config.modules.size());
    for (size_t i = 0; i < config.modules.size(); ++i)
      EXPECT_EQ(esi.module_idents[i], config.modules[i].card->module_ident);
  }
  // The serial number is the rack's position in the segment, not part of the ESI.
  esi.description.serial = config.control.serial;
  // An ETG.5001 module is described once for every slot it may sit in, so what differs between
  // two instances of it cannot be in the ESI: the module information 0x3nn1 (card type of the
  // idents several cards share, RIM, slot, channel range) and the like. With a module list the
  // copy's modules carry the catalogue's values there; the test gives them the rack's and counts
  // them (docs/LINE.md "Round trip"): everything else must already be equal.
  size_t instance_values = 0;
  if (choose_modules) {
    native_od.for_each([&](const coe::Object& n) {
      if (n.index() <= 0x3000 || n.index() > 0x9FFF) return;  // module objects only
      coe::Object* c = esi.dictionary.find(n.index());
      ASSERT_NE(c, nullptr) << "module object 0x" << std::hex << n.index() << " missing";
      bool changed = false;
      for (const auto& e : n.entries()) {
        const coe::Entry* ce = c->entry(e.subindex);
        if (ce == nullptr || e.padding) continue;
        std::vector<uint8_t> want(e.byte_length());
        if (e.bit_offset % 8 == 0 && e.bit_length % 8 == 0) {
          const auto b = n.bytes(e.subindex);
          want.assign(b.begin(), b.end());
        } else {
          const uint64_t v = n.get_u(e.subindex);
          for (size_t k = 0; k < want.size() && k < 8; ++k)
            want[k] = static_cast<uint8_t>(v >> (8 * k));
        }
        const auto have = c->bytes(e.subindex);
        if (e.bit_offset % 8 == 0 && e.bit_length % 8 == 0
                ? std::equal(want.begin(), want.end(), have.begin(), have.end())
                : c->get_u(e.subindex) == n.get_u(e.subindex))
          continue;
        // Only the module information 0x3nn1 (guide §2.3 Table 6) is per instance.
        EXPECT_EQ(n.index() & 0xF00F, 0x3001)
            << "0x" << std::hex << n.index() << ":" << int(e.subindex) << " differs";
        c->set_default(e.subindex, want);
        changed = true;
        ++instance_values;
      }
      if (changed) c->load_defaults();
    });
  }
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
  // Read without the module list (a reader that ignores <Slots>), the device level has the
  // default configuration's SII, PDOs and sizes, but not the module objects: those are in the
  // <Module>s only (docs/LINE.md "Round trip").
  if (!choose_modules) {
    for (const auto& m : config.modules)
      EXPECT_EQ(copy.esi().dictionary.find(static_cast<uint16_t>(0x3001 + m.nn() * 0x10)), nullptr);
    return;
  }

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
      "for their names; %zu module instance values)\n",
      indices.size(), entries, renamed, instance_values);
}

TEST_F(RoundTripTest, TinyRackWithoutModuleListSameSii) {
  round_trip(mdp::load_rack_config(RACKCAT_SOURCE_DIR "/examples/tiny-rack.yaml"), dir_.string());
}

TEST_F(RoundTripTest, DefaultRackWithoutModuleListSameSii) {
  auto config = load_rack_or_report("");
  ASSERT_TRUE(config.has_value());
  round_trip(*config, dir_.string());
}

TEST_F(RoundTripTest, TinyRackWithItsModuleList) {
  round_trip(mdp::load_rack_config(RACKCAT_SOURCE_DIR "/examples/tiny-rack.yaml"), dir_.string(),
             true);
}

TEST_F(RoundTripTest, DefaultRackWithItsModuleList) {
  auto config = load_rack_or_report("");
  ASSERT_TRUE(config.has_value());
  round_trip(*config, dir_.string(), true);
}

}  // namespace
}  // namespace rackcat::apps
