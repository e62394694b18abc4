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

// What FileAccess needs from the device it serves.
struct FileAccessHooks {
  std::function<EsmState()> state;
  std::function<std::vector<uint8_t>()> parameter_file;  // the stored parameter file's bytes
  // Checks and applies a parameter file; returns the refusal (None: stored and applied).
  std::function<foe::FoeError(std::span<const uint8_t>, std::string& detail)> restore_parameters;
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
  foe::CommitProgress parameters_result_;
  bool reported_ = false;  // the firmware commit's outcome was logged
};

}  // namespace rackcat::mdp
