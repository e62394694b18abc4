// The files a device from its ESI serves over FoE (ETG.1000.6 §5.8) when its ESI announces
// <Mailbox><FoE/>: a flat directory of its own (the line's state directory / "esi-<position>"),
// files written by the master are stored there and read back. The ESI does not say what a
// device's files mean, so they are kept as written, nothing is executed or interpreted.
//
// The device thread never touches the file system: it checks a request (name, password) and
// keeps the data of a write in memory; opening, reading, writing, fsync and rename run on the
// process's background worker (base/background_worker.hpp). Meanwhile the FoE server answers
// a write's last Data with Busy (foe::FileBackend::commit/poll_commit) and defers a read
// request's first Data (read_file/poll_read) until the worker is done.
//
// Rules (each refusal is the FoE error the master gets, ETG.1000.6 §5.8 Table "FoE error codes"):
// - names: 1..48 of [A-Za-z0-9._-], not starting with '.' (0x8004 Illegal otherwise); they
//   never reach a path: each is one component beneath the directory's descriptor, opened with
//   O_NOFOLLOW, so a planted link or a directory is refused (0x8002 Access denied), never
//   followed, and ".." is not a name;
// - the device's FoE password (rackcat run --foe-password, docs/FOE.md) on every read and
//   write request (0x800A No rights otherwise);
// - a missing file: 0x8001 Not found; at most kMaxFiles files and kMaxFileBytes per file, and
//   a full disk (ENOSPC, EDQUOT, EFBIG): 0x8003 Disk full; no permission, a read-only file
//   system: 0x8002 Access denied; any other I/O failure (EIO, ...): 0x8000 Not defined;
// - a write lands in a temporary file (".<name>.tmp"), fsync'ed and renamed over the old file,
//   then the directory is fsync'ed: a reader sees the old file or the new one, and a refused or
//   failed write leaves the old file as it was (the temporary file is removed);
// - an unusable directory (not creatable, a link) refuses every request with 0x8000.
// The limits on a file's count and on a link or directory in the way are checked when the
// write is committed (on the worker), so the last Data, not the write request, gets them.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/background_worker.hpp"
#include "foe/file_backend.hpp"

namespace rackcat::device {

class FoeFiles final : public foe::FileBackend, private base::BackgroundWorker::Client {
 public:
  static constexpr size_t kMaxFiles = 64;
  static constexpr size_t kMaxFileBytes = 1u << 20;

  // The subdirectory `name` (one component) of the directory open as `parent_fd` (created
  // 0700 when missing; parent_fd < 0 or a link there: unusable). Runs on the thread that builds
  // the line, not the device thread. File work runs on `worker`.
  FoeFiles(int parent_fd, const std::string& name, uint32_t password,
           base::BackgroundWorker& worker = base::BackgroundWorker::shared());
  ~FoeFiles() override;
  FoeFiles(const FoeFiles&) = delete;
  FoeFiles& operator=(const FoeFiles&) = delete;

  bool usable() const { return dir_fd_ >= 0; }

  // --- the device thread (FoE server) -----------------------------------------------------
  foe::ReadProgress read_file(std::string_view name, uint32_t password, size_t max_size,
                              std::vector<uint8_t>& contents) override;
  foe::ReadProgress poll_read(std::vector<uint8_t>& contents) override;
  void abort_read() override;
  foe::FoeError begin_write(std::string_view name, uint32_t password) override;
  foe::FoeError write_data(std::span<const uint8_t> data) override;
  foe::CommitProgress commit() override;
  foe::CommitProgress poll_commit() override;
  void abort_write() override;

  static bool valid_name(std::string_view name);

 private:
  enum class Kind : uint8_t { None, Read, Write };
  // One file operation. The device thread fills it while the worker is idle and then sets
  // busy_; while busy_ is set it belongs to the worker, which sets `error` (and `bytes` for a
  // read) and clears busy_.
  struct Job {
    Kind kind = Kind::None;
    uint32_t id = 0;
    std::string name;
    std::vector<uint8_t> bytes;  // a write's data, a read's contents
    size_t max_size = 0;
    foe::FoeError error = foe::FoeError::None;
  };

  foe::FoeError check(std::string_view name, uint32_t password) const;
  // Device thread: the next job waits for the worker to be free; start_queued() hands it over.
  void queue(Kind kind, std::string_view name, size_t max_size);
  void start_queued();
  // Whether the awaited job of `kind` is finished (its result in job_).
  bool finished(Kind kind);

  // Worker thread.
  bool run_one() override;
  foe::FoeError load(Job& job) const;
  foe::FoeError store(const Job& job) const;
  size_t file_count() const;

  int dir_fd_ = -1;
  uint32_t password_;
  base::BackgroundWorker& worker_;

  // Device thread only.
  Kind queued_ = Kind::None;  // a job not yet handed to the worker
  std::string queued_name_;
  size_t queued_max_ = 0;
  uint32_t awaited_ = 0;  // the id of the job whose result the FoE server waits for (0: none)
  Kind awaited_kind_ = Kind::None;
  uint32_t last_id_ = 0;
  bool writing_ = false;           // a write request is receiving data
  std::string write_name_;         // its file
  std::vector<uint8_t> incoming_;  // its data so far
  foe::CommitProgress commit_result_;

  Job job_;
  std::atomic<bool> busy_{false};
};

}  // namespace rackcat::device
