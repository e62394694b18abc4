// FoE files of an ESI device (foe_files.hpp). The device thread only checks requests and keeps
// a write's data; the worker does the POSIX *at() calls relative to the directory's descriptor,
// O_NOFOLLOW on every name: write, fsync, renameat, fsync of the directory.
#include "device/foe_files.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "base/fd_io.hpp"

namespace rackcat::device {

using foe::CommitProgress;
using foe::FoeError;
using foe::ReadProgress;

namespace {

std::string tmp_name(const std::string& name) {
  return "." + name + ".tmp";  // a leading dot: never a valid file name itself
}

// The FoE error for a failed system call (foe_files.hpp "Rules").
FoeError error_of(int err) {
  switch (err) {
    case ENOENT:
      return FoeError::NotFound;
    case ENOSPC:
    case EDQUOT:
    case EFBIG:
      return FoeError::DiskFull;
    case EACCES:
    case EPERM:
    case EROFS:
    case ELOOP:  // O_NOFOLLOW met a link
    case EISDIR:
    case ENOTDIR:
    case EEXIST:
    case ETXTBSY:
    case ENXIO:
      return FoeError::AccessDenied;
    default:
      return FoeError::NotDefined;
  }
}

// The directory open as `dir_fd` for readdir(3), on a descriptor of its own (nullptr: failed).
DIR* open_listing(int dir_fd) {
  const int fd = ::openat(dir_fd, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return nullptr;
  DIR* d = ::fdopendir(fd);
  if (d == nullptr) ::close(fd);
  return d;
}

}  // namespace

FoeFiles::FoeFiles(int parent_fd, const std::string& name, uint32_t password,
                   base::BackgroundWorker& worker)
    : password_(password), worker_(worker) {
  if (parent_fd < 0 || !valid_name(name)) return;
  if (::mkdirat(parent_fd, name.c_str(), 0700) != 0 && errno != EEXIST) return;
  dir_fd_ = ::openat(parent_fd, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (dir_fd_ < 0) return;
  // A write interrupted before its rename left only its temporary file: not a file of the
  // device. Removed here, at start, not on the device thread.
  if (DIR* d = open_listing(dir_fd_)) {
    std::vector<std::string> stale;
    while (const dirent* e = ::readdir(d)) {
      const std::string n = e->d_name;
      if (n.size() > 5 && n.front() == '.' && n.ends_with(".tmp")) stale.push_back(n);
    }
    ::closedir(d);
    for (const auto& n : stale) ::unlinkat(dir_fd_, n.c_str(), 0);
  }
}

FoeFiles::~FoeFiles() {
  worker_.forget(*this);  // a running job finishes first
  if (dir_fd_ >= 0) ::close(dir_fd_);
}

bool FoeFiles::valid_name(std::string_view name) {
  if (name.empty() || name.size() > 48 || name.front() == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' ||
           c == '_' || c == '-';
  });
}

FoeError FoeFiles::check(std::string_view name, uint32_t password) const {
  if (dir_fd_ < 0) return FoeError::NotDefined;
  if (!valid_name(name)) return FoeError::Illegal;
  if (password != password_) return FoeError::NoRights;
  return FoeError::None;
}

// --- device thread ------------------------------------------------------------------------

void FoeFiles::queue(Kind kind, std::string_view name, size_t max_size) {
  queued_ = kind;
  queued_name_.assign(name);
  queued_max_ = max_size;
  awaited_ = ++last_id_;
  if (awaited_ == 0) awaited_ = ++last_id_;  // 0 means "none"
  awaited_kind_ = kind;
  start_queued();
}

void FoeFiles::start_queued() {
  if (queued_ == Kind::None || busy_.load(std::memory_order_acquire)) return;
  job_.kind = queued_;
  job_.id = awaited_;
  job_.name.swap(queued_name_);
  job_.max_size = queued_max_;
  job_.error = FoeError::None;
  job_.bytes.clear();
  if (queued_ == Kind::Write) job_.bytes.swap(incoming_);
  queued_ = Kind::None;
  busy_.store(true, std::memory_order_release);
  worker_.schedule(*this);
}

bool FoeFiles::finished(Kind kind) {
  start_queued();
  return awaited_ != 0 && awaited_kind_ == kind && queued_ == Kind::None &&
         !busy_.load(std::memory_order_acquire) && job_.id == awaited_;
}

ReadProgress FoeFiles::read_file(std::string_view name, uint32_t password, size_t max_size,
                                 std::vector<uint8_t>& contents) {
  abort_read();
  if (const FoeError e = check(name, password); e != FoeError::None) return {false, e};
  queue(Kind::Read, name, std::min(max_size, kMaxFileBytes));
  return poll_read(contents);
}

ReadProgress FoeFiles::poll_read(std::vector<uint8_t>& contents) {
  if (awaited_ == 0 || awaited_kind_ != Kind::Read) return {false, FoeError::NotDefined};
  if (!finished(Kind::Read)) return {true, FoeError::None};
  awaited_ = 0;
  if (job_.error != FoeError::None) return {false, job_.error};
  contents.swap(job_.bytes);
  return {false, FoeError::None};
}

void FoeFiles::abort_read() {
  if (awaited_kind_ != Kind::Read) return;
  // A read the worker runs finishes there; its result is not awaited any more.
  if (queued_ == Kind::Read) queued_ = Kind::None;
  awaited_ = 0;
  awaited_kind_ = Kind::None;
}

FoeError FoeFiles::begin_write(std::string_view name, uint32_t password) {
  abort_write();
  if (const FoeError e = check(name, password); e != FoeError::None) return e;
  write_name_.assign(name);
  incoming_.clear();
  // Address space only (pages come as the file arrives): no reallocation while it does.
  incoming_.reserve(kMaxFileBytes);
  writing_ = true;
  return FoeError::None;
}

FoeError FoeFiles::write_data(std::span<const uint8_t> data) {
  if (!writing_) return FoeError::Illegal;
  if (incoming_.size() + data.size() > kMaxFileBytes) return FoeError::DiskFull;
  incoming_.insert(incoming_.end(), data.begin(), data.end());
  return FoeError::None;
}

CommitProgress FoeFiles::commit() {
  if (!writing_) return commit_result_ = {false, FoeError::Illegal, 0, 0};
  writing_ = false;
  queue(Kind::Write, write_name_, 0);
  return poll_commit();
}

CommitProgress FoeFiles::poll_commit() {
  if (awaited_ == 0 || awaited_kind_ != Kind::Write) return commit_result_;
  // Done / Entire: one step (the store), 0 of 1 while it runs.
  if (!finished(Kind::Write)) return {true, FoeError::None, 0, 1};
  awaited_ = 0;
  return commit_result_ = {false, job_.error, 1, 1};
}

void FoeFiles::abort_write() {
  if (!writing_) return;  // a committed write's data waits for the worker: kept
  writing_ = false;
  incoming_ = {};
}

// --- worker thread ------------------------------------------------------------------------

bool FoeFiles::run_one() {
  if (job_.kind == Kind::Read) {
    job_.error = load(job_);
  } else {
    job_.error = store(job_);
    job_.bytes = {};  // stored: the memory goes back
  }
  busy_.store(false, std::memory_order_release);
  return false;
}

size_t FoeFiles::file_count() const {
  DIR* d = open_listing(dir_fd_);
  if (d == nullptr) return kMaxFiles;
  size_t n = 0;
  while (const dirent* e = ::readdir(d))
    if (e->d_name[0] != '.') ++n;
  ::closedir(d);
  return n;
}

FoeError FoeFiles::load(Job& job) const {
  const int fd =
      ::openat(dir_fd_, job.name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return error_of(errno);
  struct stat st {};
  FoeError result = FoeError::None;
  if (::fstat(fd, &st) != 0) {
    result = error_of(errno);
  } else if (!S_ISREG(st.st_mode)) {
    result = FoeError::AccessDenied;
  } else if (static_cast<size_t>(st.st_size) > job.max_size) {
    result = FoeError::DiskFull;
  } else {
    job.bytes.resize(static_cast<size_t>(st.st_size));
    const ssize_t got = base::read_fully(fd, job.bytes.data(), job.bytes.size());
    if (got < 0) {
      result = error_of(errno);
      job.bytes.clear();
    } else {
      job.bytes.resize(static_cast<size_t>(got));
    }
  }
  ::close(fd);
  return result;
}

FoeError FoeFiles::store(const Job& job) const {
  struct stat st {};
  if (::fstatat(dir_fd_, job.name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0) {
    if (!S_ISREG(st.st_mode)) return FoeError::AccessDenied;  // a link or a directory
  } else if (errno != ENOENT) {
    return error_of(errno);
  } else if (file_count() >= kMaxFiles) {
    return FoeError::DiskFull;
  }
  const std::string tmp = tmp_name(job.name);
  // A planted or stale temporary file is removed, never followed; the new one made afresh.
  if (::unlinkat(dir_fd_, tmp.c_str(), 0) != 0 && errno != ENOENT) return error_of(errno);
  const int fd =
      ::openat(dir_fd_, tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) return error_of(errno);
  FoeError e = FoeError::None;
  if (!base::write_all(fd, job.bytes.data(), job.bytes.size()) || ::fsync(fd) != 0) {
    e = error_of(errno);
  }
  ::close(fd);
  // rename(2) replaces a file named `name` itself; the old file stays until then.
  if (e == FoeError::None && ::renameat(dir_fd_, tmp.c_str(), dir_fd_, job.name.c_str()) != 0) {
    e = error_of(errno);
  }
  if (e != FoeError::None) {
    ::unlinkat(dir_fd_, tmp.c_str(), 0);
    return e;
  }
  // The rename itself survives a power loss only once the directory is synced.
  if (::fsync(dir_fd_) != 0) return error_of(errno);
  return FoeError::None;
}

}  // namespace rackcat::device
