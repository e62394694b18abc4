// The gaps an audit of the device against the guide found on the wire, each pinned by a vector
// written from the guide's Appendix A or ETG.1000.6 (never from the device's own output):
// complete-access packing, the enumeration objects, record data types in SDO Information and
// the description of gaps below MaxSubindex.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "mdp/device.hpp"
#include "sdo_client.hpp"
#include "sdo_info_client.hpp"

namespace rackcat::mdp {
namespace {

using rackcat::EsmState;
using testing::SdoClient;
using testing::SdoInfoClient;

class AuditWire : public ::testing::Test {
 protected:
  void SetUp() override {
    DeviceOptions opt;
    opt.load_stored_parameters = false;
    opt.state_dir = ::testing::TempDir() + "/audit_wire";
    device = std::make_unique<Device>(default_rack(), opt);
    sdo = std::make_unique<SdoClient>(*device);
    info = std::make_unique<SdoInfoClient>(*device);
    device->state_changed(EsmState::Init, EsmState::PreOp);
  }
  std::unique_ptr<Device> device;
  std::unique_ptr<SdoClient> sdo;
  std::unique_ptr<SdoInfoClient> info;
};

void put_text(std::vector<uint8_t>& v, size_t at, const char* text) {
  std::memcpy(v.data() + at, text, std::strlen(text));
}

// Appendix A, 0x2000: subindex 0 (8 bits + 8 bits padding, ETG.1000.6 §5.6.2.1.4), then
// string(64), string(4), string(24), string(16), string(24), string(24), string(16), string(32),
// UDINT, UDINT, BIT1, pad_15, REAL, REAL, REAL. Byte offsets: 01 at 2, 02 at 66, 03 at 70,
// 04 at 94, 05 at 110, 06 at 134, 07 at 158, 08 at 174, 09 at 206, 0A at 210, 0B bit 0 of 214,
// 0C the 15 bits after it, 0D at 216, 0E at 220, 0F at 224; 228 bytes in all.
TEST_F(AuditWire, CompleteAccessOfDeviceInformationPacksBit1AndPad15IntoSixteenBits) {
  std::vector<uint8_t> ca;
  ASSERT_EQ(sdo->upload(0x2000, 0, ca, true), 0u);
  ASSERT_EQ(ca.size(), 228u);
  std::vector<uint8_t> golden(228, 0);
  golden[0] = 0x0F;
  put_text(golden, 2, "FI-CM0100-00");
  put_text(golden, 94, "192.168.9.50");
  golden[206] = golden[207] = golden[208] = golden[209] = 0xFF;  // event mask: all
  golden[214] = 0x01;                                            // Detect Modules Override 1
  const uint8_t rpm[4] = {0x00, 0x80, 0x3B, 0x45};               // 3000.0f
  const uint8_t temp[4] = {0x00, 0x00, 0x20, 0x42};              // 40.0f
  std::memcpy(&golden[220], rpm, 4);
  std::memcpy(&golden[224], temp, 4);
  // The rack file's strings (02, 03, 05, 06, 07) and the running clock (08) vary; compare the
  // layout-defining bytes.
  EXPECT_EQ(ca[0], golden[0]);
  EXPECT_EQ(std::vector<uint8_t>(ca.begin() + 2, ca.begin() + 14),
            std::vector<uint8_t>(golden.begin() + 2, golden.begin() + 14));
  EXPECT_EQ(std::vector<uint8_t>(ca.begin() + 94, ca.begin() + 106),
            std::vector<uint8_t>(golden.begin() + 94, golden.begin() + 106));
  EXPECT_EQ(std::vector<uint8_t>(ca.begin() + 206, ca.end()),
            std::vector<uint8_t>(golden.begin() + 206, golden.end()));

  // The same offsets on the way in: clear Detect Modules Override through a complete download.
  ca[214] = 0x00;
  EXPECT_EQ(sdo->download(0x2000, 0, ca, true), 0u);
  EXPECT_EQ(sdo->read_u(0x2000, 0x0B), 0u);
  std::vector<uint8_t> rpm_sdo;
  ASSERT_EQ(sdo->upload(0x2000, 0x0E, rpm_sdo), 0u);
  EXPECT_EQ(rpm_sdo, std::vector<uint8_t>(rpm, rpm + 4));
}

// Appendix A 0x0800..0x0805 as ETG.1000.6 enumeration objects (data type ENUM 0x0028): each
// value a 32-bit little-endian number followed by its text.
TEST_F(AuditWire, EnumerationObjectsAreServedAndListed) {
  EXPECT_EQ(sdo->read_u(0x0800, 0), 9u);
  std::vector<uint8_t> v;
  ASSERT_EQ(sdo->upload(0x0800, 0x01, v), 0u);
  const std::vector<uint8_t> baud1200 = {0, 0, 0, 0, '1', '2', '0', '0', ' ', 'B', 'a', 'u', 'd'};
  EXPECT_EQ(v, baud1200);
  ASSERT_EQ(sdo->upload(0x0801, 0x03, v), 0u);
  const std::vector<uint8_t> even = {2,   0,   0,   0,   'E', 'v', 'e', 'n',
                                     ' ', 'P', 'a', 'r', 'i', 't', 'y'};
  EXPECT_EQ(v, even);
  ASSERT_EQ(sdo->upload(0x0805, 0x03, v), 0u);
  const std::vector<uint8_t> rtscts = {2, 0, 0, 0, 'R', 'T', 'S', '/', 'C', 'T', 'S'};
  EXPECT_EQ(v, rtscts);

  uint32_t abort = 0;
  const auto list = info->all_objects(abort);
  ASSERT_EQ(abort, 0u);
  for (uint16_t index = 0x0800; index <= 0x0805; ++index) {
    EXPECT_NE(std::find(list.begin(), list.end(), index), list.end()) << std::hex << index;
    const auto o = info->object(index, abort);
    EXPECT_EQ(abort, 0u);
    EXPECT_EQ(o.data_type, 0x0028) << std::hex << index;
    EXPECT_EQ(o.object_code, 9);
  }
  const auto e = info->entry(0x0802, 0x02, abort);
  EXPECT_EQ(abort, 0u);
  EXPECT_EQ(e.data_type, 0x000A);          // OCTET_STRING
  EXPECT_EQ(e.bit_length, 8u * (4 + 11));  // value + "2 Stop Bits"
  EXPECT_EQ(e.name, "2 Stop Bits");
}

// ETG.1000.6 §5.6.7.4.5: the standard records carry their structure's data type.
TEST_F(AuditWire, SdoInformationGivesRecordsTheirStandardDataType) {
  struct Expect {
    uint16_t index, type;
  };
  for (const Expect x : {Expect{0x1018, 0x0023}, Expect{0x1600, 0x0021}, Expect{0x1A01, 0x0021},
                         Expect{0x1C32, 0x0029}, Expect{0x1C33, 0x0029}, Expect{0xF000, 0x002C},
                         Expect{0xFBF0, 0x0025}, Expect{0xF002, 0x0025}, Expect{0x2000, 0x002A}}) {
    uint32_t abort = 0;
    const auto o = info->object(x.index, abort);
    EXPECT_EQ(abort, 0u);
    EXPECT_EQ(o.object_code, 9) << std::hex << x.index;
    EXPECT_EQ(o.data_type, x.type) << std::hex << x.index;
  }
}

// 0x1C32/0x1C33 have subindices 0x01..0x0C and 0x20 (ETG.1020 §8.2.2); every subindex up to
// MaxSubindex has a description, the gaps with no type, no bits and no access.
TEST_F(AuditWire, GapsBelowMaxSubindexAreDescribedLikePadding) {
  for (uint16_t index : {0x1C32, 0x1C33}) {
    uint32_t abort = 0;
    const auto o = info->object(index, abort);
    ASSERT_EQ(o.max_subindex, 0x20);
    for (uint8_t sub = 0; sub <= o.max_subindex; ++sub) {
      const auto e = info->entry(index, sub, abort);
      EXPECT_EQ(abort, 0u) << std::hex << index << ":" << int(sub);
      if (sub >= 0x0D && sub <= 0x1F) {
        EXPECT_EQ(e.data_type, 0);
        EXPECT_EQ(e.bit_length, 0);
        EXPECT_EQ(e.access, 0);
      }
    }
    // Beyond MaxSubindex: still "subindex does not exist".
    info->entry(index, 0x21, abort);
    EXPECT_EQ(abort, 0x06090011u);
    // A gap is not addressable by SDO.
    std::vector<uint8_t> v;
    EXPECT_EQ(sdo->upload(index, 0x10, v), 0x06090011u);
  }
}

// Guide Appendix A 0xF002:02: "0: default value if the command has not been initiated. Not a
// supported value otherwise"; 100..200 give the progress, 200 = 100 %.
TEST_F(AuditWire, DetectModulesStatusReadsTwoHundredAfterACompletedScan) {
  EXPECT_EQ(sdo->read_u(0xF002, 2), 0u);
  ASSERT_EQ(sdo->download(0xF002, 1, std::vector<uint8_t>{0x73, 0x63, 0x61, 0x6E}), 0u);
  EXPECT_EQ(sdo->read_u(0xF002, 2), 200u);
}

// 0xF6F0 "Input Latch Local Timestamp" is the time the inputs were latched, not of the read.
TEST_F(AuditWire, InputLatchTimestampIsTheTimeOfTheLatch) {
  device->state_changed(EsmState::PreOp, EsmState::SafeOp);
  std::vector<uint8_t> sm3(device->input_bytes());
  std::this_thread::sleep_for(std::chrono::milliseconds(2));
  device->read_inputs(sm3);
  const uint64_t latched = device->dictionary().find(0xF6F0)->get_u(1);
  EXPECT_GT(latched, 0u);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_EQ(sdo->read_u(0xF6F0, 1), latched);
  EXPECT_EQ(sdo->read_u(0xF6F0, 1), latched);
}

}  // namespace
}  // namespace rackcat::mdp
