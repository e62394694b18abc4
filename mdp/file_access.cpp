// File names, states and passwords of the device's FoE files (file_access.hpp).
#include "mdp/file_access.hpp"

#include <algorithm>
#include <cstdio>

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
    contents = hooks_.running_firmware();
  } else {
    if (state == EsmState::Boot) {
      return {false, refuse(FoeError::NotBootstrap, "parameters are not served in BOOT")};
    }
    contents = hooks_.parameter_file();
  }
  if (contents.size() > max_size)
    return {false, refuse(FoeError::DiskFull, "file larger than FoE allows")};
  return {false, FoeError::None};
}

FoeError FileAccess::begin_write(std::string_view name, uint32_t password) {
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
    std::string detail;
    const FoeError e = hooks_.restore_parameters(parameters_, detail);
    if (e != FoeError::None) refuse(e, detail);
    parameters_.clear();
    parameters_result_ = CommitProgress{false, e, 0, 0};
    return parameters_result_;
  }
  return CommitProgress{false, FoeError::Illegal, 0, 0};
}

CommitProgress FileAccess::poll_commit() {
  if (target_ == Target::Parameters) return parameters_result_;
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
  parameters_.clear();
  target_ = Target::None;
}

}  // namespace rackcat::mdp
