// The firmware container (mdp/firmware_image.hpp, docs/FOE.md) byte by byte, its refusals with
// their FoE error codes, the atomic store (mdp/firmware_store.hpp) and the FoE file rules of
// the device (mdp/file_access.hpp).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <gtest/gtest.h>
#include <filesystem>
#include <fstream>

#include "base/little_endian.hpp"
#include "mdp/file_access.hpp"
#include "mdp/firmware_image.hpp"
#include "mdp/firmware_store.hpp"
#include "tests/support/worker_gate.hpp"

namespace rackcat::mdp {
namespace {

using foe::FoeError;
using Bytes = std::vector<uint8_t>;

constexpr uint32_t kVendor = 0x00000000, kProduct = 0x00464E01;

Bytes pack_abc() {
  std::string error;
  const Bytes payload = {'a', 'b', 'c'};
  auto f = pack_firmware({kVendor, kProduct, 0x00020001, "2.00.1", "7a"}, payload, error);
  EXPECT_TRUE(f) << error;
  return f.value_or(Bytes{});
}

uint32_t le32(const Bytes& b, size_t at) {
  return le::get32(&b[at]);
}

void fix_header_crc(Bytes& f) {
  const uint32_t crc = static_cast<uint32_t>(::crc32(0, f.data(), 124));
  for (int i = 0; i < 4; ++i) f[124 + i] = static_cast<uint8_t>(crc >> (8 * i));
}

TEST(FirmwareImage, HeaderLayoutByteByByte) {
  const Bytes f = pack_abc();
  ASSERT_EQ(f.size(), 128u + 3);
  const Bytes head(f.begin(), f.begin() + 32);
  const Bytes expected = {
      'R',  'C',  'A',  'T',  'F', 'W', '\r', '\n',  // magic
      0x01, 0x00, 0x00, 0x00,                        // format 1
      0x80, 0x00, 0x00, 0x00,                        // header size 128
      0x00, 0x00, 0x00, 0x00,                        // vendor
      0x01, 0x4E, 0x46, 0x00,                        // product 0x00464E01
      0x01, 0x00, 0x02, 0x00,                        // revision 0x00020001
      0x03, 0x00, 0x00, 0x00,                        // payload length 3
  };
  EXPECT_EQ(head, expected);
  EXPECT_EQ(le32(f, 32), 0x352441C2u);  // CRC-32 of "abc" (the standard check value)
  EXPECT_EQ(std::string(f.begin() + 36, f.begin() + 42), "2.00.1");
  EXPECT_EQ(f[42], 0);
  EXPECT_EQ(std::string(f.begin() + 60, f.begin() + 62), "7a");
  // SHA-256("abc"), FIPS 180-2 Appendix B.1.
  const Bytes sha = {0xba, 0x78, 0x16, 0xbf, 0x8f, 0x01, 0xcf, 0xea, 0x41, 0x41, 0x40,
                     0xde, 0x5d, 0xae, 0x22, 0x23, 0xb0, 0x03, 0x61, 0xa3, 0x96, 0x17,
                     0x7a, 0x9c, 0xb4, 0x10, 0xff, 0x61, 0xf2, 0x00, 0x15, 0xad};
  EXPECT_EQ(Bytes(f.begin() + 64, f.begin() + 96), sha);
  EXPECT_EQ(Bytes(f.begin() + 96, f.begin() + 124), Bytes(28, 0));
  EXPECT_EQ(le32(f, 124), static_cast<uint32_t>(::crc32(0, f.data(), 124)));
  EXPECT_EQ(std::string(f.begin() + 128, f.end()), "abc");
}

TEST(FirmwareImage, AcceptedFileGivesItsVersions) {
  FirmwareInfo info;
  std::string detail;
  EXPECT_EQ(verify_firmware(pack_abc(), kVendor, kProduct, info, detail), FoeError::None);
  EXPECT_EQ(info.revision, 0x00020001u);
  EXPECT_EQ(info.software_version, "2.00.1");
  EXPECT_EQ(info.short_version, "7a");
}

TEST(FirmwareImage, EachDefectHasItsFoeError) {
  FirmwareInfo info;
  std::string d;
  const Bytes good = pack_abc();
  EXPECT_EQ(verify_firmware(Bytes(good.begin(), good.begin() + 100), kVendor, kProduct, info, d),
            FoeError::FileHeaderDoesNotExist);
  Bytes magic = good;
  magic[0] = 'X';
  EXPECT_EQ(verify_firmware(magic, kVendor, kProduct, info, d), FoeError::FileHeaderDoesNotExist);
  Bytes header = good;
  header[30] ^= 1;  // header CRC no longer matches
  EXPECT_EQ(verify_firmware(header, kVendor, kProduct, info, d), FoeError::FileHeaderDoesNotExist);
  EXPECT_EQ(verify_firmware(good, kVendor, kProduct + 1, info, d),
            FoeError::FirmwareDoesNotFitHardware);
  EXPECT_EQ(verify_firmware(good, kVendor + 1, kProduct, info, d),
            FoeError::FirmwareDoesNotFitHardware);
  EXPECT_EQ(verify_firmware(Bytes(good.begin(), good.end() - 1), kVendor, kProduct, info, d),
            FoeError::WrongChecksum);  // truncated
  Bytes longer = good;
  longer.push_back(0);
  EXPECT_EQ(verify_firmware(longer, kVendor, kProduct, info, d), FoeError::WrongChecksum);
  Bytes payload = good;
  payload.back() ^= 1;
  EXPECT_EQ(verify_firmware(payload, kVendor, kProduct, info, d), FoeError::WrongChecksum);
  // CRC-32 right, SHA-256 wrong: the SHA-256 alone refuses it.
  Bytes sha = good;
  sha[70] ^= 1;
  fix_header_crc(sha);
  EXPECT_EQ(verify_firmware(sha, kVendor, kProduct, info, d), FoeError::WrongChecksum);
  EXPECT_EQ(d, "payload SHA-256 mismatch");
}

TEST(FirmwareImage, VersionsLongerThanTheirFieldsAreRefusedByPack) {
  std::string error;
  EXPECT_FALSE(pack_firmware({kVendor, kProduct, 1, std::string(24, 'v'), ""}, {}, error));
  EXPECT_FALSE(pack_firmware({kVendor, kProduct, 1, "1", "12345"}, {}, error));
  EXPECT_TRUE(pack_firmware({kVendor, kProduct, 1, std::string(23, 'v'), "1234"}, {}, error));
}

class FirmwareStoreTest : public ::testing::Test {
 protected:
  std::filesystem::path dir = std::filesystem::temp_directory_path() /
                              ("rackcat-fw-" + std::to_string(::getpid()) + "-" +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  void TearDown() override { std::filesystem::remove_all(dir); }
  static FirmwareStore::Verifier verifier() {
    return [](std::span<const uint8_t> f, std::string& d) {
      FirmwareInfo info;
      return verify_firmware(f, kVendor, kProduct, info, d);
    };
  }
  FirmwareStore::Status write(FirmwareStore& s, const Bytes& f) {
    std::string error;
    EXPECT_TRUE(s.begin(error)) << error;
    EXPECT_TRUE(s.append({f.data(), f.size() / 2}, error));
    EXPECT_TRUE(s.append({f.data() + f.size() / 2, f.size() - f.size() / 2}, error));
    s.start_commit(verifier());
    s.wait();
    return s.poll_commit();
  }
};

TEST_F(FirmwareStoreTest, CommitInstallsTheVerifiedFileAndLeavesNoTemporary) {
  FirmwareStore s(StateDirectory::open(dir.string()));
  const Bytes f = pack_abc();
  const auto st = write(s, f);
  EXPECT_FALSE(st.busy);
  EXPECT_EQ(st.error, FoeError::None) << st.detail;
  std::string d;
  EXPECT_EQ(s.read_installed(1 << 20, d).value_or(Bytes{}), f);
  EXPECT_FALSE(std::filesystem::exists(dir / "firmware.rfw.tmp"));
  EXPECT_EQ(std::filesystem::status(dir).permissions() & std::filesystem::perms::all,
            std::filesystem::perms::owner_all);
}

// The device thread only hands the bytes over: while the worker is held, the commit is busy and
// nothing (not even the temporary file) is in the state directory; the worker writes,
// verifies and installs it.
TEST_F(FirmwareStoreTest, CommitRunsOnTheWorkerNotOnTheDeviceThread) {
  base::BackgroundWorker worker;
  FirmwareStore s(StateDirectory::open(dir.string()), worker);
  const Bytes f = pack_abc();
  std::string error;
  {
    rackcat::testing::WorkerGate gate(worker);
    ASSERT_TRUE(s.begin(error)) << error;
    ASSERT_TRUE(s.append(f, error)) << error;
    s.start_commit(verifier());
    EXPECT_TRUE(s.poll_commit().busy);
    EXPECT_FALSE(s.begin(error));  // one write at a time
    EXPECT_FALSE(std::filesystem::exists(dir / "firmware.rfw.tmp"));
    EXPECT_FALSE(std::filesystem::exists(dir / "firmware.rfw"));
    gate.open();
  }
  s.wait();
  EXPECT_EQ(s.poll_commit().error, FoeError::None) << s.poll_commit().detail;
  std::string d;
  EXPECT_EQ(s.read_installed(1 << 20, d).value_or(Bytes{}), f);
}

TEST_F(FirmwareStoreTest, RefusedFileLeavesTheInstalledOneUnchanged) {
  FirmwareStore s(StateDirectory::open(dir.string()));
  const Bytes f = pack_abc();
  ASSERT_EQ(write(s, f).error, FoeError::None);
  Bytes bad = f;
  bad.back() ^= 1;
  EXPECT_EQ(write(s, bad).error, FoeError::WrongChecksum);
  std::string d;
  EXPECT_EQ(s.read_installed(1 << 20, d).value_or(Bytes{}), f);
  EXPECT_FALSE(std::filesystem::exists(dir / "firmware.rfw.tmp"));
}

TEST_F(FirmwareStoreTest, LeftoverTemporaryIsRemovedAtStartAndLinksAreNotFollowed) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "firmware.rfw.tmp") << "half a firmware";
  const auto outside = dir.string() + "-outside";
  std::ofstream(outside) << "not yours";
  {
    FirmwareStore s(StateDirectory::open(dir.string()));
    EXPECT_FALSE(std::filesystem::exists(dir / "firmware.rfw.tmp"));
    // A link planted where the installed file goes is not read through...
    std::filesystem::create_symlink(outside, dir / "firmware.rfw");
    std::string d;
    EXPECT_FALSE(s.read_installed(1 << 20, d));
    // ...and one planted at the temporary name is replaced, never written through.
    std::filesystem::create_symlink(outside, dir / "firmware.rfw.tmp");
    std::filesystem::remove(dir / "firmware.rfw");
    EXPECT_EQ(write(s, pack_abc()).error, FoeError::None);
  }
  std::ifstream in(outside);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "not yours");
  std::filesystem::remove(outside);
}

