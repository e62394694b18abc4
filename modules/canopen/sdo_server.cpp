#include "modules/canopen/sdo_server.hpp"

#include "coe/abort_code.hpp"
#include "coe/bits.hpp"
#include "coe/coe_header.hpp"
#include "coe/sdo_command.hpp"

namespace rackcat::modules::canopen {

namespace {
constexpr size_t kBody = coe::CoeHeader::kSize;
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
  // CoE header "SDO request" and the 8 bytes.
  coe::CoeHeader ch;
  ch.service = static_cast<uint8_t>(coe::CoeService::SdoRequest);
  ch.encode(request_);
  std::copy(request.data.begin(), request.data.end(), request_.begin() + kBody);

  const auto answer = server_.handle(request_, reply_, state);
  if (answer.length == 0 && answer.error == mailbox::Error::None) {
    return true;  // the client aborted: no answer
  }
  if (answer.error != mailbox::Error::None || answer.length < kBody + 8) {
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
