// SDO over CAN, server side (CiA 301 §7.2.4): a thin adapter around the CoE SDO server.
// The 8 bytes of a CANopen SDO frame are byte for byte the SDO command body of a CoE SDO
// request (ETG.1000.6 §5.6.2 reuses the CiA 301 command specifiers, flags and layouts), so
// each request frame (COB-ID 0x600 + node) is wrapped in a CoE header, handed to
// coe::SdoServer, and the 8-byte body of its reply goes back on COB-ID 0x580 + node. The
// reply is sized to exactly one 8-byte body: the CoE server then answers a large
// upload with a "normal" initiate carrying no data and 7-byte segments, which is the CiA 301
// segmented transfer; downloads likewise. Expedited, segmented and abort all come from coe/.
#pragma once

#include <array>
#include <cstdint>

#include "coe/access.hpp"
#include "coe/sdo_server.hpp"
#include "modules/canopen/frame.hpp"

namespace rackcat::modules::canopen {

class CanSdoServer {
 public:
  CanSdoServer(coe::SdoServer& server, uint8_t node_id) : server_(server), node_(node_id) {}

  // True when `request` is an SDO request for this node; `response` is then set when the
  // server answers (an abort from the client gets no answer, CiA 301 §7.2.4.3.17).
  // `state` sets the access rights: PRE-OPERATIONAL -> PreOp, OPERATIONAL -> Op.
  bool handle(const CanFrame& request, EsmState state, CanFrame& response, bool& has_response);
  uint8_t node_id() const { return node_; }

 private:
  coe::SdoServer& server_;
  uint8_t node_;
  std::array<uint8_t, 2 + 8> request_{};  // CoE header + SDO body
  std::array<uint8_t, 2 + 8> reply_{};
};

}  // namespace rackcat::modules::canopen
