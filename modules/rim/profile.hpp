// How a RIM's slot cards appear as a CANopen I/O node after CiA 401 (docs/CAN.md):
//   0x6000 Read input 8-bit      digital inputs, each card from a byte boundary, bit n = ch n
//   0x6200 Write output 8-bit    digital outputs (relays, sourcing/sinking/opto, E84 outputs)
//   0x6401 Read analog input 16  analog inputs (±10 V code of analog_scale.hpp) and
//                                temperatures (thermocouple, RTD: INTEGER16 in 0.1 °C)
//   0x6411 Write analog output 16  analog outputs (±10 V code)
// plus identity 0x1018, device name 0x1008 (the RIM's part number), software version 0x100A,
// heartbeat time 0x1017 and the slot card list 0x2001 (OCTET_STRING, 4 bytes per occupied
// slot: UNSIGNED16 slot number, UNSIGNED16 card ID of the guide's Table 3).
//
// Process data: the transmit stream is [0x6000 bytes][pad to even][0x6401 words], the receive
// stream [0x6200 bytes][pad to even][0x6411 words]; PDO k carries bytes 8k..8k+7 of its
// stream, so a 16-bit value never straddles two PDOs. PDOs 1..4 use the pre-defined
// connection set (TPDO 0x180/0x280/0x380/0x480 + node-ID, RPDO 0x200..0x500 + node-ID); PDO
// k >= 5 uses the same function code as PDO ((k-1) mod 4)+1 with node-ID + 8 * ((k-1) / 4)
// (the IDs of node-IDs above 8, which a rack of five RIMs never uses). The 0x1800/0x1A00 and
// 0x1400/0x1600 objects in the dictionary say exactly this, so a third-party CiA 401 node
// configured the same way can stand in for a RIM. UART cards carry no process data on CAN.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::modules::canopen {

enum class ChannelKind : uint8_t { DigitalIn, DigitalOut, AnalogIn, AnalogOut, Temperature };

struct RimChannel {
  uint8_t slot = 0;
  uint8_t channel = 0;  // 0-based channel of the card
  ChannelKind kind = ChannelKind::DigitalIn;
  uint16_t offset = 0;  // byte offset in the transmit (inputs) or receive (outputs) stream
  uint8_t bit = 0;      // digital channels: bit in that byte
  double min_v = -10.0, max_v = 10.0;  // analog channels: the card's range
};

// Identity a RIM reports in 0x1018 and the control module expects (derived from the rack
// file, so both sides compute the same values).
struct RimIdentity {
  uint32_t vendor_id = 0;
  uint32_t product_code = 0;
  uint32_t revision = 0;
  uint32_t serial = 0;
};

inline constexpr size_t kPdoBytes = 8;
// The control module's own node-ID: it produces a heartbeat the RIMs consume (0x1016), so a
// RIM that loses its control module de-energises its outputs. 0x7F is above every RIM's
// node-ID and its heartbeat COB-ID (0x77F) is no PDO's.
inline constexpr uint8_t kControlModuleNode = 0x7F;
inline constexpr uint16_t kCardListIndex = 0x2001;

struct RimProfile {
  uint8_t rim = 0;  // = node-ID
  RimIdentity identity;
  std::string device_name;          // 0x1008
  std::string software_version;     // 0x100A
  std::vector<RimChannel> inputs;   // transmit stream, slot/channel order
  std::vector<RimChannel> outputs;  // receive stream
  size_t di_bytes = 0, do_bytes = 0, ai_words = 0, ao_words = 0;
  size_t tx_bytes = 0, rx_bytes = 0;  // stream lengths
  std::vector<uint8_t> card_list;     // the value of 0x2001

  size_t tpdo_count() const { return (tx_bytes + kPdoBytes - 1) / kPdoBytes; }
  size_t rpdo_count() const { return (rx_bytes + kPdoBytes - 1) / kPdoBytes; }
  const RimChannel* input(uint8_t slot, uint8_t channel) const;
  const RimChannel* output(uint8_t slot, uint8_t channel) const;
};

// The profile of RIM `rim` of a rack file; throws std::invalid_argument when the rack has no
// such RIM or its cards need more PDOs than the COB-ID scheme has for its node-ID (node-ID
// <= 7; node-ID 1 carries up to 64 PDOs per direction = 512 bytes).
RimProfile rim_profile(const mdp::RackConfig& rack, uint8_t rim);

// COB-ID of TPDO (transmit = true) or RPDO number k (0-based) of a node.
uint32_t pdo_cob_id(bool transmit, size_t k, uint8_t node);
// The PDO number (0-based) a COB-ID is for this node, or -1.
int pdo_number(bool transmit, uint32_t cob_id, uint8_t node);

// Physical value <-> the 16-bit (or 1-bit) process-data value of a channel.
uint16_t encode_channel(const RimChannel& c, double value);
double decode_channel(const RimChannel& c, uint16_t raw);
// Stream access (little-endian words, bits in bytes).
void put_channel(std::span<uint8_t> stream, const RimChannel& c, double value);
double get_channel(std::span<const uint8_t> stream, const RimChannel& c);

// The RIM's object dictionary (CiA 301 communication area + CiA 401 I/O objects).
// `consumer_ms` is 0x1016:01's time for the control module's heartbeat (0 = not watched).
coe::ObjectDictionary rim_dictionary(const RimProfile& profile, uint16_t heartbeat_ms,
                                     uint16_t consumer_ms = 0);
// Copies a stream into the I/O objects (0x6000+0x6401 for transmit, 0x6200+0x6411 for
// receive) so SDO reads see the same values as the PDOs.
void stream_to_objects(coe::ObjectDictionary& od, const RimProfile& p, bool transmit,
                       std::span<const uint8_t> stream);

}  // namespace rackcat::modules::canopen
