// The writable non-volatile parameters 0xFBF2 stores (ETG.5003.1 "backup" parameters): IPv4
// address 0x2000:04, event masks 0x2000:09 and 0x2rr1:07, Detect Modules Override 0x2000:0B,
// the safe-state settings 0x4nnX, the UART configuration 0x5nn5, the exception masks 0xF3Ax and
// the configured module list 0xF030, the encoder settings 0x8nn0 and offset 0x8nn1:01. Captured
// into / applied from a flat byte payload whose layout the fingerprint names (see
// parameter_store.hpp).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::mdp {

class ParameterSet {
 public:
  ParameterSet(coe::ObjectDictionary& od, const RackConfig& config);

  // CRC-32 over (index, subindex, data type, bit length) of every parameter, in order.
  uint32_t fingerprint() const { return fingerprint_; }
  size_t payload_bytes() const { return payload_bytes_; }
  size_t count() const { return refs_.size(); }
  std::vector<uint8_t> capture() const;
  // False (and nothing changed) when the payload does not have this set's size.
  bool apply(std::span<const uint8_t> payload) const;
  // The checks an SDO write of the same values must pass (value range, enumerations, the
  // objects' own validate_write hooks, as a complete access in PREOP), so that a stored file
  // can never give the device a value the master could not have written. Empty when the
  // payload passes; else one line naming the first refused entry and its SDO abort code.
  std::string check(std::span<const uint8_t> payload) const;

 private:
  struct Ref {
    coe::Object* object;
    uint8_t subindex;
    uint16_t bytes;
    bool raw;  // byte-aligned whole bytes: copied as is; else an integer via get_u/set_u
  };
  const coe::ObjectDictionary* od_;
  std::vector<Ref> refs_;
  uint32_t fingerprint_ = 0;
  size_t payload_bytes_ = 0;
};

}  // namespace rackcat::mdp
