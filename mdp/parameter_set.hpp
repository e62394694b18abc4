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
  size_t count() const { return count_; }
  std::vector<uint8_t> capture() const;
  // False (and nothing changed) when the payload does not have this set's size.
  bool apply(std::span<const uint8_t> payload) const;
  // The checks an SDO write of the same values must pass (value range, enumerations, the
  // objects' own validate_write hooks, as a complete access in PREOP), so that a stored file
  // can never give the device a value the master could not have written. Empty when the
  // payload passes; else one line naming the first refused entry and its SDO abort code.
  std::string check(std::span<const uint8_t> payload) const;

 private:
  // One stored parameter: an entry and its bytes in the payload.
  struct Ref {
    coe::Object* object;
    uint8_t subindex;
    uint16_t bytes;
    bool raw;  // byte-aligned whole bytes: copied as is; else an integer via get_u/set_u
  };
  // Consecutive parameters of one object with consecutive subindices and the same size and
  // kind, kept as one run (0xF030's 255 module entries are one run): the set's memory grows
  // with the objects it stores, not with their entries.
  struct Run {
    coe::Object* object;
    uint8_t first;
    uint8_t last;
    uint16_t bytes;
    bool raw;
  };
  // Calls f(const Ref&) for every parameter in payload order.
  template <class F>
  void for_each_ref(F&& f) const {
    for (const Run& run : runs_) {
      for (unsigned sub = run.first; sub <= run.last; ++sub) {
        f(Ref{run.object, static_cast<uint8_t>(sub), run.bytes, run.raw});
      }
    }
  }
  void push(const Ref& ref);

  const coe::ObjectDictionary* od_;
  std::vector<Run> runs_;
  size_t count_ = 0;
  uint32_t fingerprint_ = 0;
  size_t payload_bytes_ = 0;
};

}  // namespace rackcat::mdp
