// Command objects 0xFBF0..0xFBF4 through SDO: the guide's byte sequences, status and response
// subindices, stored parameters surviving a new Device (a restart), reload, factory reset,
// checksums (zlib CRC-32, libcrypto MD5/SHA-1) and latched-exception reset.
#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <zlib.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "mdp/device.hpp"
#include "mdp/firmware_image.hpp"
#include "mdp/parameter_store.hpp"
#include "sdo_client.hpp"

namespace rackcat::mdp {
namespace {

using testing::SdoClient;

const std::vector<uint8_t> kStore{0x73, 0x61, 0x76, 0x65};
const std::vector<uint8_t> kLoad{0x6C, 0x6F, 0x61, 0x64};
const std::vector<uint8_t> kExceptionReset{0x74, 0x65, 0x73, 0x65, 0x72};
const std::vector<uint8_t> kDeviceReset{0x74, 0x65, 0x73, 0x65, 0x72, 0x00};
const std::vector<uint8_t> kFactoryReset{0x74, 0x65, 0x73, 0x65, 0x72, 0x66};
constexpr uint32_t kIncompatible = 0x06040043;

class Commands : public testing::RestartingDeviceTest {
 protected:
  Commands() : RestartingDeviceTest("mdp_commands_") {}
  void go(EsmState to) { device->state_changed(device->state(), to); }
  // 0xFBF0, 0xFBF2, 0xFBF3 and 0xFBF4 answer at once with status 255 (executing); the file work
  // finishes on a worker thread and the status changes when the master polls subindex 2.
  uint64_t wait_command(uint16_t index) {
    // Bounded only so a broken worker fails the test instead of hanging it.
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    uint64_t status = sdo->read_u(index, 2);
    while (status == 255 && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      status = sdo->read_u(index, 2);
    }
    return status;
  }
  uint64_t wait_store() { return wait_command(0xFBF2); }
  // Writes command `bytes` to `index`:01 and waits for the worker; returns the final status.
  uint64_t command(uint16_t index, const std::vector<uint8_t>& bytes) {
    EXPECT_EQ(sdo->download(index, 1, bytes), 0u) << std::hex << index;
    return wait_command(index);
  }
  std::vector<uint8_t> read(uint16_t index, uint8_t sub) {
    std::vector<uint8_t> d;
    EXPECT_EQ(sdo->upload(index, sub, d), 0u);
    return d;
  }
};

TEST_F(Commands, StoreKeepsParametersOverARestart) {
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.7"), 0u);
  ASSERT_EQ(sdo->write_u(0x2000, 0x0B, 0, 1), 0u);  // Detect Modules Override
  ASSERT_EQ(sdo->write_u(0xF3A2, 1, 0x0000FFFF, 4), 0u);
  go(EsmState::SafeOp);
  go(EsmState::Op);
  ASSERT_EQ(sdo->write_u(0x4000, 3, 0x00A5, 2), 0u);  // safe-state value (writable in OP)
  ASSERT_EQ(sdo->download(0xFBF2, 1, kStore), 0u);
  EXPECT_EQ(wait_store(), 0u);                                        // done, no error
  EXPECT_EQ(read(0xFBF2, 1), (std::vector<uint8_t>{0x01, 0, 0, 0}));  // reads its capability
  EXPECT_EQ(read(0xFBF2, 3), (std::vector<uint8_t>{0, 0}));
  restart();
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "10.0.0.7");
  EXPECT_EQ(sdo->read_u(0x2000, 0x0B), 0u);
  EXPECT_EQ(sdo->read_u(0xF3A2, 1), 0x0000FFFFu);
  EXPECT_EQ(sdo->read_u(0x4000, 3), 0x00A5u);
  EXPECT_NE(device->load_report().find("loaded"), std::string::npos) << device->load_report();
}

TEST_F(Commands, StoreAnswersAtOnceAndReportsExecutingUntilWritten) {
  ASSERT_EQ(sdo->download(0xFBF2, 1, kStore), 0u);
  const uint64_t first = sdo->read_u(0xFBF2, 2);
  EXPECT_TRUE(first == 255 || first == 0) << first;
  EXPECT_EQ(wait_store(), 0u);
  EXPECT_TRUE(std::filesystem::exists(device->parameter_file()));
}

TEST_F(Commands, StoreFailureIsReportedInTheStatus) {
  // The state directory is a file: the store cannot create it.
  sdo.reset();
  device.reset();
  std::filesystem::remove_all(dir);  // created by the device at start
  std::filesystem::create_directories(std::filesystem::path(dir).parent_path());
  { std::ofstream(dir) << "not a directory"; }
  DeviceOptions opt;
  opt.state_dir = dir;
  device = std::make_unique<Device>(default_rack(), opt);
  sdo = std::make_unique<SdoClient>(*device);
  device->state_changed(EsmState::Init, EsmState::PreOp);
  ASSERT_EQ(sdo->download(0xFBF2, 1, kStore), 0u);
  EXPECT_EQ(wait_store(), 2u);  // last command completed, error
  EXPECT_EQ(read(0xFBF2, 3)[0], 2);
  EXPECT_NE(device->load_report().find("cannot"), std::string::npos) << device->load_report();
  sdo.reset();
  device.reset();
  std::filesystem::remove(dir);
}

TEST_F(Commands, CompleteAccessWriteBackOfACommandObjectExecutesNothing) {
  struct L : CycleListener {
    int resets = 0;
    void on_device_reset(Device&, bool) override { ++resets; }
  } l;
  device->add_listener(&l);
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.20"), 0u);
  for (uint16_t index : {0xFBF0, 0xFBF1, 0xFBF2, 0xFBF3, 0xFBF4}) {
    std::vector<uint8_t> image;
    ASSERT_EQ(sdo->upload(index, 0, image, true), 0u) << std::hex << index;
    EXPECT_EQ(sdo->download(index, 0, image, true), 0u) << std::hex << index;
  }
  EXPECT_EQ(l.resets, 0);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "10.0.0.20");
  EXPECT_FALSE(std::filesystem::exists(device->parameter_file()));
  // A complete access carrying the command does execute it.
  std::vector<uint8_t> image;
  ASSERT_EQ(sdo->upload(0xFBF0, 0, image, true), 0u);
  std::copy(kDeviceReset.begin(), kDeviceReset.end(), image.begin() + 2);
  EXPECT_EQ(sdo->download(0xFBF0, 0, image, true), 0u);
  EXPECT_EQ(wait_command(0xFBF0), 0u);
  EXPECT_EQ(l.resets, 1);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "192.168.9.50");
  device->remove_listener(&l);
}

