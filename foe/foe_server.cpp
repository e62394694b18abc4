// FoE request handling (ETG.1000.6 §5.8): read and write sequences, packet numbers, the
// last-packet rule, busy while committing, errors with their standard texts, timeouts.
#include "foe/foe_server.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace rackcat::foe {
namespace {

uint64_t steady_ms() {
  return static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                   std::chrono::steady_clock::now().time_since_epoch())
                                   .count());
}

}  // namespace

FoeServer::FoeServer(FileBackend& backend, FoeLimits limits, Clock clock)
    : backend_(backend), limits_(limits), clock_(clock ? std::move(clock) : Clock(steady_ms)) {}

mailbox::Answer FoeServer::handle_mailbox(std::span<const uint8_t> request, size_t request_capacity,
                                          std::span<uint8_t> reply) {
  if (reply.size() < FoeHeader::kSize) return {0, mailbox::Error::NoMoreMemory};
  const Result r = handle(request, request_capacity, reply);
  if (r.too_short) return {0, mailbox::Error::SizeTooShort};
  return {r.length, mailbox::Error::None};
}

FoeServer::Result FoeServer::handle(std::span<const uint8_t> request, size_t request_capacity,
                                    std::span<uint8_t> reply) {
  // A transfer idle past its timeout is gone before this request is looked at.
  if ((phase_ == Phase::Opening || phase_ == Phase::Reading || phase_ == Phase::Writing) &&
      clock_() - last_activity_ > limits_.transfer_timeout_ms) {
    end_transfer();
  }
  const auto hdr = FoeHeader::decode(request);
  if (!hdr) return {0, true};
  // The reply must hold at least a header; a send mailbox smaller than that cannot answer.
  if (reply.size() < FoeHeader::kSize) return {};
  last_activity_ = clock_();
  const auto body = request.subspan(FoeHeader::kSize);
  // The most file data one request can carry: the receive mailbox minus the FoE header.
  const size_t max_data =
      request_capacity > FoeHeader::kSize ? request_capacity - FoeHeader::kSize : 0;
  switch (static_cast<OpCode>(hdr->opcode)) {
    case OpCode::ReadRequest:
      return {read_request(body, hdr->value, reply)};
    case OpCode::WriteRequest:
      return {write_request(body, hdr->value, reply)};
    case OpCode::Data:
      return {data(hdr->value, body, max_data, reply)};
    case OpCode::Ack:
      return {ack(hdr->value, reply)};
    case OpCode::Error:
      // The master gives up (ETG.1000.6 §5.8: an Error request is not answered).
      if (phase_ != Phase::Committing) end_transfer();
      return {};
    case OpCode::Busy:
      break;
  }
  if (phase_ != Phase::Committing) end_transfer();
  return {error(FoeError::Illegal, reply)};
}

void FoeServer::tick() {
  if (phase_ == Phase::Committing) {
    const CommitProgress p = backend_.poll_commit();
    // A finished commit whose master went away still ends here; the master that comes back
    // with its repeated last Data then finds no transfer.
    if (!p.busy && clock_() - last_activity_ > limits_.transfer_timeout_ms) phase_ = Phase::Idle;
    return;
  }
  if (phase_ != Phase::Idle && clock_() - last_activity_ > limits_.transfer_timeout_ms) {
    end_transfer();
  }
}

size_t FoeServer::poll(std::span<uint8_t> reply) {
  tick();
  if (phase_ != Phase::Opening || reply.size() < FoeHeader::kSize) return 0;
  const ReadProgress p = backend_.poll_read(file_);
  if (p.busy) return 0;
  // The deferred reply of the read request: its first Data or the refusal.
  return opened(p.error, reply);
}

void FoeServer::reset() {
  // A running commit is not waited for (that would hold the device thread): it completes on
  // its own, and a request meanwhile finds it busy (write_request, read_request).
  if (phase_ == Phase::Committing) {
    if (!backend_.poll_commit().busy) phase_ = Phase::Idle;
    return;
  }
  end_transfer();
}

void FoeServer::end_transfer() {
  if (phase_ == Phase::Writing) backend_.abort_write();
  if (phase_ == Phase::Opening) backend_.abort_read();
  phase_ = Phase::Idle;
  file_.clear();
  file_.shrink_to_fit();
  packet_ = 0;
  offset_ = 0;
  received_ = 0;
}

bool FoeServer::name_of(std::span<const uint8_t> raw, std::string& name) const {
  // Some masters send the name NUL-terminated: the name ends at the first NUL.
  const auto nul = std::find(raw.begin(), raw.end(), uint8_t{0});
  const size_t len = static_cast<size_t>(nul - raw.begin());
  if (len > limits_.max_name_length) return false;
  name.assign(raw.begin(), raw.begin() + static_cast<std::ptrdiff_t>(len));
  return true;
}

size_t FoeServer::read_request(std::span<const uint8_t> raw, uint32_t password,
                               std::span<uint8_t> reply) {
  if (phase_ == Phase::Committing) {
    if (backend_.poll_commit().busy) return error(FoeError::AccessDenied, reply);
    phase_ = Phase::Idle;
  }
  end_transfer();  // a new request ends a stale one
  if (!name_of(raw, name_)) return error(FoeError::Illegal, reply);
  if (name_.empty()) return error(FoeError::NotFound, reply);
  phase_ = Phase::Opening;
  const ReadProgress p = backend_.read_file(name_, password, limits_.max_file_size, file_);
  if (p.busy) return 0;  // the reply follows from poll()
  return opened(p.error, reply);
}

