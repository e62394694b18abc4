#include "modules/canopen/sdo_server.hpp"

#include "coe/abort_code.hpp"
#include "coe/bits.hpp"
#include "coe/coe_header.hpp"
#include "coe/mailbox_header.hpp"
#include "coe/sdo_command.hpp"

namespace rackcat::modules::canopen {

namespace {
constexpr size_t kBody = coe::MailboxHeader::kSize + coe::CoeHeader::kSize;
}

bool CanSdoServer::handle(const CanFrame& request, EsmState state, CanFrame& response,
                          bool& has_response) {
  has_response = false;
  if (request.id != cob::kSdoRx + node_) {
    return false;
  }
  response = CanFrame{};
  response.id = cob::kSdoTx + node_;
  response.len = 8;
  if (request.len != 8) {
    // CiA 301 §7.2.4.3: SDO frames always carry 8 bytes. Anything else is no valid command.
    const uint8_t abort[8] = {coe::sdo::kAbortCommand, 0, 0, 0, 0, 0, 0, 0};
    response = CanFrame::make(cob::kSdoTx + node_, abort);
    le::put32(response.data.data() + 4, static_cast<uint32_t>(coe::AbortCode::CommandSpecifier));
    has_response = true;
    return true;
  }
  // Mailbox header (counter 0: CAN has no repeat service) + CoE header "SDO request".
  coe::MailboxHeader mh;
  mh.length = static_cast<uint16_t>(coe::CoeHeader::kSize + 8);
  mh.type = static_cast<uint8_t>(coe::MailboxType::CoE);
  mh.encode(request_);
  coe::CoeHeader ch;
  ch.service = static_cast<uint8_t>(coe::CoeService::SdoRequest);
  ch.encode(std::span(request_).subspan(coe::MailboxHeader::kSize));
  std::copy(request.data.begin(), request.data.end(), request_.begin() + kBody);

  const size_t n = server_.handle(request_, reply_, state);
  if (n == 0) {
    return true;  // the client aborted: no answer
  }
  const auto reply_header = coe::MailboxHeader::decode(reply_);
  if (n < kBody + 8 || !reply_header || reply_header->mailbox_type() != coe::MailboxType::CoE) {
    // A mailbox-level error has no CAN equivalent: abort the addressed object.
    std::array<uint8_t, 8> abort{coe::sdo::kAbortCommand, request.data[1], request.data[2],
                                 request.data[3]};
    le::put32(abort.data() + 4, static_cast<uint32_t>(coe::AbortCode::GeneralError));
    response = CanFrame::make(cob::kSdoTx + node_, abort);
  } else {
    std::copy_n(reply_.begin() + kBody, 8, response.data.begin());
  }
  has_response = true;
  return true;
}

}  // namespace rackcat::modules::canopen
