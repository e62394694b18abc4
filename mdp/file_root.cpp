// openat2(2) with RESOLVE_BENEATH (Linux 5.6); see file_root.hpp.
#include "mdp/file_root.hpp"

#include <fcntl.h>
#include <linux/openat2.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "base/fd_io.hpp"

namespace rackcat::mdp {
namespace {

// The name as shown in errors: bounded, printable.
std::string shown(const std::string& name) {
  std::string out = name.substr(0, 120);
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  return out;
}

}  // namespace

std::shared_ptr<const FileRoot> FileRoot::open(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    throw std::runtime_error("cannot open directory " + shown(dir) + ": " + std::strerror(errno));
  }
  return std::shared_ptr<const FileRoot>(new FileRoot(dir, fd));
}

FileRoot::~FileRoot() {
  if (fd_ >= 0) ::close(fd_);
}

std::string FileRoot::read(const std::string& relative, size_t max_bytes) const {
  const std::string name = shown(relative);
  if (relative.empty() || relative.find('\0') != std::string::npos) {
    throw std::invalid_argument("'" + name + "': not a file name");
  }
  open_how how{};
  how.flags = O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC;
  how.resolve = RESOLVE_BENEATH | RESOLVE_NO_MAGICLINKS;
  const int fd = static_cast<int>(::syscall(SYS_openat2, fd_, relative.c_str(), &how, sizeof how));
  if (fd < 0) {
    const int err = errno;
    if (err == EXDEV || err == ELOOP) {
      throw std::invalid_argument(name + ": not below " + shown(path_));
    }
    if (err == ENOENT) throw std::invalid_argument(name + ": no such file below " + shown(path_));
    throw std::invalid_argument(name + ": cannot open: " + std::strerror(err));
  }
  struct stat st {};
  std::string out;
  const char* problem = nullptr;
  int read_error = 0;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    problem = "not a regular file";
  } else if (static_cast<uint64_t>(st.st_size) > max_bytes) {
    problem = "too large";
  } else {
    out.resize(static_cast<size_t>(st.st_size));
    const ssize_t got = base::read_fully(fd, out.data(), out.size());
    if (got < 0) {
      read_error = errno;
      out.clear();
    } else {
      out.resize(static_cast<size_t>(got));
    }
  }
  ::close(fd);
  if (read_error != 0)
    throw std::invalid_argument(name + ": cannot read: " + std::strerror(read_error));
  if (problem != nullptr) {
    throw std::invalid_argument(name + ": " + problem + " (at most " + std::to_string(max_bytes) +
                                " bytes of a regular file)");
  }
  return out;
}

}  // namespace rackcat::mdp
