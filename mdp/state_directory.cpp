// State directory access through one directory descriptor (see state_directory.hpp). POSIX
// *at() calls relative to the descriptor; O_NOFOLLOW on every name, O_NONBLOCK so that a FIFO
// planted in the directory cannot block the open, fstat(2) before any byte is read.
#include "mdp/state_directory.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "base/fd_io.hpp"

namespace rackcat::mdp {
namespace {

std::string reason(int err) {
  return std::strerror(err);
}

// mkdir -p with mode 0700 for the components the user named.
bool make_dirs(const std::string& dir, std::string& error) {
  size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    const std::string partial = dir.substr(0, pos);
    if (partial.empty()) continue;
    if (::mkdir(partial.c_str(), 0700) != 0 && errno != EEXIST) {
      error = "cannot create " + partial + ": " + reason(errno);
      return false;
    }
  }
  return true;
}

bool single_component(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name.find('\0') == std::string::npos;
}

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

StateDirectory::StateDirectory(std::string path, int fd, std::string problem)
    : path_(std::move(path)), fd_(fd), problem_(std::move(problem)) {}

StateDirectory::~StateDirectory() {
  if (fd_ >= 0) ::close(fd_);
}

std::shared_ptr<StateDirectory> StateDirectory::open(const std::string& path) {
  std::string error;
  if (path.empty()) error = "no state directory given";
  if (error.empty() && !make_dirs(path, error)) {
    return std::shared_ptr<StateDirectory>(new StateDirectory(path, -1, error));
  }
  int fd = -1;
  if (error.empty()) {
    fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) error = "cannot open state directory " + path + ": " + reason(errno);
  }
  return std::shared_ptr<StateDirectory>(new StateDirectory(path, fd, error));
}

std::shared_ptr<StateDirectory> StateDirectory::child(const std::string& name) const {
  const std::string path = path_ + "/" + name;
  auto unusable = [&](const std::string& why) {
    return std::shared_ptr<StateDirectory>(new StateDirectory(path, -1, why));
  };
  if (std::string problem = name_problem(name); !problem.empty()) return unusable(problem);
  if (::mkdirat(fd_, name.c_str(), 0700) != 0 && errno != EEXIST) {
    return unusable("cannot create " + path + ": " + reason(errno));
  }
  const int fd = ::openat(fd_, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) {
    // ELOOP: a symlink (O_NOFOLLOW); ENOTDIR: a file or a symlink to one.
    const int err = errno;
    if (err == ELOOP || err == ENOTDIR) {
      return unusable(path + " is not a directory of its own (symlinks are not followed)");
    }
    return unusable("cannot open " + path + ": " + reason(err));
  }
  return std::shared_ptr<StateDirectory>(new StateDirectory(path, fd, {}));
}

std::string StateDirectory::name_problem(const std::string& name) const {
  if (!usable()) return problem_.empty() ? "state directory " + path_ + " unusable" : problem_;
  if (!single_component(name)) return "not a single path component: " + path_ + "/" + name;
  return {};
}

