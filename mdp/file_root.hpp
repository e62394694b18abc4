// A directory the user named at start (the rack file's own directory, `--data-dir`), below
// which files named by a rack file or a control-API request are read: opened relative to the
// directory's descriptor with openat2(2) RESOLVE_BENEATH, so neither "..", an absolute path
// nor a symbolic link can lead out of it; regular files only, never more than a size cap.
// Errors name the file and the reason, never its content.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace rackcat::mdp {

class FileRoot {
 public:
  // Throws std::runtime_error when `dir` cannot be opened as a directory.
  static std::shared_ptr<const FileRoot> open(const std::string& dir);
  ~FileRoot();
  FileRoot(const FileRoot&) = delete;
  FileRoot& operator=(const FileRoot&) = delete;

  const std::string& path() const { return path_; }
  // The content of `relative` (below the root). Throws std::invalid_argument with one line:
  // "FILE: not below DIR", "FILE: no such file", "FILE: not a regular file", "FILE: larger
  // than N bytes".
  std::string read(const std::string& relative, size_t max_bytes) const;

 private:
  FileRoot(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}
  std::string path_;
  int fd_ = -1;
};

}  // namespace rackcat::mdp
