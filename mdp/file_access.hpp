// The device's files over FoE (docs/FOE.md): what a master reads and writes, in which ESM
// state, with which password. The FoE protocol itself is foe::FoeServer's.
//
//   rackcat-<name>.rfw  firmware container (firmware_image.hpp). Write: BOOT only (else 0x8008
//                       Bootstrap only); verified, then installed atomically (FirmwareStore);
//                       runs after the next power cycle. Read: BOOT only; the running firmware.
//                       <name>: 1..48 of [A-Za-z0-9._-].
//   parameters.bin      the stored parameter set, the bytes 0xFBF2 stores (parameter_store.hpp).
//                       Read: PREOP, SAFEOP, OP. Write: PREOP only (SAFEOP/OP: 0x8002 Access
//                       denied; BOOT: 0x8009 Not Bootstrap); checked like SDO writes, stored as
//                       0xFBF2 would, applied as 0xFBF4 would.
//                       The disk work runs off the device thread (the device's hooks queue it on
//                       the background worker): a read request's first Data waits until the
//                       file is read (deferred, never Busy: ETG.1000.6 §5.8); a write's last
//                       Data is answered Busy until the save is durable and the set applied.
// Any other name: 0x8001 Not found. A password other than the device's FoE password: 0x800A
// No rights.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "coe/access.hpp"
#include "foe/file_backend.hpp"
#include "mdp/firmware_store.hpp"

namespace rackcat::mdp {

inline constexpr char kParameterFileName[] = "parameters.bin";
inline constexpr size_t kMaxParameterFile = 64 * 1024;
// The largest firmware file FoE takes (0x8003 Disk full beyond).
inline constexpr size_t kMaxFirmwareFile = FirmwareStore::kMaxBytes;

// What FileAccess needs from the device it serves. All called on the device thread; none may
// wait for the disk.
struct FileAccessHooks {
  std::function<EsmState()> state;
  // parameters.bin read: start_parameter_read queues the read of the stored file;
  // poll_parameter_read answers busy until the file's bytes are in `contents` (or the
  // refusal); abort_parameter_read drops a read no one waits for any more.
  std::function<void()> start_parameter_read;
  std::function<foe::ReadProgress(std::vector<uint8_t>& contents)> poll_parameter_read;
  std::function<void()> abort_parameter_read;
  // parameters.bin write: checks the file at once (the refusal, nothing changes) and queues
  // its durable save (None); poll_restore answers busy until it is saved and applied, then
  // the outcome (a failed save: its FoE error, the old set stays in use and on disk).
  std::function<foe::FoeError(std::span<const uint8_t>, std::string& detail)> restore_parameters;
  std::function<foe::CommitProgress(std::string& detail)> poll_restore;
  std::function<std::vector<uint8_t>()> running_firmware;  // the firmware container running now
  FirmwareStore::Verifier verify_firmware;
  std::function<void(const std::string&)> log;  // one line per refused or finished transfer
};

// True for a firmware file name: "rackcat-" + 1..48 of [A-Za-z0-9._-] + ".rfw".
bool is_firmware_file_name(std::string_view name);

class FileAccess final : public foe::FileBackend {
 public:
  FileAccess(FirmwareStore& store, uint32_t password, FileAccessHooks hooks);

  foe::ReadProgress read_file(std::string_view name, uint32_t password, size_t max_size,
                              std::vector<uint8_t>& contents) override;
  foe::ReadProgress poll_read(std::vector<uint8_t>& contents) override;
  void abort_read() override;
  foe::FoeError begin_write(std::string_view name, uint32_t password) override;
  foe::FoeError write_data(std::span<const uint8_t> data) override;
  foe::CommitProgress commit() override;
  foe::CommitProgress poll_commit() override;
  void abort_write() override;

 private:
  enum class Target : uint8_t { None, Firmware, Parameters };
  foe::FoeError refuse(foe::FoeError e, const std::string& why);

  FirmwareStore& store_;
  uint32_t password_;
  FileAccessHooks hooks_;
  Target target_ = Target::None;
  std::vector<uint8_t> parameters_;  // a parameter file being received
  size_t received_ = 0;
  bool reading_parameters_ = false;  // a parameters.bin read waits for its bytes
  size_t read_max_ = 0;              // ... and may be at most this long
  bool restoring_ = false;           // a received parameter file is being saved and applied
  foe::CommitProgress parameters_result_;
  bool reported_ = false;  // the firmware commit's outcome was logged
};

}  // namespace rackcat::mdp
