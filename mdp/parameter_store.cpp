// Atomic, durable parameter file (see parameter_store.hpp). POSIX: write(2) to a temporary
// file in the same directory, fsync(2), rename(2) over the old file, fsync(2) of the directory
// so the rename itself survives a power loss.
#include "mdp/parameter_store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

namespace rackcat::mdp {
namespace {

constexpr char kMagic[8] = {'R', 'A', 'C', 'K', 'C', 'A', 'T', 'P'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeader = 8 + 4 + 4 + 4;

void put32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
uint32_t get32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
uint32_t crc32_of(const uint8_t* data, size_t n) {
  return static_cast<uint32_t>(::crc32(::crc32(0L, Z_NULL, 0), data, static_cast<uInt>(n)));
}

std::string dir_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string errno_text(const std::string& what, const std::string& path) {
  return what + " " + path + ": " + std::strerror(errno);
}

bool make_dirs(const std::string& dir, std::string& error) {
  std::string partial;
  size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    partial = dir.substr(0, pos);
    if (partial.empty()) continue;
    if (::mkdir(partial.c_str(), 0700) != 0 && errno != EEXIST) {
      error = errno_text("cannot create", partial);
      return false;
    }
  }
  return true;
}

bool fsync_dir(const std::string& dir, std::string& error) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    error = errno_text("cannot open", dir);
    return false;
  }
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) {
    error = errno_text("cannot fsync", dir);
    return false;
  }
  return true;
}

}  // namespace

std::vector<uint8_t> ParameterStore::encode(uint32_t fingerprint,
                                            std::span<const uint8_t> payload) {
  std::vector<uint8_t> out(kMagic, kMagic + 8);
  put32(out, kVersion);
  put32(out, fingerprint);
  put32(out, static_cast<uint32_t>(payload.size()));
  out.insert(out.end(), payload.begin(), payload.end());
  put32(out, crc32_of(out.data(), out.size()));
  return out;
}

bool ParameterStore::save(uint32_t fingerprint, std::span<const uint8_t> payload,
                          std::string& error) const {
  const std::string dir = dir_of(path_);
  if (!make_dirs(dir, error)) return false;
  const std::vector<uint8_t> bytes = encode(fingerprint, payload);
  const std::string tmp = path_ + ".tmp";
  // A leftover temp file (or a symlink planted in its place) is removed, never followed: the
  // new one is created afresh (O_EXCL, O_NOFOLLOW), so a store writes only inside `dir`.
  if (::unlink(tmp.c_str()) != 0 && errno != ENOENT) {
    error = errno_text("cannot remove", tmp);
    return false;
  }
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) {
    error = errno_text("cannot create", tmp);
    return false;
  }
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = errno_text("cannot write", tmp);
      ::close(fd);
      ::unlink(tmp.c_str());
      return false;
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) {
    error = errno_text("cannot fsync", tmp);
    ::close(fd);
    ::unlink(tmp.c_str());
    return false;
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path_.c_str()) != 0) {
    error = errno_text("cannot rename onto", path_);
    ::unlink(tmp.c_str());
    return false;
  }
  return fsync_dir(dir, error);
}

ParameterStore::LoadResult ParameterStore::load(uint32_t fingerprint, std::vector<uint8_t>& payload,
                                                std::string& detail) const {
  std::ifstream in(path_, std::ios::binary);
  if (!in) {
    detail = "no stored parameters (" + path_ + ")";
    return LoadResult::Missing;
  }
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  if (bytes.size() < kHeader + 4 || std::memcmp(bytes.data(), kMagic, 8) != 0) {
    detail = "ignored foreign parameter file " + path_ + ": not a rackcat parameter file";
    return LoadResult::Foreign;
  }
  const uint32_t length = get32(&bytes[16]);
  if (bytes.size() != kHeader + length + 4) {
    detail = "ignored corrupt parameter file " + path_ + ": length " +
             std::to_string(bytes.size()) + " does not match its header";
    return LoadResult::Corrupt;
  }
  if (crc32_of(bytes.data(), kHeader + length) != get32(&bytes[kHeader + length])) {
    detail = "ignored corrupt parameter file " + path_ + ": checksum mismatch";
    return LoadResult::Corrupt;
  }
  if (get32(&bytes[8]) != kVersion || get32(&bytes[12]) != fingerprint) {
    detail = "ignored foreign parameter file " + path_ +
             ": written for another rack configuration or format";
    return LoadResult::Foreign;
  }
  payload.assign(bytes.begin() + kHeader, bytes.begin() + static_cast<long>(kHeader + length));
  detail = "loaded stored parameters from " + path_;
  return LoadResult::Loaded;
}

bool ParameterStore::remove(std::string& error) const {
  if (::unlink(path_.c_str()) != 0 && errno != ENOENT) {
    error = errno_text("cannot remove", path_);
    return false;
  }
  return fsync_dir(dir_of(path_), error) || errno == ENOENT;
}

}  // namespace rackcat::mdp