TEST(FileAccess, FirmwareFileNamePattern) {
  EXPECT_TRUE(is_firmware_file_name("rackcat-update.rfw"));
  EXPECT_TRUE(is_firmware_file_name("rackcat-2.00.1_A-b.rfw"));
  EXPECT_FALSE(is_firmware_file_name("rackcat-.rfw"));
  EXPECT_FALSE(is_firmware_file_name("rackcat-../x.rfw"));
  EXPECT_FALSE(is_firmware_file_name("rackcat-a/b.rfw"));
  EXPECT_FALSE(is_firmware_file_name("update.rfw"));
  EXPECT_FALSE(is_firmware_file_name("rackcat-update.bin"));
  EXPECT_FALSE(is_firmware_file_name("rackcat-" + std::string(49, 'a') + ".rfw"));
  EXPECT_TRUE(is_firmware_file_name("rackcat-" + std::string(48, 'a') + ".rfw"));
}

class FileAccessTest : public FirmwareStoreTest {
 protected:
  EsmState state = EsmState::PreOp;
  Bytes restored;
  FirmwareStore store{StateDirectory::open(dir.string())};
  FileAccess files{store, 42, [this] {
                     FileAccessHooks h;
                     h.state = [this] { return state; };
                     h.start_parameter_read = [] {};
                     h.poll_parameter_read = [](Bytes& out) {
                       out = Bytes{'P'};
                       return foe::ReadProgress{};
                     };
                     h.abort_parameter_read = [] {};
                     h.restore_parameters = [this](std::span<const uint8_t> f, std::string&) {
                       restored.assign(f.begin(), f.end());
                       return FoeError::None;
                     };
                     h.poll_restore = [](std::string&) {
                       return foe::CommitProgress{false, FoeError::None, 1, 1};
                     };
                     h.running_firmware = [] { return Bytes{'F'}; };
                     h.verify_firmware = verifier();
                     return h;
                   }()};
};

