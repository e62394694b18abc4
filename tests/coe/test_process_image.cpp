// The process image compiled from 0x1C12/0x1C13 and the mapping objects (ETG.1000.6
// §5.6.7.4.7 - .9), and the generic PDO validators.
#include "coe/pdo_mapping.hpp"
#include "coe/process_image.hpp"
#include "tests/coe/sdo_fixture.hpp"

namespace rackcat::coe::test {
namespace {

class ProcessImageTest : public SdoTest {
 protected:
  ProcessImage image{od};
};

TEST_F(ProcessImageTest, OutputsFollowTheRxMapping) {
  ASSERT_EQ(image.compile(), AbortCode::None);
  // 0x1600: 0x7000:01 (16 bits) + 0x7000:02 (8 bits).
  EXPECT_EQ(image.output_bytes(), 3u);
  EXPECT_EQ(image.output_copies().size(), 1u);  // contiguous entries merge into one copy
  const Bytes sm2{0x34, 0x12, 0x56};
  image.write_outputs(sm2);
  EXPECT_EQ(od.find(0x7000)->get_u(1), 0x1234u);
  EXPECT_EQ(od.find(0x7000)->get_u(2), 0x56u);
}

TEST_F(ProcessImageTest, InputsFollowTheTxMappingWithBitsAndPadding) {
  ASSERT_EQ(image.compile(), AbortCode::None);
  // 0x1A00: 0x6000:01 (1 bit), 0x6000:02 (1 bit), 6 bits padding, 0x6000:04 (16 bits).
  EXPECT_EQ(image.input_bits(), 24u);
  Object& in = *od.find(0x6000);
  in.set_u(1, 1);
  in.set_u(2, 1);
  in.set_u(4, 0xBEEF);
  Bytes sm3(3, 0xFF);
  image.read_inputs(sm3);
  EXPECT_EQ(sm3, (Bytes{0x03, 0xEF, 0xBE}));
  in.set_u(1, 0);
  image.read_inputs(sm3);
  EXPECT_EQ(sm3[0], 0x02);
}

TEST_F(ProcessImageTest, HooksRunOncePerCycle) {
  int reads = 0, writes = 0;
  od.find(0x6000)->edit_hooks().before_read = [&](Object& o, int sub) {
    EXPECT_EQ(sub, ObjectHooks::kProcessData);
    o.set_u(4, 0x0102);
    ++reads;
  };
  od.find(0x7000)->edit_hooks().after_write = [&](Object&, int) { ++writes; };
  ASSERT_EQ(image.compile(), AbortCode::None);
  Bytes sm3(3), sm2(3);
  image.read_inputs(sm3);
  image.write_outputs(sm2);
  EXPECT_EQ(reads, 1);
  EXPECT_EQ(writes, 1);
  EXPECT_EQ(sm3[1], 0x02);
}

TEST_F(ProcessImageTest, ReassignmentOverSdoThenRecompile) {
  // Map only 0x7000:02 into 0x1600: clear, write entry 1, set count 1.
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 0, 0, 1))), download_ok(0x1600, 0));
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 1, 0x70000208, 4))), download_ok(0x1600, 1));
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 0, 1, 1))), download_ok(0x1600, 0));
  ASSERT_EQ(image.compile(), AbortCode::None);
  EXPECT_EQ(image.output_bytes(), 1u);
  image.write_outputs(Bytes{0x77});
  EXPECT_EQ(od.find(0x7000)->get_u(2), 0x77u);
}

TEST_F(ProcessImageTest, InvalidConfigurationKeepsThePreviousCompilation) {
  ASSERT_EQ(image.compile(), AbortCode::None);
  od.find(0x1C12)->set_u(1, 0x1A00);  // device code bypassing the validators
  EXPECT_EQ(image.compile(), AbortCode::ParameterIncompatible);
  EXPECT_EQ(image.output_bytes(), 3u);
  od.find(0x1C12)->set_u(1, 0x1601);
  EXPECT_EQ(image.compile(), AbortCode::ObjectNotFound);
}

TEST_F(ProcessImageTest, MappingValidatorAborts) {
  install_pdo_validators(od, 8, 8);
  // Entries change only while subindex 0 is 0.
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 1, 0x70000110, 4))),
            abort_payload(0x1600, 1, 0x06010003));
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 0, 0, 1))), download_ok(0x1600, 0));
  // A TxPDO-only entry in an RxPDO, an unknown object, a wrong bit length.
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 1, 0x60000101, 4))),
            abort_payload(0x1600, 1, 0x06040041));
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 1, 0x99990010, 4))),
            abort_payload(0x1600, 1, 0x06020000));
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 1, 0x70000108, 4))),
            abort_payload(0x1600, 1, 0x06040043));
  // Padding is always mappable.
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 3, 0x00000008, 4))), download_ok(0x1600, 3));
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 0, 2, 1))), download_ok(0x1600, 0));
}

TEST_F(ProcessImageTest, PdoLengthLimit) {
  install_pdo_validators(od, 2, 2);
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 0, 0, 1))), download_ok(0x1600, 0));
  // Two entries = 24 bits > 2 bytes.
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 0, 2, 1))),
            abort_payload(0x1600, 0, 0x06040042));
  EXPECT_EQ(payload(sdo(download_expedited(0x1600, 0, 1, 1))), download_ok(0x1600, 0));
}

TEST_F(ProcessImageTest, AssignValidatorAborts) {
  install_pdo_validators(od, 8, 8);
  EXPECT_EQ(payload(sdo(download_expedited(0x1C12, 1, 0x1600, 2))),
            abort_payload(0x1C12, 1, 0x06010003));
  // Complete access with a TxPDO mapping object in the RxPDO assign.
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 0, {0x01, 0x00, 0x00, 0x1A}, true))),
            abort_payload(0x1C12, 0, 0x06040043));
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 0, {0x01, 0x00, 0x01, 0x16}, true))),
            abort_payload(0x1C12, 0, 0x06020000));
  EXPECT_EQ(payload(sdo(download_normal(0x1C12, 0, {0x00, 0x00}, true))),
            download_ok(0x1C12, 0, true));
  EXPECT_EQ(payload(sdo(download_expedited(0x1C12, 1, 0x1600, 2))), download_ok(0x1C12, 1));
  EXPECT_EQ(payload(sdo(download_expedited(0x1C12, 0, 1, 1))), download_ok(0x1C12, 0));
  EXPECT_EQ(payload(sdo(download_expedited(0x1C13, 0, 0, 1))), download_ok(0x1C13, 0));
  EXPECT_EQ(payload(sdo(download_expedited(0x1C13, 1, 0x1600, 2))),
            abort_payload(0x1C13, 1, 0x06040043));
}

}  // namespace
}  // namespace rackcat::coe::test
