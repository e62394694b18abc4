// FoE files of an ESI device (device/foe_files.hpp): a file written is read back, each refusal
// is its FoE error (ETG.1000.6 §5.8 error codes) and leaves the directory unchanged, a link
// planted in the directory is never followed, and no file is opened, read, written or renamed
// on the calling (device) thread: the work waits for the background worker.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "base/background_worker.hpp"
#include "device/foe_files.hpp"
#include "tests/support/worker_gate.hpp"

namespace rackcat::device {
namespace {

namespace fs = std::filesystem;
using foe::CommitProgress;
using foe::FoeError;
using foe::ReadProgress;
using Bytes = std::vector<uint8_t>;

constexpr uint32_t kPassword = 0x52434657;

using Gate = rackcat::testing::WorkerGate;

std::string text_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

size_t entries(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}));
}

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
  // The FoE server's side: polls (as the mailbox does) until the worker is done. The deadline
  // only stops a hang; a commit takes milliseconds.
  static CommitProgress finish_commit(FoeFiles& f, CommitProgress p) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (p.busy && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      p = f.poll_commit();
    }
    return p;
  }
  static ReadProgress finish_read(FoeFiles& f, ReadProgress p, Bytes& out) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (p.busy && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      p = f.poll_read(out);
    }
    return p;
  }
  static FoeError write(FoeFiles& f, const std::string& name, const Bytes& data,
                        uint32_t password = kPassword) {
    if (auto e = f.begin_write(name, password); e != FoeError::None) return e;
    if (auto e = f.write_data(data); e != FoeError::None) return e;
    const CommitProgress p = finish_commit(f, f.commit());
    EXPECT_FALSE(p.busy);
    return p.error;
  }
  static FoeError read(FoeFiles& f, const std::string& name, Bytes& out,
                       uint32_t password = kPassword, size_t max = 1024) {
    const ReadProgress p = finish_read(f, f.read_file(name, password, max, out), out);
    EXPECT_FALSE(p.busy);
    return p.error;
  }

  base::BackgroundWorker worker_;  // outlives every FoeFiles of a test
  fs::path dir_;
  int fd_ = -1;
};

TEST_F(FoeFilesTest, WrittenFileReadsBack) {
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  ASSERT_TRUE(f.usable());
  const Bytes data{1, 2, 3, 0, 255};
  EXPECT_EQ(write(f, "params.bin", data), FoeError::None);
  Bytes back;
  EXPECT_EQ(read(f, "params.bin", back), FoeError::None);
  EXPECT_EQ(back, data);
  // Nothing but the file: the temporary file is gone.
  EXPECT_TRUE(fs::is_regular_file(dir_ / "esi-0" / "params.bin"));
  EXPECT_EQ(entries(dir_ / "esi-0"), 1u);
}

// The commit's write, fsync and rename run on the worker: while the worker is held, the
// device side has answered Busy and nothing (not even the temporary file) is in the directory.
TEST_F(FoeFilesTest, CommitRunsOnTheWorkerNotOnTheDeviceThread) {
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  Gate gate(worker_);
  ASSERT_EQ(f.begin_write("new.bin", kPassword), FoeError::None);
  ASSERT_EQ(f.write_data(Bytes{'n', 'e', 'w'}), FoeError::None);
  CommitProgress p = f.commit();
  EXPECT_TRUE(p.busy);
  EXPECT_EQ(p.entire, 1);  // Busy's Done / Entire (ETG.1000.6 §5.8)
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(f.poll_commit().busy);
  EXPECT_EQ(entries(dir_ / "esi-0"), 0u);
  gate.open();
  p = finish_commit(f, p);
  EXPECT_FALSE(p.busy);
  EXPECT_EQ(p.error, FoeError::None);
  EXPECT_EQ(text_of(dir_ / "esi-0" / "new.bin"), "new");
  EXPECT_EQ(entries(dir_ / "esi-0"), 1u);
  EXPECT_EQ(f.poll_commit().error, FoeError::None);  // polled again: the same answer
}

// A read request's file is opened and read on the worker: the content delivered is the one
// the file has when the worker runs, after the request was answered busy.
TEST_F(FoeFilesTest, ReadRunsOnTheWorkerNotOnTheDeviceThread) {
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  std::ofstream(dir_ / "esi-0" / "r.bin") << "old";
  Gate gate(worker_);
  Bytes back;
  EXPECT_TRUE(f.read_file("r.bin", kPassword, 1024, back).busy);
  EXPECT_TRUE(f.poll_read(back).busy);
  EXPECT_TRUE(back.empty());
  std::ofstream(dir_ / "esi-0" / "r.bin", std::ios::trunc) << "newer";
  gate.open();
  EXPECT_EQ(finish_read(f, {true, FoeError::None}, back).error, FoeError::None);
  EXPECT_EQ(std::string(back.begin(), back.end()), "newer");
}

// An abandoned read (the master's new request) does not hand its file to the next one.
TEST_F(FoeFilesTest, AbandonedReadDoesNotAnswerTheNextRequest) {
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  std::ofstream(dir_ / "esi-0" / "a.bin") << "aaa";
  std::ofstream(dir_ / "esi-0" / "b.bin") << "bb";
  Gate gate(worker_);
  Bytes back;
  ASSERT_TRUE(f.read_file("a.bin", kPassword, 1024, back).busy);
  f.abort_read();
  ASSERT_TRUE(f.read_file("b.bin", kPassword, 1024, back).busy);  // waits for a.bin's job
  gate.open();
  EXPECT_EQ(finish_read(f, {true, FoeError::None}, back).error, FoeError::None);
  EXPECT_EQ(std::string(back.begin(), back.end()), "bb");
}

