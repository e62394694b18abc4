#include "mdp/parameter_writer.hpp"

#include <openssl/evp.h>
#include <zlib.h>

#include <algorithm>

#include "mdp/command_bytes.hpp"

#include "base/event_log.hpp"

namespace rackcat::mdp {
namespace {

std::vector<uint8_t> digest(uint8_t algorithm, const std::vector<uint8_t>& data) {
  if (algorithm == cmd::kChecksumCrc32) {
    const auto crc = static_cast<uint32_t>(
        ::crc32(::crc32(0L, Z_NULL, 0), data.data(), static_cast<uInt>(data.size())));
    return {static_cast<uint8_t>(crc), static_cast<uint8_t>(crc >> 8),
            static_cast<uint8_t>(crc >> 16), static_cast<uint8_t>(crc >> 24)};
  }
  const EVP_MD* md = algorithm == cmd::kChecksumSha1 ? EVP_sha1() : EVP_md5();
  unsigned char out[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  // A digest libcrypto refuses (MD5 and SHA-1 are absent from a FIPS-only configuration):
  // no checksum, and the command reports failure instead of an arbitrary value.
  if (md == nullptr || EVP_Digest(data.data(), data.size(), out, &len, md, nullptr) != 1) return {};
  return std::vector<uint8_t>(out, out + len);
}

size_t slot_of(ParameterWriter::Job job) {
  return static_cast<size_t>(job);
}

}  // namespace

ParameterWriter::ParameterWriter(const ParameterStore& store, BackgroundWorker& worker)
    : store_(store), worker_(worker) {}

ParameterWriter::~ParameterWriter() {
  wait_idle();
  worker_.forget(*this);
}

void ParameterWriter::submit(Job job, Request request) {
  {
    std::lock_guard lock(mutex_);
    Slot& s = slots_[slot_of(job)];
    s.request = std::move(request);
    if (s.result) results_.fetch_sub(1, std::memory_order_acq_rel);
    s.result.reset();
    if (!s.queued) {
      s.queued = true;
      order_.push_back(job);
    }
  }
  worker_.schedule(*this);
}

void ParameterWriter::submit_store(uint32_t fingerprint, std::vector<uint8_t> payload) {
  Request r;
  r.fingerprint = fingerprint;
  r.payload = std::move(payload);
  submit(Job::Store, std::move(r));
}

void ParameterWriter::submit_checksum(uint32_t fingerprint, uint8_t algorithm,
                                      std::vector<uint8_t> defaults) {
  Request r;
  r.fingerprint = fingerprint;
  r.payload = std::move(defaults);
  r.algorithm = algorithm;
  submit(Job::Checksum, std::move(r));
}

void ParameterWriter::submit_load(uint32_t fingerprint) {
  Request r;
  r.fingerprint = fingerprint;
  submit(Job::Load, std::move(r));
}

void ParameterWriter::submit_read_file(uint32_t fingerprint) {
  Request r;
  r.fingerprint = fingerprint;
  submit(Job::ReadFile, std::move(r));
}

void ParameterWriter::submit_restore(uint32_t fingerprint, std::vector<uint8_t> payload) {
  Request r;
  r.fingerprint = fingerprint;
  r.payload = std::move(payload);
  submit(Job::Restore, std::move(r));
}

void ParameterWriter::submit_reset(uint32_t fingerprint, bool factory, std::function<void()> also) {
  Request r;
  r.fingerprint = fingerprint;
  r.factory = factory;
  r.also = std::move(also);
  submit(Job::Reset, std::move(r));
}

std::optional<ParameterWriter::Result> ParameterWriter::take(Job job) {
  std::lock_guard lock(mutex_);
  Slot& s = slots_[slot_of(job)];
  if (s.queued || s.running || !s.result) return std::nullopt;
  std::optional<Result> r = std::move(s.result);
  s.result.reset();
  results_.fetch_sub(1, std::memory_order_acq_rel);
  return r;
}

bool ParameterWriter::busy(Job job) const {
  std::lock_guard lock(mutex_);
  const Slot& s = slots_[slot_of(job)];
  return s.queued || s.running;
}

void ParameterWriter::wait_idle() {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [this] {
    return order_.empty() &&
           std::none_of(slots_.begin(), slots_.end(), [](const Slot& s) { return s.running; });
  });
}

ParameterWriter::Result ParameterWriter::execute(Job job, const Request& r) const {
  Result out;
  switch (job) {
    case Job::Store:
    case Job::Restore:
      out.ok = store_.save(r.fingerprint, r.payload, out.report, &out.error_number);
      break;
    case Job::ReadFile: {
      out.stored =
          store_.load(r.fingerprint, out.bytes, out.report) == ParameterStore::LoadResult::Loaded;
      out.ok = true;
      break;
    }
    case Job::Checksum: {
      std::vector<uint8_t> payload;
      std::string detail;
      const bool stored =
          store_.load(r.fingerprint, payload, detail) == ParameterStore::LoadResult::Loaded;
      out.bytes = digest(r.algorithm, stored ? payload : r.payload);
      out.ok = !out.bytes.empty();
      if (!out.ok) out.report = "checksum algorithm not available from libcrypto";
      break;
    }
    case Job::Reset:
      if (r.also) r.also();
      if (r.factory && !store_.remove(out.report)) break;
      [[fallthrough]];
    case Job::Load: {
      const auto loaded = store_.load(r.fingerprint, out.bytes, out.report);
      out.stored = loaded == ParameterStore::LoadResult::Loaded;
      // Load: a damaged or foreign file is an error; nothing stored means the shipped defaults.
      // Reset: always succeeds once the file is deleted (factory); a bad file means defaults.
      out.ok = out.stored || loaded == ParameterStore::LoadResult::Missing || job == Job::Reset;
      break;
    }
  }
  return out;
}

bool ParameterWriter::run_one() {
  std::unique_lock lock(mutex_);
  if (order_.empty()) return false;
  const Job job = order_.front();
  order_.pop_front();
  Slot& s = slots_[slot_of(job)];
  const Request request = std::move(s.request);
  s.queued = false;
  s.running = true;
  lock.unlock();
  Result result = execute(job, request);
  // 0xFBF2 store, 0xFBF0 factory reset, FoE restore
  if (job == Job::Store || job == Job::Reset || job == Job::Restore) {
    base::Event e{.kind = base::EventKind::Store, .code = result.ok ? uint16_t{0} : uint16_t{1}};
    e.set_text(job == Job::Store     ? "store parameters"
               : job == Job::Restore ? "FoE parameter restore"
                                     : "reset stored parameters");
    base::log_event(e);
  }
  lock.lock();
  s.running = false;
  result.sequence = ++finished_;
  // A newer request of the same kind queued meanwhile supersedes this result.
  if (!s.queued) {
    if (!s.result) results_.fetch_add(1, std::memory_order_acq_rel);
    s.result = std::move(result);
    if (result_flag_ != nullptr) {
      // The result is published before the flag rises (the owner clears the flag, fences,
      // then looks at has_results(): one of the two sees the other).
      std::atomic_thread_fence(std::memory_order_seq_cst);
      result_flag_->store(true, std::memory_order_seq_cst);
    }
  }
  cv_.notify_all();
  return !order_.empty();
}

}  // namespace rackcat::mdp