TEST_F(FileAccessTest, StatesAndPasswordsPerFile) {
  Bytes out;
  EXPECT_EQ(files.read_file("parameters.bin", 41, 100, out).error, FoeError::NoRights);
  EXPECT_EQ(files.read_file("other.bin", 42, 100, out).error, FoeError::NotFound);
  EXPECT_EQ(files.read_file("parameters.bin", 42, 100, out).error, FoeError::None);
  EXPECT_EQ(out, Bytes{'P'});
  EXPECT_EQ(files.read_file("rackcat-x.rfw", 42, 100, out).error, FoeError::BootstrapOnly);
  EXPECT_EQ(files.begin_write("rackcat-x.rfw", 42), FoeError::BootstrapOnly);
  state = EsmState::SafeOp;
  EXPECT_EQ(files.begin_write("parameters.bin", 42), FoeError::AccessDenied);
  state = EsmState::Boot;
  EXPECT_EQ(files.begin_write("parameters.bin", 42), FoeError::NotBootstrap);
  EXPECT_EQ(files.read_file("parameters.bin", 42, 100, out).error, FoeError::NotBootstrap);
  EXPECT_EQ(files.read_file("rackcat-x.rfw", 42, 100, out).error, FoeError::None);
  EXPECT_EQ(out, Bytes{'F'});
  EXPECT_EQ(files.begin_write("rackcat-x.rfw", 42), FoeError::None);
  const Bytes f = pack_abc();
  EXPECT_EQ(files.write_data(f), FoeError::None);
  auto p = files.commit();
  while (p.busy) p = files.poll_commit();
  EXPECT_EQ(p.error, FoeError::None);
  EXPECT_TRUE(std::filesystem::exists(dir / "firmware.rfw"));
}

TEST_F(FileAccessTest, ParameterFileLargerThanTheCapIsDiskFull) {
  ASSERT_EQ(files.begin_write("parameters.bin", 42), FoeError::None);
  const Bytes chunk(kMaxParameterFile, 0);
  EXPECT_EQ(files.write_data(chunk), FoeError::None);
  EXPECT_EQ(files.write_data(Bytes{1}), FoeError::DiskFull);
  files.abort_write();
  ASSERT_EQ(files.begin_write("parameters.bin", 42), FoeError::None);
  EXPECT_EQ(files.write_data(Bytes{1, 2}), FoeError::None);
  EXPECT_EQ(files.commit().error, FoeError::None);
  EXPECT_EQ(restored, (Bytes{1, 2}));
}

}  // namespace
}  // namespace rackcat::mdp
