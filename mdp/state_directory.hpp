// The state directory (`--state-dir`): one directory descriptor, opened once, and every file
// below it reached relative to it. Names are single path components; symbolic links below the
// directory are never followed (O_NOFOLLOW on every component), only regular files are read,
// and never more than a size cap, so nothing planted in the directory (a symlink out of it, a
// directory, a FIFO, a device, a huge file) can redirect, block or exhaust the device. Files
// are replaced atomically and durably: temporary file, fsync, renameat, fsync of the directory.
//
// An unusable directory (missing and not creatable, a symlink where a subdirectory should be,
// no permission) is not an error at start: it keeps its reason, every read says "missing", and
// every write fails with that reason. The device then runs on its defaults.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace rackcat::mdp {

class StateDirectory {
 public:
  enum class ReadResult { Ok, Missing, Refused };

  // The directory the user named (its own path is resolved as given, symlinks included: the
  // user chose it), created with mode 0700 when missing. Opens it with the rights of the
  // calling process: call it after privileges are dropped.
  static std::shared_ptr<StateDirectory> open(const std::string& path);

  ~StateDirectory();
  StateDirectory(const StateDirectory&) = delete;
  StateDirectory& operator=(const StateDirectory&) = delete;

  // The subdirectory `name` (one component), created 0700 when missing. A symlink, a
  // non-directory or a name with '/' gives an unusable directory that says why.
  std::shared_ptr<StateDirectory> child(const std::string& name) const;

  bool usable() const { return fd_ >= 0; }
  const std::string& problem() const { return problem_; }  // empty when usable
  const std::string& path() const { return path_; }
  int fd() const { return fd_; }

  // Reads the regular file `name` if it holds at most `max_bytes`. Missing: no such file (or
  // the directory is unusable). Refused: a symlink, a directory, a FIFO, a device, a file over
  // the cap, or a read error; `why` says which without quoting any content.
  ReadResult read(const std::string& name, size_t max_bytes, std::vector<uint8_t>& out,
                  std::string& why) const;
  // Replaces `name` by `bytes` (mode `mode`, owned by the calling user). A planted temp file
  // or symlink is removed, never followed. False with `error`; the old file is then unchanged.
  // `error_number` (when given) receives the errno of the failed call (ENOSPC for a full
  // disk...), 0 when the directory is unusable or the name is not a single component.
  bool replace(const std::string& name, std::span<const uint8_t> bytes, mode_t mode,
               std::string& error, int* error_number = nullptr) const;
  // Deletes `name` durably; a missing file is success.
  bool remove(const std::string& name, std::string& error) const;

 private:
  StateDirectory(std::string path, int fd, std::string problem);
  // Why `name` cannot be used here: the directory is unusable, or `name` is not a single path
  // component; empty when it can.
  std::string name_problem(const std::string& name) const;

  std::string path_;
  int fd_ = -1;
  std::string problem_;
};

}  // namespace rackcat::mdp