// The device reset loads every object's power-on value, the input latch times too; the next
// input update writes the last SYNC0's time into 0xF6F2 again although no SYNC0 came since.
TEST_F(Commands, InputLatchEscTimeIsBackAfterADeviceReset) {
  device->sync_event(0, 123456789);
  std::vector<uint8_t> sm3(device->input_bytes());
  device->read_inputs(sm3);
  ASSERT_EQ(sdo->read_u(0xF6F2, 1), 123456789u);
  EXPECT_EQ(command(0xFBF0, kDeviceReset), 0u);
  EXPECT_EQ(sdo->read_u(0xF6F2, 1), 0u);
  device->read_inputs(sm3);
  EXPECT_EQ(sdo->read_u(0xF6F2, 1), 123456789u);
}

TEST_F(Commands, WrongCommandBytesAreIncompatibleAndChangeNothing) {
  EXPECT_EQ(sdo->download(0xFBF2, 1, std::vector<uint8_t>{0x73, 0x61, 0x76, 0x66}), kIncompatible);
  EXPECT_FALSE(std::filesystem::exists(device->parameter_file()));
  EXPECT_EQ(sdo->download(0xFBF1, 1, std::vector<uint8_t>{0x74, 0x65, 0x73, 0x65, 0x73}),
            kIncompatible);
  EXPECT_EQ(sdo->download(0xFBF0, 1, std::vector<uint8_t>{0x74, 0x65, 0x73, 0x65, 0x72, 0x01}),
            kIncompatible);
  EXPECT_EQ(sdo->download(0xFBF4, 1, std::vector<uint8_t>{0x6C, 0x6F, 0x61, 0x65}), kIncompatible);
  EXPECT_EQ(sdo->download(0xFBF3, 1, std::vector<uint8_t>{0x06, 0, 0, 0}),
            kIncompatible);  // 2 bits
  EXPECT_EQ(sdo->download(0xFBF3, 1, std::vector<uint8_t>{0x80, 0, 0, 0}), kIncompatible);  // other
  EXPECT_EQ(sdo->download(0xFBF3, 1, std::vector<uint8_t>{0x02, 0, 1, 0}), kIncompatible);
}