size_t FoeServer::opened(FoeError e, std::span<uint8_t> reply) {
  if (e == FoeError::None && file_.size() > limits_.max_file_size) e = FoeError::DiskFull;
  if (e != FoeError::None) {
    phase_ = Phase::Idle;
    file_.clear();
    return error(e, reply);
  }
  phase_ = Phase::Reading;
  packet_ = 0;
  offset_ = 0;
  last_sent_ = 0;
  return send_data(reply);
}

size_t FoeServer::send_data(std::span<uint8_t> reply) {
  offset_ += last_sent_;
  last_max_ = reply.size() - FoeHeader::kSize;
  last_sent_ = std::min(last_max_, file_.size() - offset_);
  ++packet_;
  // An empty file (the last packet of an exact multiple, or a 0-byte file) has no data().
  if (last_sent_ > 0)
    std::memcpy(reply.data() + FoeHeader::kSize, file_.data() + offset_, last_sent_);
  return simple(OpCode::Data, packet_, reply) + last_sent_;
}

size_t FoeServer::ack(uint32_t packet, std::span<uint8_t> reply) {
  if (phase_ != Phase::Reading) {
    if (phase_ == Phase::Writing || phase_ == Phase::Opening) end_transfer();
    return error(FoeError::Illegal, reply);
  }
  if (packet != packet_) {
    end_transfer();
    return error(FoeError::PacketNumberWrong, reply);
  }
  // The acknowledged packet was shorter than a full one: it was the last (ETG.1000.6 §5.8).
  if (last_sent_ < last_max_) {
    end_transfer();
    return 0;
  }
  return send_data(reply);
}

size_t FoeServer::write_request(std::span<const uint8_t> raw, uint32_t password,
                                std::span<uint8_t> reply) {
  if (phase_ == Phase::Committing) {
    if (backend_.poll_commit().busy) return error(FoeError::AccessDenied, reply);
    phase_ = Phase::Idle;
  }
  end_transfer();
  if (!name_of(raw, name_)) return error(FoeError::Illegal, reply);
  if (name_.empty()) return error(FoeError::NotFound, reply);
  const FoeError e = backend_.begin_write(name_, password);
  if (e != FoeError::None) return error(e, reply);
  phase_ = Phase::Writing;
  packet_ = 0;
  received_ = 0;
  return simple(OpCode::Ack, 0, reply);
}

size_t FoeServer::data(uint32_t packet, std::span<const uint8_t> bytes, size_t max_data,
                       std::span<uint8_t> reply) {
  if (phase_ == Phase::Committing) {
    // The master repeats the last Data after each Busy (ETG.1000.6 §5.8 "Busy").
    if (packet != packet_) return error(FoeError::PacketNumberWrong, reply);
    const CommitProgress p = backend_.poll_commit();
    return progress_reply(p, reply);
  }
  if (phase_ != Phase::Writing) {
    end_transfer();
    return error(FoeError::Illegal, reply);
  }
  if (packet == packet_ && packet_ != 0) {
    // A resend of the packet just acknowledged (the master missed the Ack): acknowledge again.
    return simple(OpCode::Ack, packet_, reply);
  }
  if (packet != packet_ + 1) {
    end_transfer();
    return error(FoeError::PacketNumberWrong, reply);
  }
  if (bytes.size() > max_data) {
    end_transfer();
    return error(FoeError::Illegal, reply);
  }
  if (received_ + bytes.size() > limits_.max_file_size) {
    end_transfer();
    return error(FoeError::DiskFull, reply);
  }
  if (!bytes.empty()) {
    const FoeError e = backend_.write_data(bytes);
    if (e != FoeError::None) {
      end_transfer();
      return error(e, reply);
    }
  }
  received_ += bytes.size();
  packet_ = packet;
  if (bytes.size() == max_data) return simple(OpCode::Ack, packet_, reply);
  // Shorter than the mailbox allows: the last packet. Verify and commit.
  phase_ = Phase::Committing;
  return progress_reply(backend_.commit(), reply);
}

size_t FoeServer::progress_reply(const CommitProgress& p, std::span<uint8_t> reply) {
  if (p.busy) {
    return simple(OpCode::Busy,
                  static_cast<uint32_t>(p.done) | (static_cast<uint32_t>(p.entire) << 16), reply);
  }
  phase_ = Phase::Idle;
  const uint32_t packet = packet_;
  packet_ = 0;
  received_ = 0;
  if (p.error != FoeError::None) return error(p.error, reply);
  return simple(OpCode::Ack, packet, reply);
}

size_t FoeServer::simple(OpCode op, uint32_t value, std::span<uint8_t> reply) {
  FoeHeader{static_cast<uint8_t>(op), value}.encode(reply);
  return FoeHeader::kSize;
}

size_t FoeServer::error(FoeError code, std::span<uint8_t> reply) {
  // Error request: code, then the error text (ETG.1000.6 §5.8 "Error request"), cut to fit.
  const std::string_view text = describe(code);
  const size_t n = std::min(text.size(), reply.size() - FoeHeader::kSize);
  std::memcpy(reply.data() + FoeHeader::kSize, text.data(), n);
  return simple(OpCode::Error, static_cast<uint32_t>(code), reply) + n;
}

}  // namespace rackcat::foe
