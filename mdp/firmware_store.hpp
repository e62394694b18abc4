// The installed firmware container in the state directory (state_dir/firmware.rfw) and the
// atomic replacement of it: a firmware file arriving over FoE is written to firmware.rfw.tmp
// as it comes, then fsync(2), read back and verified, renameat(2)d over firmware.rfw and the
// directory fsync(2)ed. Every file is opened relative to the state directory's descriptor
// (state_directory.hpp) with O_NOFOLLOW (the temporary file with O_EXCL as well), so nothing
// outside the directory is ever written and a planted link is refused, not followed. A kill -9 at
// any moment leaves the old firmware.rfw or the new one; a leftover temporary file is removed at
// the next start.
//
// The commit (fsync, read back, SHA-256) runs on a worker thread: the mailbox keeps answering
// (FoE Busy) meanwhile. One write at a time; all methods but poll_commit() belong to one thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "foe/foe_error.hpp"
#include "mdp/state_directory.hpp"

namespace rackcat::mdp {

class FirmwareStore {
 public:
  // The largest file the store reads back (the FoE limit, file_access.hpp, is the same).
  static constexpr size_t kMaxBytes = 16 * 1024 * 1024;
  // Checks a complete candidate file; returns the FoE error that refuses it (None accepts).
  using Verifier = std::function<foe::FoeError(std::span<const uint8_t>, std::string& detail)>;

  // `dir` must stay open while the store lives; an unusable one refuses every write.
  explicit FirmwareStore(std::shared_ptr<const StateDirectory> dir);
  ~FirmwareStore();
  FirmwareStore(const FirmwareStore&) = delete;
  FirmwareStore& operator=(const FirmwareStore&) = delete;

  bool ok() const { return dir_fd_ >= 0; }
  const std::string& error() const { return error_; }
  std::string path() const;

  // The installed file's bytes (at most `max_size`); nullopt when there is none or it cannot
  // be read (`detail` says why).
  std::optional<std::vector<uint8_t>> read_installed(size_t max_size, std::string& detail) const;

  // --- one write -------------------------------------------------------------------------
  bool begin(std::string& error);
  bool append(std::span<const uint8_t> data, std::string& error);
  // Starts the commit on the worker; poll_commit() reports it.
  void start_commit(Verifier verify);
  struct Status {
    bool busy = false;
    foe::FoeError error = foe::FoeError::None;  // when done: None = installed
    std::string detail;
  };
  Status poll_commit() const;
  // Drops an open write (not a running commit, which finishes first).
  void abort();
  // Waits for a running commit to finish.
  void wait();

 private:
  void commit(const Verifier& verify);
  void close_tmp();

  std::shared_ptr<const StateDirectory> dir_;
  int dir_fd_ = -1;
  std::string error_;
  int tmp_fd_ = -1;
  std::thread worker_;
  std::atomic<bool> busy_{false};
  foe::FoeError result_ = foe::FoeError::None;  // written by the worker before busy_ = false
  std::string result_detail_;
};

}  // namespace rackcat::mdp
