// The process image: the PDO assignment (0x1C12 -> outputs/SM2, 0x1C13 -> inputs/SM3) and the
// mapping objects compiled into a flat list of bit copies between the process-data buffer and
// the mapped entries' object images (ETG.1000.6 §5.6.7.4.7 - §5.6.7.4.9). The cyclic path is
// one loop over that list: no lookup, no allocation.
//
// compile() on start-up and whenever the assignment may have changed (the ESM's PREOP->SAFEOP
// request, where a refusal maps to AL status 0x001D/0x001E). The compiled list points into the
// objects' images: compile again after adding or removing objects.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "coe/abort_code.hpp"
#include "coe/object_dictionary.hpp"
#include "coe/pdo_mapping.hpp"

namespace rackcat::coe {

class ProcessImage {
 public:
  struct Copy {
    uint8_t* image;      // the mapped object's image
    uint32_t image_bit;  // entry bit offset inside it
    uint32_t pd_bit;     // bit offset in the process-data buffer
    uint32_t bits;
  };

  explicit ProcessImage(ObjectDictionary& od) : od_(od) {}

  // Rebuilds both directions. On an invalid configuration returns its abort code (the same
  // code the validators give) and keeps the previous compilation.
  // `failed` (optional) names the direction whose configuration is invalid.
  AbortCode compile(PdoDirection* failed = nullptr);

  // SM2 (outputs) -> mapped objects, then after_write(obj, ObjectHooks::kProcessData) on every
  // mapped object with that hook. A shorter buffer copies the entries that fit.
  void write_outputs(std::span<const uint8_t> sm2);
  // before_read(obj, ObjectHooks::kProcessData) on every mapped object with that hook, then
  // objects -> SM3 (inputs); padding and unmapped bits read as 0.
  void read_inputs(std::span<uint8_t> sm3);

  size_t output_bytes() const { return (output_bits_ + 7) / 8; }
  size_t input_bytes() const { return (input_bits_ + 7) / 8; }
  size_t output_bits() const { return output_bits_; }
  size_t input_bits() const { return input_bits_; }
  std::span<const Copy> output_copies() const { return outputs_; }
  std::span<const Copy> input_copies() const { return inputs_; }
  // Whether a mapped object runs a process-data hook (its value may change without a write).
  bool hooked() const { return !output_hooks_.empty() || !input_hooks_.empty(); }
  // Whether an entry of `o` is mapped into the inputs (SM3).
  bool maps_input(const Object& o) const;

 private:
  struct Direction {
    std::vector<Copy> copies;
    std::vector<Object*> hooked;
    size_t bits = 0;
  };
  AbortCode compile_direction(PdoDirection dir, Direction& out);

  // In the order write_outputs() then read_inputs() read them (issue 16: the cyclic path of a
  // line of devices is bound by the cache lines it touches).
  std::vector<Copy> outputs_;
  std::vector<Object*> output_hooks_;
  std::vector<Object*> input_hooks_;
  size_t input_bits_ = 0;
  std::vector<Copy> inputs_;
  size_t output_bits_ = 0;
  ObjectDictionary& od_;
};

}  // namespace rackcat::coe
