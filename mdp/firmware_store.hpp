// The installed firmware container in the state directory (state_dir/firmware.rfw) and the
// atomic replacement of it: a firmware file arriving over FoE is kept in memory as it comes;
// at the last packet it is written to firmware.rfw.tmp, fsync(2)ed, read back and verified,
// renameat(2)d over firmware.rfw and the directory fsync(2)ed. Every file is opened relative to
// the state directory's descriptor (state_directory.hpp) with O_NOFOLLOW (the temporary file
// with O_EXCL as well), so nothing outside the directory is ever written and a planted link is
// refused, not followed. A kill -9 at any moment leaves the old firmware.rfw or the new one; a
// leftover temporary file is removed at the next start.
//
// The device thread never touches a file here: begin/append keep the bytes, and the commit
// (write, fsync, read back, SHA-256, rename) runs on the process's background worker
// (base/background_worker.hpp); the mailbox keeps answering (FoE Busy) meanwhile. One write at
// a time; all methods but poll_commit() and wait() belong to one thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "base/background_worker.hpp"
#include "foe/foe_error.hpp"
#include "mdp/state_directory.hpp"

namespace rackcat::mdp {

class FirmwareStore final : private base::BackgroundWorker::Client {
 public:
  // The largest file the store takes and reads back (the FoE limit, file_access.hpp, is the
  // same).
  static constexpr size_t kMaxBytes = 16 * 1024 * 1024;
  // Checks a complete candidate file; returns the FoE error that refuses it (None accepts).
  using Verifier = std::function<foe::FoeError(std::span<const uint8_t>, std::string& detail)>;

  // `dir` must stay open while the store lives; an unusable one refuses every write. Commits
  // run on `worker`.
  explicit FirmwareStore(std::shared_ptr<const StateDirectory> dir,
                         base::BackgroundWorker& worker = base::BackgroundWorker::shared());
  ~FirmwareStore();
  FirmwareStore(const FirmwareStore&) = delete;
  FirmwareStore& operator=(const FirmwareStore&) = delete;

  bool ok() const { return dir_fd_ >= 0; }
  const std::string& error() const { return error_; }
  std::string path() const;

  // The installed file's bytes (at most `max_size`); nullopt when there is none or it cannot
  // be read (`detail` says why). Reads the disk: not for the device thread.
  std::optional<std::vector<uint8_t>> read_installed(size_t max_size, std::string& detail) const;

  // --- one write -------------------------------------------------------------------------
  // Starts receiving a file (false while a commit runs, or with an unusable directory).
  bool begin(std::string& error);
  // The next bytes of the file (false beyond kMaxBytes or without begin()).
  bool append(std::span<const uint8_t> data, std::string& error);
  // Hands the file to the worker for its commit; poll_commit() reports it.
  void start_commit(Verifier verify);
  struct Status {
    bool busy = false;
    foe::FoeError error = foe::FoeError::None;  // when done: None = installed
    std::string detail;
  };
  Status poll_commit() const;
  // Drops an open write (not a running commit, which finishes first).
  void abort();
  // Waits for a running commit to finish (tests, shutdown; never the device thread).
  void wait();

 private:
  bool run_one() override;  // the worker: the commit
  foe::FoeError commit(std::string& detail);

  std::shared_ptr<const StateDirectory> dir_;
  base::BackgroundWorker& worker_;
  int dir_fd_ = -1;
  std::string error_;
  bool open_ = false;              // begin() was called, no commit or abort since
  std::vector<uint8_t> incoming_;  // the file being received

  // The worker's while busy_: the file, its check, the result.
  std::vector<uint8_t> file_;
  Verifier verify_;
  foe::FoeError result_ = foe::FoeError::None;
  std::string result_detail_;
  std::atomic<bool> busy_{false};
  mutable std::mutex done_mutex_;  // wait() sleeps on done_ until busy_ is false
  std::condition_variable done_;
};

}  // namespace rackcat::mdp
