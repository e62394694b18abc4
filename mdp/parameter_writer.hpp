// Runs every file operation of the command objects off the ESC thread: 0xFBF2 store, 0xFBF3
// checksum, 0xFBF4 load and 0xFBF0 reset (the factory reset deletes the file, both resets read
// it back), and those of the FoE file parameters.bin (docs/FOE.md): its read (ReadFile) and the
// durable save of a restored set (Restore). A store is a write, two fsyncs and a rename: several
// milliseconds on a real disk, long enough for SOEM (2 ms frame timeout) to lose the frames a
// blocked ESC thread could not answer; a read of a planted file could block or take long too. So
// each SDO write returns at once with status 255 "command is executing" (ETG.5003.1 command status)
// and this worker does the file work; the ESC thread takes the result with take() and finishes the
// command (status 0/1 done, 2 error) while the master polls subindex 2.
//
// Jobs run in the order they were submitted (a checksum after a store sums what was stored, an
// FoE read after a store reads what was stored: no waiting for the store on the ESC thread);
// a job submitted again while still queued replaces its own earlier request (the latest store
// snapshot is the one that ends up on disk).
//
// The work runs on the process-wide BackgroundWorker (one thread for all devices, started with
// the first job), not on a thread per device: the thread count does not grow with the slaves.
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "mdp/background_worker.hpp"
#include "mdp/parameter_store.hpp"

namespace rackcat::mdp {

class ParameterWriter final : private BackgroundWorker::Client {
 public:
  enum class Job : uint8_t { Store, Checksum, Load, Reset, ReadFile, Restore };
  static constexpr size_t kJobs = 6;

  struct Result {
    bool ok = false;
    std::string report;          // one line: why not ok, or what was loaded (no file content)
    std::vector<uint8_t> bytes;  // Checksum: the digest; Load/Reset/ReadFile: the stored payload
    bool stored = false;         // Load/Reset/ReadFile: a valid file was read (else: none stored)
    int error_number = 0;        // Store/Restore not ok: the errno of the failed call (or 0)
    uint64_t sequence = 0;       // finishing order: results taken together apply in this order
  };

  explicit ParameterWriter(const ParameterStore& store,
                           BackgroundWorker& worker = BackgroundWorker::shared());
  // Finishes what is queued, then stops.
  ~ParameterWriter();
  ParameterWriter(const ParameterWriter&) = delete;
  ParameterWriter& operator=(const ParameterWriter&) = delete;

  void submit_store(uint32_t fingerprint, std::vector<uint8_t> payload);
  // `algorithm`: 0xFBF3 bit (CRC-32 0x02, MD5 0x04, SHA-1 0x08) over the stored payload, or
  // over `defaults` when nothing valid is stored.
  void submit_checksum(uint32_t fingerprint, uint8_t algorithm, std::vector<uint8_t> defaults);
  void submit_load(uint32_t fingerprint);
  // The stored payload for an FoE read of parameters.bin (ok; `stored` false when none is
  // valid: the caller serves its defaults).
  void submit_read_file(uint32_t fingerprint);
  // Saves `payload` as a store does (FoE write of parameters.bin); the caller applies it to the
  // objects once the result says ok.
  void submit_restore(uint32_t fingerprint, std::vector<uint8_t> payload);
  // `also`: more file work of the reset (the device's firmware container), run on the worker
  // before the result is published.
  void submit_reset(uint32_t fingerprint, bool factory, std::function<void()> also = {});

  // The result of `job` once it has finished, taken once; nullopt while it is queued or
  // running, or when none was submitted.
  std::optional<Result> take(Job job);
  // True when some finished result waits to be taken (one atomic load: cheap to ask every cycle).
  bool has_results() const { return results_.load(std::memory_order_acquire) != 0; }
  // `flag` (or nullptr) is set to true, after a full fence, whenever the worker has made a
  // result available, so an owner can wait for results without asking has_results() every
  // cycle (mdp::Device's mailbox hint, issue 16). Set before the first submit.
  void notify_results(std::atomic<bool>* flag) { result_flag_ = flag; }
  // True while `job` is queued or running.
  bool busy(Job job) const;
  // Blocks until nothing is queued or running (tests, shutdown).
  void wait_idle();

 private:
  struct Request {
    uint32_t fingerprint = 0;
    std::vector<uint8_t> payload;  // Store/Restore: the set to save; Checksum: the defaults
    uint8_t algorithm = 0;
    bool factory = false;
    std::function<void()> also;  // Reset: the caller's own file work
  };
  struct Slot {
    bool queued = false;
    bool running = false;
    Request request;
    std::optional<Result> result;
  };
  void submit(Job job, Request request);
  Result execute(Job job, const Request& r) const;
  bool run_one() override;

  const ParameterStore& store_;
  BackgroundWorker& worker_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> order_;
  std::array<Slot, kJobs> slots_;
  std::atomic<unsigned> results_{0};          // results set and not yet taken
  uint64_t finished_ = 0;                     // jobs finished (under mutex_): Result::sequence
  std::atomic<bool>* result_flag_ = nullptr;  // notify_results()
};

}  // namespace rackcat::mdp
