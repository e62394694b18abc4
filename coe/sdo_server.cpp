// CoE framing (the CoE header), request dispatch and the unsolicited message queue of the SDO
// server (ETG.1000.6 §5.6.1); the mailbox header around it is the MailboxServer's.
#include "coe/sdo_server.hpp"

#include <algorithm>
#include <cstring>

#include "coe/bits.hpp"
#include "coe/coe_header.hpp"
#include "coe/sdo_command.hpp"

namespace rackcat::coe {
namespace {
// CoE header + the 8-byte SDO body of an abort: the smallest reply the server must always be
// able to send.
constexpr size_t kMinReply = CoeHeader::kSize + 8;
constexpr size_t kMinTransferBuffer = 256;
}  // namespace

SdoServer::SdoServer(ObjectDictionary& od) : od_(od) {
  prepare();
}

void SdoServer::prepare() {
  const size_t n = std::max(od_.max_image_bytes(), kMinTransferBuffer);
  capacity_ = n;
  // An entry description holds three values of the entry (default, min, max) plus name.
  const size_t info = 3 * n + 512;
  const size_t big = n > kStackScratch ? n : 0;
  data_ = {};
  info_buf_ = {};
  scratch_ = {};
  value_ = {};
  buffers_ = LazyBuffer(n + info + 2 * big);
  const std::span<uint8_t> all = buffers_.span();
  data_ = all.first(n);
  info_buf_ = all.subspan(n, info);
  scratch_ = all.subspan(n + info, big);
  value_ = all.subspan(n + info + big, big);
}

void SdoServer::reset() {
  transfer_ = {};
  info_ = {};
}

bool SdoServer::queue_emergency(uint16_t error_code, uint8_t error_register,
                                std::array<uint8_t, 5> data) {
  return emergencies_.push(Emergency{error_code, error_register, data});
}

size_t SdoServer::finish_coe(std::span<uint8_t> reply, size_t body_length, uint8_t service) {
  CoeHeader{0, service}.encode(reply);
  return CoeHeader::kSize + body_length;
}

size_t SdoServer::mailbox_error(mailbox::Error error) {
  error_ = error;
  return 0;
}

size_t SdoServer::abort(std::span<uint8_t> reply, uint16_t index, uint8_t subindex,
                        AbortCode code) {
  // ETG.1000.6 §5.6.2.7.1: an abort travels as an SDO *request* (service 2), command byte
  // exactly 0x80, index, subindex, 32-bit abort code: 10 bytes with the CoE header.
  transfer_ = {};
  uint8_t* b = reply.data() + CoeHeader::kSize;
  b[0] = sdo::kAbortCommand;
  le::put16(b + 1, index);
  b[3] = subindex;
  le::put32(b + 4, static_cast<uint32_t>(code));
  return finish_coe(reply, 8, static_cast<uint8_t>(CoeService::SdoRequest));
}

mailbox::Answer SdoServer::handle(std::span<const uint8_t> request, std::span<uint8_t> reply,
                                  EsmState state) {
  if (reply.size() < kMinReply) return {0, mailbox::Error::NoMoreMemory};
  // A new request ends any SDO Information fragments still queued for an earlier one.
  info_ = {};
  error_ = mailbox::Error::None;
  const size_t n = dispatch(request, reply, state);
  return {error_ == mailbox::Error::None ? n : 0, error_};
}

size_t SdoServer::dispatch(std::span<const uint8_t> data, std::span<uint8_t> reply,
                           EsmState state) {
  const auto coe = CoeHeader::decode(data);
  if (!coe) return mailbox_error(mailbox::Error::SizeTooShort);
  const auto body = data.subspan(CoeHeader::kSize);
  switch (static_cast<CoeService>(coe->service)) {
    case CoeService::SdoRequest:
      // Every SDO request is at least 8 bytes after the CoE header (mailbox length >= 10).
      if (body.size() < sdo::kInitiateBody) return mailbox_error(mailbox::Error::SizeTooShort);
      return sdo_request(body, reply, state);
    case CoeService::SdoInformation:
      if (body.size() < 4) return mailbox_error(mailbox::Error::SizeTooShort);
      return sdo_info(body, reply);
    default:
      return mailbox_error(mailbox::Error::ServiceNotSupported);
  }
}

size_t SdoServer::sdo_request(std::span<const uint8_t> body, std::span<uint8_t> reply,
                              EsmState state) {
  switch (sdo::specifier(body[0])) {
    case sdo::kCcsDownloadInitiate:
      return download_initiate(body, reply, state);
    case sdo::kCcsDownloadSegment:
      return download_segment(body, reply, state);
    case sdo::kCcsUploadInitiate:
      return upload_initiate(body, reply, state);
    case sdo::kCcsUploadSegment:
      return upload_segment(body, reply);
    case sdo::kCcsAbort:
      // The master gave up the transfer (ETG.1000.6 §5.6.2.7): no reply.
      transfer_ = {};
      return 0;
    default:
      // Block transfers (5, 6) and 7 do not exist in CoE.
      return abort(reply, le::get16(&body[1]), body[3], AbortCode::CommandSpecifier);
  }
}

SdoServer::InitiateRequest SdoServer::begin_initiate(std::span<const uint8_t> body) {
  transfer_ = {};
  const uint8_t cmd = body[0];
  const uint16_t index = le::get16(&body[1]);
  return {cmd, index, body[3], (cmd & sdo::kCompleteAccess) != 0, od_.find(index)};
}

AbortCode SdoServer::missing_object() const {
  return od_.size() ? AbortCode::ObjectNotFound : AbortCode::NoDictionary;
}

size_t SdoServer::poll(std::span<uint8_t> reply) {
  if (reply.size() < kMinReply) {
    return 0;
  }
  Emergency e;
  if (emergencies_.pop(e)) {
    // ETG.1000.6 §5.6.4: error code, error register, 5 data bytes after the CoE header.
    uint8_t* b = reply.data() + CoeHeader::kSize;
    le::put16(b, e.error_code);
    b[2] = e.error_register;
    std::copy(e.data.begin(), e.data.end(), b + 3);
    return finish_coe(reply, 8, static_cast<uint8_t>(CoeService::Emergency));
  }
  if (info_.kind != InfoKind::None) {
    return info_fragment(reply);
  }
  return 0;
}

}  // namespace rackcat::coe
