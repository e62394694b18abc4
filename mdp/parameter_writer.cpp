#include "mdp/parameter_writer.hpp"

namespace rackcat::mdp {

ParameterWriter::ParameterWriter(const ParameterStore& store)
    : store_(store), thread_([this] { run(); }) {}

ParameterWriter::~ParameterWriter() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void ParameterWriter::submit(uint32_t fingerprint, std::vector<uint8_t> payload) {
  {
    std::lock_guard lock(mutex_);
    fingerprint_ = fingerprint;
    payload_ = std::move(payload);
    has_job_ = true;
  }
  cv_.notify_all();
}

bool ParameterWriter::busy() const {
  std::lock_guard lock(mutex_);
  return has_job_ || writing_;
}

std::optional<std::string> ParameterWriter::last_error() const {
  std::lock_guard lock(mutex_);
  return error_;
}

void ParameterWriter::wait_idle() {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [this] { return !has_job_ && !writing_; });
}

void ParameterWriter::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    cv_.wait(lock, [this] { return stop_ || has_job_; });
    if (!has_job_) return;  // stop requested and nothing pending
    const uint32_t fingerprint = fingerprint_;
    const std::vector<uint8_t> payload = std::move(payload_);
    has_job_ = false;
    writing_ = true;
    lock.unlock();
    std::string error;
    const bool ok = store_.save(fingerprint, payload, error);
    lock.lock();
    writing_ = false;
    error_ = ok ? std::nullopt : std::optional<std::string>(error);
    cv_.notify_all();
  }
}

}  // namespace rackcat::mdp
