// FoE files of an ESI device (foe_files.hpp). POSIX *at() calls relative to the directory's
// descriptor, O_NOFOLLOW on every name; write, fsync, renameat, fsync of the directory.
#include "device/foe_files.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

namespace rackcat::device {

using foe::CommitProgress;
using foe::FoeError;

namespace {
std::string tmp_name(const std::string& name) {
  return "." + name + ".tmp";  // a leading dot: never a valid file name itself
}
}  // namespace

FoeFiles::FoeFiles(int parent_fd, const std::string& name, uint32_t password)
    : password_(password) {
  if (parent_fd < 0 || !valid_name(name)) return;
  if (::mkdirat(parent_fd, name.c_str(), 0700) != 0 && errno != EEXIST) return;
  dir_fd_ = ::openat(parent_fd, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
}

FoeFiles::~FoeFiles() {
  abort_write();
  if (dir_fd_ >= 0) ::close(dir_fd_);
}

bool FoeFiles::valid_name(std::string_view name) {
  if (name.empty() || name.size() > 48 || name.front() == '.') return false;
  for (const char c : name) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

FoeError FoeFiles::check(std::string_view name, uint32_t password) const {
  if (dir_fd_ < 0) return FoeError::NotDefined;
  if (!valid_name(name)) return FoeError::Illegal;
  if (password != password_) return FoeError::NoRights;
  return FoeError::None;
}

size_t FoeFiles::file_count() const {
  const int fd = ::openat(dir_fd_, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return kMaxFiles;
  DIR* d = ::fdopendir(fd);
  if (d == nullptr) {
    ::close(fd);
    return kMaxFiles;
  }
  size_t n = 0;
  while (const dirent* e = ::readdir(d))
    if (e->d_name[0] != '.') ++n;
  ::closedir(d);
  return n;
}

FoeError FoeFiles::read_file(std::string_view name, uint32_t password, size_t max_size,
                             std::vector<uint8_t>& contents) {
  if (const FoeError e = check(name, password); e != FoeError::None) return e;
  const std::string n(name);
  const int fd = ::openat(dir_fd_, n.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return errno == ENOENT ? FoeError::NotFound : FoeError::AccessDenied;
  struct stat st {};
  FoeError result = FoeError::None;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    result = FoeError::AccessDenied;
  } else if (static_cast<size_t>(st.st_size) > std::min(max_size, kMaxFileBytes)) {
    result = FoeError::DiskFull;
  } else {
    contents.resize(static_cast<size_t>(st.st_size));
    size_t got = 0;
    while (got < contents.size()) {
      const ssize_t r = ::read(fd, contents.data() + got, contents.size() - got);
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) break;
      got += static_cast<size_t>(r);
    }
    contents.resize(got);
  }
  ::close(fd);
  return result;
}

FoeError FoeFiles::begin_write(std::string_view name, uint32_t password) {
  abort_write();
  if (const FoeError e = check(name, password); e != FoeError::None) return e;
  name_ = std::string(name);
  struct stat st {};
  const bool exists = ::fstatat(dir_fd_, name_.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0;
  if (exists && !S_ISREG(st.st_mode)) return FoeError::AccessDenied;  // a link or directory
  if (!exists && file_count() >= kMaxFiles) return FoeError::DiskFull;
  const std::string tmp = tmp_name(name_);
  ::unlinkat(dir_fd_, tmp.c_str(), 0);  // a planted or stale temp file is removed, not followed
  tmp_fd_ =
      ::openat(dir_fd_, tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (tmp_fd_ < 0) return FoeError::AccessDenied;
  written_ = 0;
  result_ = {};
  return FoeError::None;
}

FoeError FoeFiles::write_data(std::span<const uint8_t> data) {
  if (tmp_fd_ < 0) return FoeError::Illegal;
  if (written_ + data.size() > kMaxFileBytes) return FoeError::DiskFull;
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t r = ::write(tmp_fd_, data.data() + done, data.size() - done);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return FoeError::DiskFull;
    done += static_cast<size_t>(r);
  }
  written_ += data.size();
  return FoeError::None;
}

CommitProgress FoeFiles::commit() {
  if (tmp_fd_ < 0) return result_ = {false, FoeError::Illegal, 0, 0};
  const std::string tmp = tmp_name(name_);
  FoeError e = FoeError::None;
  if (::fsync(tmp_fd_) != 0) e = FoeError::DiskFull;
  ::close(tmp_fd_);
  tmp_fd_ = -1;
  if (e == FoeError::None && ::renameat(dir_fd_, tmp.c_str(), dir_fd_, name_.c_str()) != 0)
    e = FoeError::AccessDenied;
  if (e == FoeError::None) (void)::fsync(dir_fd_);
  if (e != FoeError::None) ::unlinkat(dir_fd_, tmp.c_str(), 0);
  return result_ = {false, e, 0, 0};
}

void FoeFiles::abort_write() {
  if (tmp_fd_ < 0) return;
  ::close(tmp_fd_);
  tmp_fd_ = -1;
  ::unlinkat(dir_fd_, tmp_name(name_).c_str(), 0);
}

}  // namespace rackcat::device