StateDirectory::ReadResult StateDirectory::read(const std::string& name, size_t max_bytes,
                                                std::vector<uint8_t>& out, std::string& why) const {
  out.clear();
  const std::string path = path_ + "/" + name;
  if (std::string problem = name_problem(name); !problem.empty()) {
    why = std::move(problem);
    return usable() ? ReadResult::Refused : ReadResult::Missing;
  }
  const int fd =
      ::openat(fd_, name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    if (err == ENOENT) {
      why = "no " + path;
      return ReadResult::Missing;
    }
    why = err == ELOOP ? path + " is a symbolic link (not followed)"
                       : "cannot open " + path + ": " + reason(err);
    return ReadResult::Refused;
  }
  struct stat st {};
  ReadResult result = ReadResult::Ok;
  if (::fstat(fd, &st) != 0) {
    why = "cannot stat " + path + ": " + reason(errno);
    result = ReadResult::Refused;
  } else if (!S_ISREG(st.st_mode)) {
    why = path + " is " + kind_of(st.st_mode) + ", not a regular file";
    result = ReadResult::Refused;
  } else if (static_cast<uint64_t>(st.st_size) > max_bytes) {
    why = path + " is " + std::to_string(st.st_size) + " bytes, more than the " +
          std::to_string(max_bytes) + " allowed";
    result = ReadResult::Refused;
  } else {
    // One byte more than the cap: a file that grew since fstat is refused too.
    out.resize(max_bytes + 1);
    const ssize_t n = base::read_fully(fd, out.data(), out.size());
    const size_t got = n < 0 ? 0 : static_cast<size_t>(n);
    if (n < 0) {
      why = "cannot read " + path + ": " + reason(errno);
      result = ReadResult::Refused;
    } else if (got > max_bytes) {
      why = path + " grew beyond " + std::to_string(max_bytes) + " bytes";
      result = ReadResult::Refused;
    }
    out.resize(result == ReadResult::Ok ? got : 0);
  }
  ::close(fd);
  return result;
}

bool StateDirectory::replace(const std::string& name, std::span<const uint8_t> bytes, mode_t mode,
                             std::string& error, int* error_number) const {
  const std::string path = path_ + "/" + name;
  int ignored = 0;
  int& err = error_number != nullptr ? *error_number : ignored;
  err = 0;
  if (std::string problem = name_problem(name); !problem.empty()) {
    error = std::move(problem);
    return false;
  }
  const std::string tmp = name + ".tmp";
  // A leftover temp file (or a symlink planted in its place) is removed, never followed: the
  // new one is created afresh (O_EXCL, O_NOFOLLOW), so a store writes only inside the directory.
  if (::unlinkat(fd_, tmp.c_str(), 0) != 0 && errno != ENOENT) {
    err = errno;
    error = "cannot remove " + path + ".tmp: " + reason(err);
    return false;
  }
  const int fd =
      ::openat(fd_, tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, mode);
  if (fd < 0) {
    err = errno;
    error = "cannot create " + path + ".tmp: " + reason(err);
    return false;
  }
  auto fail = [&](const char* what) {
    err = errno;
    error = std::string(what) + " " + path + ".tmp: " + reason(err);
    ::close(fd);
    ::unlinkat(fd_, tmp.c_str(), 0);
    return false;
  };
  if (!base::write_all(fd, bytes.data(), bytes.size())) return fail("cannot write");
  if (::fchmod(fd, mode) != 0) return fail("cannot chmod");  // umask may have narrowed it
  if (::fsync(fd) != 0) return fail("cannot fsync");
  ::close(fd);
  // rename(2) replaces a symlink or file named `name` itself, never what it points to; a
  // directory there makes it fail (EISDIR), leaving everything as it was.
  if (::renameat(fd_, tmp.c_str(), fd_, name.c_str()) != 0) {
    err = errno;
    error = "cannot rename onto " + path + ": " + reason(err);
    ::unlinkat(fd_, tmp.c_str(), 0);
    return false;
  }
  if (::fsync(fd_) != 0) {
    err = errno;
    error = "cannot fsync " + path_ + ": " + reason(err);
    return false;
  }
  return true;
}

bool StateDirectory::remove(const std::string& name, std::string& error) const {
  const std::string path = path_ + "/" + name;
  if (std::string problem = name_problem(name); !problem.empty()) {
    error = std::move(problem);
    return false;
  }
  if (::unlinkat(fd_, name.c_str(), 0) != 0) {
    if (errno == ENOENT) return true;
    error = "cannot remove " + path + ": " + reason(errno);
    return false;
  }
  if (::fsync(fd_) != 0) {
    error = "cannot fsync " + path_ + ": " + reason(errno);
    return false;
  }
  return true;
}

}  // namespace rackcat::mdp
