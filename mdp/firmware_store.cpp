// Atomic, durable replacement of the installed firmware (firmware_store.hpp). POSIX: openat(2)
// beneath a directory descriptor with O_NOFOLLOW, write(2), fsync(2), pread(2) back, renameat(2),
// fsync(2) of the directory so the rename itself survives a power loss.
#include "mdp/firmware_store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "base/real_time.hpp"

namespace rackcat::mdp {
namespace {

constexpr const char* kFile = "firmware.rfw";
constexpr const char* kTmp = "firmware.rfw.tmp";

std::string errno_text(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

bool write_all(int fd, const uint8_t* p, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

}  // namespace

FirmwareStore::FirmwareStore(std::shared_ptr<const StateDirectory> dir) : dir_(std::move(dir)) {
  if (!dir_->usable()) {
    error_ = dir_->problem();
    return;
  }
  dir_fd_ = dir_->fd();
  // A commit interrupted before its rename left only the temporary file: it is not firmware.
  ::unlinkat(dir_fd_, kTmp, 0);
}

FirmwareStore::~FirmwareStore() {
  wait();
  close_tmp();
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

void FirmwareStore::close_tmp() {
  if (tmp_fd_ >= 0) ::close(tmp_fd_);
  tmp_fd_ = -1;
}

bool FirmwareStore::begin(std::string& error) {
  wait();
  close_tmp();
  if (!ok()) {
    error = error_;
    return false;
  }
  // A leftover (or a link planted in its place) is removed, never followed; the new one is
  // created afresh.
  if (::unlinkat(dir_fd_, kTmp, 0) != 0 && errno != ENOENT) {
    error = errno_text(std::string("cannot remove ") + kTmp);
    return false;
  }
  tmp_fd_ = ::openat(dir_fd_, kTmp, O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (tmp_fd_ < 0) {
    error = errno_text(std::string("cannot create ") + kTmp);
    return false;
  }
  return true;
}

bool FirmwareStore::append(std::span<const uint8_t> data, std::string& error) {
  if (tmp_fd_ < 0 || !write_all(tmp_fd_, data.data(), data.size())) {
    error = errno_text(std::string("cannot write ") + kTmp);
    return false;
  }
  return true;
}

void FirmwareStore::abort() {
  if (busy_.load()) return;
  if (tmp_fd_ >= 0) {
    close_tmp();
    ::unlinkat(dir_fd_, kTmp, 0);
  }
}

void FirmwareStore::wait() {
  if (worker_.joinable()) worker_.join();
}

void FirmwareStore::start_commit(Verifier verify) {
  wait();
  busy_.store(true);
  worker_ = std::thread([this, v = std::move(verify)] { commit(v); });
}

FirmwareStore::Status FirmwareStore::poll_commit() const {
  if (busy_.load(std::memory_order_acquire)) return {true, foe::FoeError::None, {}};
  return {false, result_, result_detail_};
}

void FirmwareStore::commit(const Verifier& verify) {
  (void)base::leave_real_time();  // a helper thread, not the device thread
  auto finish = [this](foe::FoeError e, std::string detail) {
    if (e != foe::FoeError::None) {
      close_tmp();
      ::unlinkat(dir_fd_, kTmp, 0);
    }
    result_ = e;
    result_detail_ = std::move(detail);
    busy_.store(false, std::memory_order_release);
  };
  if (::fsync(tmp_fd_) != 0) return finish(foe::FoeError::FlashProblem, errno_text("fsync"));
  close_tmp();
  // Verify what is on disk, not what was meant to be written.
  std::vector<uint8_t> bytes;
  std::string detail;
  if (dir_->read(kTmp, kMaxBytes, bytes, detail) != StateDirectory::ReadResult::Ok) {
    return finish(foe::FoeError::FlashProblem, detail);
  }
  if (const foe::FoeError e = verify(bytes, detail); e != foe::FoeError::None) {
    return finish(e, detail);
  }
  if (::renameat(dir_fd_, kTmp, dir_fd_, kFile) != 0) {
    return finish(foe::FoeError::FlashProblem, errno_text("cannot rename onto firmware.rfw"));
  }
  if (::fsync(dir_fd_) != 0) return finish(foe::FoeError::FlashProblem, errno_text("fsync dir"));
  finish(foe::FoeError::None, "installed " + path());
}

}  // namespace rackcat::mdp
