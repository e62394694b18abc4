// Atomic, durable replacement of the installed firmware (firmware_store.hpp). POSIX: openat(2)
// beneath a directory descriptor with O_NOFOLLOW, write(2), fsync(2), pread(2) back, renameat(2),
// fsync(2) of the directory so the rename itself survives a power loss. All of it on the
// background worker.
#include "mdp/firmware_store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "base/fd_io.hpp"

namespace rackcat::mdp {
namespace {

constexpr const char* kFile = "firmware.rfw";
constexpr const char* kTmp = "firmware.rfw.tmp";

std::string errno_text(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

}  // namespace

FirmwareStore::FirmwareStore(std::shared_ptr<const StateDirectory> dir,
                             base::BackgroundWorker& worker)
    : dir_(std::move(dir)), worker_(worker) {
  if (!dir_->usable()) {
    error_ = dir_->problem();
    return;
  }
  dir_fd_ = dir_->fd();
  // A commit interrupted before its rename left only the temporary file: it is not firmware.
  ::unlinkat(dir_fd_, kTmp, 0);
}

FirmwareStore::~FirmwareStore() {
  wait();  // a commit handed over is finished, not dropped
  worker_.forget(*this);
}

std::string FirmwareStore::path() const {
  return dir_->path() + "/" + kFile;
}

std::optional<std::vector<uint8_t>> FirmwareStore::read_installed(size_t max_size,
                                                                  std::string& detail) const {
  if (!ok()) {
    detail = error_;
    return std::nullopt;
  }
  std::vector<uint8_t> bytes;
  if (dir_->read(kFile, max_size, bytes, detail) != StateDirectory::ReadResult::Ok) {
    return std::nullopt;
  }
  return bytes;
}

bool FirmwareStore::begin(std::string& error) {
  if (!ok()) {
    error = error_;
    return false;
  }
  if (busy_.load(std::memory_order_acquire)) {
    error = "a firmware commit is still running";
    return false;
  }
  incoming_.clear();
  // Address space only (pages come as the file arrives): no reallocation while it does.
  incoming_.reserve(kMaxBytes);
  open_ = true;
  return true;
}

bool FirmwareStore::append(std::span<const uint8_t> data, std::string& error) {
  if (!open_) {
    error = "no firmware write was begun";
    return false;
  }
  if (incoming_.size() + data.size() > kMaxBytes) {
    error = "firmware file larger than " + std::to_string(kMaxBytes) + " bytes";
    return false;
  }
  incoming_.insert(incoming_.end(), data.begin(), data.end());
  return true;
}

void FirmwareStore::abort() {
  open_ = false;
  incoming_ = {};
}

void FirmwareStore::start_commit(Verifier verify) {
  if (busy_.load(std::memory_order_acquire)) return;  // begin() refused meanwhile: not reached
  file_.swap(incoming_);
  incoming_ = {};
  verify_ = std::move(verify);
  open_ = false;
  busy_.store(true, std::memory_order_release);
  worker_.schedule(*this);
}

FirmwareStore::Status FirmwareStore::poll_commit() const {
  if (busy_.load(std::memory_order_acquire)) return {true, foe::FoeError::None, {}};
  return {false, result_, result_detail_};
}

void FirmwareStore::wait() {
  std::unique_lock lock(done_mutex_);
  done_.wait(lock, [this] { return !busy_.load(std::memory_order_acquire); });
}

bool FirmwareStore::run_one() {
  std::string detail;
  const foe::FoeError e = commit(detail);
  if (e != foe::FoeError::None) ::unlinkat(dir_fd_, kTmp, 0);
  file_ = {};
  result_ = e;
  result_detail_ = std::move(detail);
  {
    std::lock_guard lock(done_mutex_);
    busy_.store(false, std::memory_order_release);
  }
  done_.notify_all();
  return false;
}

foe::FoeError FirmwareStore::commit(std::string& detail) {
  // A leftover (or a link planted in its place) is removed, never followed; the new one is
  // created afresh.
  if (::unlinkat(dir_fd_, kTmp, 0) != 0 && errno != ENOENT) {
    detail = errno_text(std::string("cannot remove ") + kTmp);
    return foe::FoeError::FlashProblem;
  }
  const int fd =
      ::openat(dir_fd_, kTmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) {
    detail = errno_text(std::string("cannot create ") + kTmp);
    return foe::FoeError::FlashProblem;
  }
  const bool written = base::write_all(fd, file_.data(), file_.size());
  if (!written || ::fsync(fd) != 0) {
    detail = errno_text(std::string(written ? "cannot fsync " : "cannot write ") + kTmp);
    ::close(fd);
    return foe::FoeError::FlashProblem;
  }
  ::close(fd);
  // Verify what is on disk, not what was meant to be written.
  std::vector<uint8_t> bytes;
  if (dir_->read(kTmp, kMaxBytes, bytes, detail) != StateDirectory::ReadResult::Ok) {
    return foe::FoeError::FlashProblem;
  }
  if (const foe::FoeError e = verify_(bytes, detail); e != foe::FoeError::None) return e;
  if (::renameat(dir_fd_, kTmp, dir_fd_, kFile) != 0) {
    detail = errno_text("cannot rename onto firmware.rfw");
    return foe::FoeError::FlashProblem;
  }
  if (::fsync(dir_fd_) != 0) {
    detail = errno_text("fsync dir");
    return foe::FoeError::FlashProblem;
  }
  detail = "installed " + path();
  return foe::FoeError::None;
}

}  // namespace rackcat::mdp
