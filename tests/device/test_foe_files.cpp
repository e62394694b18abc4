// FoE files of an ESI device (device/foe_files.hpp): a file written is read back, each refusal
// is its FoE error (ETG.1000.6 §5.8 error codes) and leaves the directory unchanged, and a
// link planted in the directory is never followed.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "device/foe_files.hpp"

namespace rackcat::device {
namespace {

namespace fs = std::filesystem;
using foe::FoeError;

constexpr uint32_t kPassword = 0x52434657;

class FoeFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rackcat-foe-files-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    fd_ = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  }
  void TearDown() override {
    ::close(fd_);
    fs::remove_all(dir_);
  }
  FoeError write(FoeFiles& f, const std::string& name, const std::vector<uint8_t>& data,
                 uint32_t password = kPassword) {
    if (auto e = f.begin_write(name, password); e != FoeError::None) return e;
    if (auto e = f.write_data(data); e != FoeError::None) return e;
    return f.commit().error;
  }
  fs::path dir_;
  int fd_ = -1;
};

TEST_F(FoeFilesTest, WrittenFileReadsBack) {
  FoeFiles f(fd_, "esi-0", kPassword);
  ASSERT_TRUE(f.usable());
  const std::vector<uint8_t> data{1, 2, 3, 0, 255};
  EXPECT_EQ(write(f, "params.bin", data), FoeError::None);
  std::vector<uint8_t> back;
  EXPECT_EQ(f.read_file("params.bin", kPassword, 1024, back), FoeError::None);
  EXPECT_EQ(back, data);
  // Nothing but the file: the temporary file is gone.
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "esi-0"))
    n += e.path().filename() == "params.bin";
  EXPECT_EQ(n, 1u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_ / "esi-0"), fs::directory_iterator{}), 1);
}

TEST_F(FoeFilesTest, RefusalsAreFoeErrors) {
  FoeFiles f(fd_, "esi-0", kPassword);
  std::vector<uint8_t> back;
  EXPECT_EQ(f.read_file("missing.bin", kPassword, 1024, back), FoeError::NotFound);
  EXPECT_EQ(write(f, "a.bin", {1}, kPassword + 1), FoeError::NoRights);
  EXPECT_EQ(f.read_file("a.bin", kPassword + 1, 1024, back), FoeError::NoRights);
  for (const char* bad : {"", "..", "../x", "a/b", ".hidden", "x y"})
    EXPECT_EQ(write(f, bad, {1}), FoeError::Illegal) << bad;
  EXPECT_EQ(write(f, std::string(49, 'a'), {1}), FoeError::Illegal);
  EXPECT_TRUE(fs::is_empty(dir_ / "esi-0"));
  // Larger than a file may be.
  EXPECT_EQ(write(f, "big.bin", std::vector<uint8_t>(FoeFiles::kMaxFileBytes + 1)),
            FoeError::DiskFull);
  f.abort_write();
  EXPECT_TRUE(fs::is_empty(dir_ / "esi-0"));
}

TEST_F(FoeFilesTest, PlantedLinksAreNotFollowed) {
  const fs::path secret = dir_ / "secret.txt";
  std::ofstream(secret) << "secret";
  FoeFiles f(fd_, "esi-0", kPassword);
  fs::create_symlink(secret, dir_ / "esi-0" / "link.bin");
  std::vector<uint8_t> back;
  EXPECT_EQ(f.read_file("link.bin", kPassword, 1024, back), FoeError::AccessDenied);
  EXPECT_EQ(write(f, "link.bin", {1}), FoeError::AccessDenied);
  std::ifstream in(secret);
  std::string text;
  in >> text;
  EXPECT_EQ(text, "secret");
  // A link where the directory should be: unusable, every request refused.
  fs::create_symlink(dir_, dir_ / "esi-1");
  FoeFiles linked(fd_, "esi-1", kPassword);
  EXPECT_FALSE(linked.usable());
  EXPECT_EQ(linked.read_file("secret.txt", kPassword, 1024, back), FoeError::NotDefined);
}

}  // namespace
}  // namespace rackcat::device
