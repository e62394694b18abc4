// File names, states and passwords of the device's FoE files (file_access.hpp).
#include "mdp/file_access.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace rackcat::mdp {

using foe::CommitProgress;
using foe::FoeError;

bool is_firmware_file_name(std::string_view name) {
  constexpr std::string_view kPrefix = "rackcat-", kSuffix = ".rfw";
  if (name.size() <= kPrefix.size() + kSuffix.size() ||
      name.size() > kPrefix.size() + 48 + kSuffix.size()) {
    return false;
  }
  if (name.substr(0, kPrefix.size()) != kPrefix ||
      name.substr(name.size() - kSuffix.size()) != kSuffix) {
    return false;
  }
  const auto stem = name.substr(kPrefix.size(), name.size() - kPrefix.size() - kSuffix.size());
  return std::all_of(stem.begin(), stem.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' ||
           c == '_' || c == '-';
  });
}

FileAccess::FileAccess(FirmwareStore& store, uint32_t password, FileAccessHooks hooks)
    : store_(store), password_(password), hooks_(std::move(hooks)) {}

FoeError FileAccess::refuse(FoeError e, const std::string& why) {
  if (hooks_.log) {
    char code[8];
    std::snprintf(code, sizeof code, "%04X", static_cast<unsigned>(e));
    hooks_.log("FoE: refused with 0x" + std::string(code) + " (" + std::string(foe::describe(e)) +
               "): " + why);
  }
  return e;
}

foe::ReadProgress FileAccess::read_file(std::string_view name, uint32_t password, size_t max_size,
                                        std::vector<uint8_t>& contents) {
  abort_read();
  const EsmState state = hooks_.state();
  const bool firmware = is_firmware_file_name(name);
  if (!firmware && name != kParameterFileName) {
    return {false, refuse(FoeError::NotFound, "no file " + std::string(name))};
  }
  if (password != password_) return {false, refuse(FoeError::NoRights, "wrong password")};
  if (firmware) {
    if (state != EsmState::Boot) {
      return {false, refuse(FoeError::BootstrapOnly, "firmware is read in BOOT only")};
    }
    contents = hooks_.running_firmware();  // in memory since power-on
    if (contents.size() > max_size)
      return {false, refuse(FoeError::DiskFull, "file larger than FoE allows")};
    return {false, FoeError::None};
  }
  if (state == EsmState::Boot) {
    return {false, refuse(FoeError::NotBootstrap, "parameters are not served in BOOT")};
  }
  // The stored file is read on the worker: the reply waits (FoeServer::poll -> poll_read).
  hooks_.start_parameter_read();
  reading_parameters_ = true;
  read_max_ = max_size;
  return poll_read(contents);
}

foe::ReadProgress FileAccess::poll_read(std::vector<uint8_t>& contents) {
  if (!reading_parameters_) return {false, FoeError::NotDefined};
  const foe::ReadProgress p = hooks_.poll_parameter_read(contents);
  if (p.busy) return p;
  reading_parameters_ = false;
  if (p.error != FoeError::None) return {false, refuse(p.error, "parameter file not read")};
  if (contents.size() > read_max_)
    return {false, refuse(FoeError::DiskFull, "file larger than FoE allows")};
  return {false, FoeError::None};
}

void FileAccess::abort_read() {
  if (!reading_parameters_) return;
  reading_parameters_ = false;
  hooks_.abort_parameter_read();
}

FoeError FileAccess::begin_write(std::string_view name, uint32_t password) {
  if (restoring_ && poll_commit().busy) {
    return refuse(FoeError::AccessDenied, "a parameter restore is still running");
  }
  abort_write();
  const EsmState state = hooks_.state();
  const bool firmware = is_firmware_file_name(name);
  if (!firmware && name != kParameterFileName) {
    return refuse(FoeError::NotFound, "no file " + std::string(name));
  }
  if (password != password_) return refuse(FoeError::NoRights, "wrong password");
  received_ = 0;
  if (firmware) {
    if (state != EsmState::Boot) {
      return refuse(FoeError::BootstrapOnly, "firmware is written in BOOT only");
    }
    if (store_.poll_commit().busy) return refuse(FoeError::AccessDenied, "a commit is running");
    std::string error;
    if (!store_.begin(error)) return refuse(FoeError::FlashProblem, error);
    target_ = Target::Firmware;
    reported_ = false;
    return FoeError::None;
  }
  if (state == EsmState::Boot) {
    return refuse(FoeError::NotBootstrap, "parameters are not written in BOOT");
  }
  if (state != EsmState::PreOp) {
    return refuse(FoeError::AccessDenied, "parameters are written in PREOP only");
  }
  parameters_.clear();
  target_ = Target::Parameters;
  return FoeError::None;
}

FoeError FileAccess::write_data(std::span<const uint8_t> data) {
  received_ += data.size();
  if (target_ == Target::Firmware) {
    std::string error;
    if (!store_.append(data, error)) return refuse(FoeError::DiskFull, error);
    return FoeError::None;
  }
  if (target_ == Target::Parameters) {
    if (received_ > kMaxParameterFile) {
      return refuse(FoeError::DiskFull, "parameter file larger than 64 KiB");
    }
    parameters_.insert(parameters_.end(), data.begin(), data.end());
    return FoeError::None;
  }
  return FoeError::Illegal;
}

CommitProgress FileAccess::commit() {
  if (target_ == Target::Firmware) {
    store_.start_commit(hooks_.verify_firmware);
    return poll_commit();
  }
  if (target_ == Target::Parameters) {
    // Checked here, on the device thread (a refusal changes nothing); saved on the worker.
    std::string detail;
    const FoeError e = hooks_.restore_parameters(parameters_, detail);
    parameters_ = {};
    if (e != FoeError::None) {
      refuse(e, detail);
      parameters_result_ = CommitProgress{false, e, 0, 0};
      return parameters_result_;
    }
    restoring_ = true;
    return poll_commit();
  }
  return CommitProgress{false, FoeError::Illegal, 0, 0};
}

CommitProgress FileAccess::poll_commit() {
  if (target_ == Target::Parameters) {
    if (!restoring_) return parameters_result_;
    std::string detail;
    const CommitProgress p = hooks_.poll_restore(detail);
    if (p.busy) return p;
    restoring_ = false;
    if (p.error != FoeError::None) {
      refuse(p.error, detail);
    } else if (hooks_.log) {
      hooks_.log("FoE: " + detail + " (" + std::to_string(received_) + " bytes)");
    }
    parameters_result_ = p;
    return p;
  }
  if (target_ != Target::Firmware) return CommitProgress{false, FoeError::Illegal, 0, 0};
  const FirmwareStore::Status s = store_.poll_commit();
  if (s.busy) {
    // Done / Entire: the commit's two steps (verify, install) are not told apart: 0 of 1.
    return CommitProgress{true, FoeError::None, 0, 1};
  }
  if (!reported_) {
    reported_ = true;
    if (s.error != FoeError::None) {
      refuse(s.error, s.detail);
    } else if (hooks_.log) {
      hooks_.log("FoE: firmware " + s.detail + " (" + std::to_string(received_) +
                 " bytes); it runs after the next power cycle");
    }
  }
  return CommitProgress{false, s.error, 1, 1};
}

void FileAccess::abort_write() {
  if (target_ == Target::Firmware && !store_.poll_commit().busy) store_.abort();
  parameters_ = {};
  // A restore handed over finishes on its own; poll_commit() still reports it.
  if (restoring_) return;
  target_ = Target::None;
}

}  // namespace rackcat::mdp