TEST_F(Commands, LoadRevertsToTheStoredSetAndFactoryResetToShippedDefaults) {
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.8"), 0u);
  ASSERT_EQ(sdo->download(0xFBF2, 1, kStore), 0u);
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.9"), 0u);
  ASSERT_EQ(command(0xFBF4, kLoad), 0u);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "10.0.0.8");
  // Device reset: stored parameters stay, settings return to power-on values.
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.10"), 0u);
  ASSERT_EQ(command(0xFBF0, kDeviceReset), 0u);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "10.0.0.8");
  EXPECT_TRUE(std::filesystem::exists(device->parameter_file()));
  // Factory reset: the stored set is gone, the rack file's value is back, also after a restart.
  ASSERT_EQ(command(0xFBF0, kFactoryReset), 0u);
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "192.168.9.50");
  EXPECT_FALSE(std::filesystem::exists(device->parameter_file()));
  restart();
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "192.168.9.50");
}

TEST_F(Commands, DeviceResetIsReportedToListeners) {
  struct L : CycleListener {
    int resets = 0;
    bool factory = true;
    void on_device_reset(Device&, bool f) override {
      ++resets;
      factory = f;
    }
  } l;
  device->add_listener(&l);
  ASSERT_EQ(command(0xFBF0, kDeviceReset), 0u);
  EXPECT_EQ(l.resets, 1);
  EXPECT_FALSE(l.factory);
  device->remove_listener(&l);
}

// Issue 17: the device reset 0xFBF0 restarts the firmware, so a container installed since
// power-on (as a FoE write in BOOT leaves it: firmware.rfw in the state directory, docs/FOE.md)
// reports its versions afterwards: 0x100A, 0x1018:03, 0x2000:02 - as a restart of the process
// does. Before the reset the old firmware still runs.
TEST_F(Commands, DeviceResetRunsTheFirmwareInstalledSincePowerOn) {
  const auto& cm = device->config().control;
  const std::string old_version = sdo->read_text(0x100A, 0);
  const uint64_t old_revision = sdo->read_u(0x1018, 3);
  ASSERT_EQ(old_version, "1.09.6");
  std::string error;
  const auto file = pack_firmware(
      {cm.vendor_id, cm.product_code, 0x00020001, "2.00.1-longer-text", "7a"}, {}, error);
  ASSERT_TRUE(file) << error;
  std::ofstream(dir + "/firmware.rfw", std::ios::binary)
      .write(reinterpret_cast<const char*>(file->data()),
             static_cast<std::streamsize>(file->size()));
  EXPECT_EQ(sdo->read_text(0x100A, 0), old_version);
  EXPECT_EQ(sdo->read_u(0x1018, 3), old_revision);
  ASSERT_EQ(command(0xFBF0, kDeviceReset), 0u);
  EXPECT_EQ(sdo->read_text(0x100A, 0), "2.00.1-longer-text");
  EXPECT_EQ(sdo->read_u(0x1018, 3), 0x00020001u);
  EXPECT_EQ(read(0x2000, 0x02), (std::vector<uint8_t>{'7', 'a', 0, 0}));
  EXPECT_EQ(device->config().control.revision, 0x00020001u);
  // A second reset keeps it; a restart of the process reports the same.
  ASSERT_EQ(command(0xFBF0, kDeviceReset), 0u);
  EXPECT_EQ(sdo->read_text(0x100A, 0), "2.00.1-longer-text");
  restart();
  EXPECT_EQ(sdo->read_text(0x100A, 0), "2.00.1-longer-text");
  EXPECT_EQ(sdo->read_u(0x1018, 3), 0x00020001u);
  // The container removed (a damaged one is ignored the same way): the reset runs the built-in
  // version of the rack file again.
  std::filesystem::remove(dir + "/firmware.rfw");
  ASSERT_EQ(command(0xFBF0, kDeviceReset), 0u);
  EXPECT_EQ(sdo->read_text(0x100A, 0), old_version);
  EXPECT_EQ(sdo->read_u(0x1018, 3), old_revision);
}

std::vector<uint8_t> stored_payload(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
  // Header: magic 8, version 4, fingerprint 4, length 4; CRC-32 trailer 4.
  return std::vector<uint8_t>(bytes.begin() + 20, bytes.end() - 4);
}

