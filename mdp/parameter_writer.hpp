// Runs 0xFBF2 stores off the ESC thread. A store is a write, two fsyncs and a rename: several
// milliseconds on a real disk, long enough for SOEM (2 ms frame timeout) to lose the frames the
// blocked ESC thread could not answer. So the SDO write returns at once with status 255 "command
// is executing" (ETG.5003.1 command status) and this worker writes the snapshot; the master
// polls subindex 2 until it reads 0 (done) or 2 (error). Stores submitted while one is running
// are coalesced: the latest snapshot is the one that ends up on disk.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "mdp/parameter_store.hpp"

namespace rackcat::mdp {

class ParameterWriter {
 public:
  explicit ParameterWriter(const ParameterStore& store);
  // Writes what is still pending, then stops.
  ~ParameterWriter();
  ParameterWriter(const ParameterWriter&) = delete;
  ParameterWriter& operator=(const ParameterWriter&) = delete;

  void submit(uint32_t fingerprint, std::vector<uint8_t> payload);
  // True while a submitted store has not reached the disk.
  bool busy() const;
  // Result of the last completed store; empty = success.
  std::optional<std::string> last_error() const;
  // Blocks until nothing is pending (0xFBF3/0xFBF4/0xFBF0 act on what is stored).
  void wait_idle();

 private:
  void run();

  const ParameterStore& store_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false;
  bool has_job_ = false;
  bool writing_ = false;
  uint32_t fingerprint_ = 0;
  std::vector<uint8_t> payload_;
  std::optional<std::string> error_;
  std::thread thread_;
};

}  // namespace rackcat::mdp
