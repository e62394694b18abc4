// The process image of one direction: the PDO assignment (0x1C12 or 0x1C13) and the mapping
// objects it names compiled into bit-copy operations between the SyncManager buffer and the
// mapped entries' object images (ETG.1000.6 §5.6.7.4.7/§5.6.7.4.8: PDOs in assignment order,
// entries in mapping order, padding entries index 0 skip bits). Compiling reuses capacity
// reserved up front; copying allocates nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "coe/object_dictionary.hpp"

namespace rackcat::mdp {

class ProcessImage {
 public:
  struct Copy {
    coe::Object* object;
    uint32_t object_bit;  // offset inside the object image
    uint32_t pd_bit;      // offset inside the SM buffer
    uint32_t bits;
  };

  // `assign_index` 0x1C12 (outputs) or 0x1C13 (inputs). Reserves room for every mapping object
  // of the dictionary so later compiles do not allocate.
  ProcessImage(coe::ObjectDictionary& od, uint16_t assign_index);

  // Rebuilds the copies from the current assignment. Entries naming missing objects are skipped
  // (the assignment validators keep them out).
  void compile();
  uint16_t bytes() const { return bytes_; }
  std::span<const Copy> copies() const { return copies_; }

  // SM buffer -> objects (outputs) and objects -> SM buffer (inputs); bits beyond a short buffer
  // are left alone.
  void to_objects(std::span<const uint8_t> pd) const;
  void from_objects(std::span<uint8_t> pd) const;

 private:
  coe::ObjectDictionary& od_;
  uint16_t assign_index_;
  std::vector<Copy> copies_;
  uint16_t bytes_ = 0;
};

}  // namespace rackcat::mdp