TEST_F(Commands, ChecksumsCoverTheParametersAsStored) {
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.11"), 0u);
  ASSERT_EQ(sdo->download(0xFBF2, 1, kStore), 0u);
  ASSERT_EQ(wait_store(), 0u);
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.12"), 0u);  // not stored: not in the sum
  const std::vector<uint8_t> payload = stored_payload(device->parameter_file());
  EXPECT_EQ(read(0xFBF3, 1), (std::vector<uint8_t>{0x0F, 0, 0, 0}));

  EXPECT_EQ(command(0xFBF3, {0x02, 0, 0, 0}), 1u);  // CRC-32: completed, reply there
  std::vector<uint8_t> resp = read(0xFBF3, 3);
  ASSERT_EQ(resp.size(), 22u);
  EXPECT_EQ(resp[0], 1);
  EXPECT_EQ(resp[1], 0);
  const uint32_t crc =
      static_cast<uint32_t>(::crc32(0, payload.data(), static_cast<uInt>(payload.size())));
  EXPECT_EQ(resp[2] | (resp[3] << 8) | (resp[4] << 16) | (uint32_t(resp[5]) << 24), crc);

  for (auto [bit, md] : {std::pair{uint8_t{0x04}, EVP_md5()}, std::pair{uint8_t{0x08}, EVP_sha1()},
                         std::pair{uint8_t{0x01}, EVP_md5()}}) {
    ASSERT_EQ(command(0xFBF3, {bit, 0, 0, 0}), 1u);
    unsigned char want[EVP_MAX_MD_SIZE];
    unsigned int len = 0;
    EVP_Digest(payload.data(), payload.size(), want, &len, md, nullptr);
    resp = read(0xFBF3, 3);
    EXPECT_TRUE(std::equal(want, want + len, resp.begin() + 2)) << int(bit);
  }
}

TEST_F(Commands, ExceptionResetClearsLatchedObjectsAndKeepsTheLiveRimState) {
  auto& od = device->dictionary();
  od.find(0xF390)->set_u(0, 0x0A);
  od.find(0xF392)->set_u(1, 0x3);
  od.find(0xF398)->set_u(1, 0x4);
  od.find(0x2021)->set_u(0x08, 0x00000019);  // comm error + state error latched, state 1
  od.find(0xF380)->set_u(0, 0x08);           // active objects are not touched
  struct L : CycleListener {
    int calls = 0;
    void on_exception_reset(Device&) override { ++calls; }
  } l;
  device->add_listener(&l);
  ASSERT_EQ(sdo->download(0xFBF1, 1, kExceptionReset), 0u);
  EXPECT_EQ(od.find(0xF390)->get_u(0), 0u);
  EXPECT_EQ(od.find(0xF392)->get_u(1), 0u);
  EXPECT_EQ(od.find(0xF398)->get_u(1), 0u);
  EXPECT_EQ(od.find(0x2021)->get_u(0x08), 0x1u);
  EXPECT_EQ(od.find(0xF380)->get_u(0), 0x08u);
  EXPECT_EQ(l.calls, 1);
  EXPECT_EQ(sdo->read_u(0xFBF1, 2), 0u);
  device->remove_listener(&l);
}

TEST_F(Commands, CorruptOrForeignFilesAreReportedAndIgnored) {
  ASSERT_EQ(sdo->write_text(0x2000, 0x04, "10.0.0.13"), 0u);
  ASSERT_EQ(sdo->download(0xFBF2, 1, kStore), 0u);
  ASSERT_EQ(wait_store(), 0u);
  const std::string file = device->parameter_file();
  {  // flip one payload byte
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(22);
    f.put('X');
  }
  restart();
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "192.168.9.50");
  EXPECT_NE(device->load_report().find("corrupt"), std::string::npos) << device->load_report();
  EXPECT_EQ(command(0xFBF4, kLoad), 2u);  // cannot load a corrupt file: completed, error
  {
    std::ofstream f(file, std::ios::binary | std::ios::trunc);
    f << "something else entirely";
  }
  restart();
  EXPECT_NE(device->load_report().find("foreign"), std::string::npos) << device->load_report();
  // A file for another rack (other fingerprint) is foreign too.
  std::string error;
  ASSERT_TRUE(ParameterStore(dir).save(0x12345678, std::vector<uint8_t>(10, 0), error)) << error;
  restart();
  EXPECT_NE(device->load_report().find("foreign"), std::string::npos) << device->load_report();
  EXPECT_EQ(sdo->read_text(0x2000, 0x04), "192.168.9.50");
}

}  // namespace
}  // namespace rackcat::mdp