// A write that fails on the disk (here: the file size limit, EFBIG) answers 0x8003 Disk full
// and leaves the old file as it was, without a temporary file.
TEST_F(FoeFilesTest, FailedWriteAnswersDiskFullAndKeepsTheOldFile) {
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  ASSERT_EQ(write(f, "keep.bin", Bytes{'o', 'l', 'd'}), FoeError::None);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // write(2) fails with EFBIG instead
  rlimit old_limit{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit small = old_limit;
  small.rlim_cur = 100;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const FoeError e = write(f, "keep.bin", Bytes(1000, 'x'));
  ::setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(e, FoeError::DiskFull);
  EXPECT_EQ(text_of(dir_ / "esi-0" / "keep.bin"), "old");
  EXPECT_EQ(entries(dir_ / "esi-0"), 1u);
}

TEST_F(FoeFilesTest, RefusalsAreFoeErrors) {
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  Bytes back;
  EXPECT_EQ(read(f, "missing.bin", back), FoeError::NotFound);
  EXPECT_EQ(write(f, "a.bin", {1}, kPassword + 1), FoeError::NoRights);
  EXPECT_EQ(read(f, "a.bin", back, kPassword + 1), FoeError::NoRights);
  for (const char* bad : {"", "..", "../x", "a/b", ".hidden", "x y"})
    EXPECT_EQ(write(f, bad, {1}), FoeError::Illegal) << bad;
  EXPECT_EQ(write(f, std::string(49, 'a'), {1}), FoeError::Illegal);
  EXPECT_TRUE(fs::is_empty(dir_ / "esi-0"));
  // Larger than a file may be: refused as it arrives.
  EXPECT_EQ(write(f, "big.bin", Bytes(FoeFiles::kMaxFileBytes + 1)), FoeError::DiskFull);
  f.abort_write();
  EXPECT_TRUE(fs::is_empty(dir_ / "esi-0"));
  // Larger than the reader takes.
  ASSERT_EQ(write(f, "mid.bin", Bytes(2000, 1)), FoeError::None);
  EXPECT_EQ(read(f, "mid.bin", back, kPassword, 1999), FoeError::DiskFull);
  // Data without a write request.
  EXPECT_EQ(f.write_data(Bytes{1}), FoeError::Illegal);
  EXPECT_EQ(f.commit().error, FoeError::Illegal);
}

TEST_F(FoeFilesTest, AtMostMaxFilesButAnExistingOneIsReplaced) {
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  for (size_t i = 0; i < FoeFiles::kMaxFiles; ++i) {
    std::string name = "f";
    name += std::to_string(i);
    std::ofstream(dir_ / "esi-0" / name) << i;
  }
  EXPECT_EQ(write(f, "one-more.bin", {1}), FoeError::DiskFull);
  EXPECT_EQ(write(f, "f7", {'x'}), FoeError::None);
  EXPECT_EQ(text_of(dir_ / "esi-0" / "f7"), "x");
  EXPECT_EQ(entries(dir_ / "esi-0"), FoeFiles::kMaxFiles);
}

TEST_F(FoeFilesTest, PlantedLinksAreNotFollowed) {
  const fs::path secret = dir_ / "secret.txt";
  std::ofstream(secret) << "secret";
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  fs::create_symlink(secret, dir_ / "esi-0" / "link.bin");
  fs::create_directory(dir_ / "esi-0" / "dir.bin");
  Bytes back;
  EXPECT_EQ(read(f, "link.bin", back), FoeError::AccessDenied);
  EXPECT_EQ(write(f, "link.bin", {1}), FoeError::AccessDenied);
  EXPECT_EQ(read(f, "dir.bin", back), FoeError::AccessDenied);
  EXPECT_EQ(write(f, "dir.bin", {1}), FoeError::AccessDenied);
  EXPECT_EQ(text_of(secret), "secret");
  // A link where the temporary file goes is removed, not followed.
  fs::create_symlink(secret, dir_ / "esi-0" / ".t.bin.tmp");
  EXPECT_EQ(write(f, "t.bin", {'t'}), FoeError::None);
  EXPECT_EQ(text_of(secret), "secret");
  EXPECT_FALSE(fs::exists(fs::symlink_status(dir_ / "esi-0" / ".t.bin.tmp")));
  // A link where the directory should be: unusable, every request refused.
  fs::create_symlink(dir_, dir_ / "esi-1");
  FoeFiles linked(fd_, "esi-1", kPassword, worker_);
  EXPECT_FALSE(linked.usable());
  EXPECT_EQ(read(linked, "secret.txt", back), FoeError::NotDefined);
}

// A write interrupted before its rename (kill -9) left its temporary file: gone at the next
// start, the old file untouched.
TEST_F(FoeFilesTest, LeftoverTemporaryFileIsRemovedAtStart) {
  fs::create_directories(dir_ / "esi-0");
  std::ofstream(dir_ / "esi-0" / "p.bin") << "old";
  std::ofstream(dir_ / "esi-0" / ".p.bin.tmp") << "half";
  FoeFiles f(fd_, "esi-0", kPassword, worker_);
  EXPECT_FALSE(fs::exists(dir_ / "esi-0" / ".p.bin.tmp"));
  EXPECT_EQ(text_of(dir_ / "esi-0" / "p.bin"), "old");
}

}  // namespace
}  // namespace rackcat::device
