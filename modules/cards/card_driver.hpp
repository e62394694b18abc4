// Slot-card drivers: one per card kind of the catalogue (mdp/card_catalogue.hpp). A driver owns
// the physical side of one EtherCAT module: the input channels with their signal sources and
// the output channels with the values on the terminals. Each cycle the rack calls
//   read_outputs()   in OP after the master's output data was unpacked into 0x7nnX,
//   write_inputs()   before the 0x6nnX objects are packed into the input data,
// and on leaving OP apply_safe_state() (0x4nn0..0x4nn3). None of them allocates.
//
// Output channel values are physical and stable in memory, so sources elsewhere can read
// them (loopback, plant inputs): digital 0/1, analog volts.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "base/cache_line_allocator.hpp"
#include "coe/entry_slot.hpp"
#include "coe/object_dictionary.hpp"
#include "mdp/rack_config.hpp"
#include "modules/signals/signal_source.hpp"

namespace rackcat::modules {

// Wiring faults of sourcing safety outputs (guide §4.7).
enum class WiringFault : uint8_t {
  None,
  ShortToGround,  // the wire reads 0 whatever is driven: driven high -> safe wiring fault
  ShortToSupply,  // the wire reads 1 whatever is driven: driven low -> unsafe wiring fault
};

// What a cycle reads and writes of an input channel (32 bytes: two channels per cache line);
// its source is the driver's (CardDriver::source / set_source).
struct InputChannel {
  double value = 0.0;       // last sample (V, °C or 0/1)
  uint32_t code = 0;        // last code written to the process data
  uint32_t last_valid = 0;  // last code from a present source (substitute "hold last")
  double loop_ohms = 10.0;  // thermocouple loop resistance reported in 0x5nn4
  bool open = false;        // thermocouple / RTD sensor break (fault injection)
};

struct OutputChannel {
  double commanded = 0.0;  // last valid output data from the master (physical)
  double driven = 0.0;     // what the card drives now (power-on rule, safe state, RIM loss)
  double wire = 0.0;       // the level on the terminal: driven, unless a wiring fault
  uint32_t code = 0;       // process-data code of `driven`
  WiringFault fault = WiringFault::None;
  bool overload = false;         // output overload (fault injection, channel diagnosis only)
  bool overtemperature = false;  // output driver overtemperature (likewise)
};

class CardDriver {
 public:
  CardDriver(const mdp::Module& module, coe::ObjectDictionary& od, size_t inputs, size_t outputs);
  virtual ~CardDriver() = default;
  CardDriver(const CardDriver&) = delete;
  CardDriver& operator=(const CardDriver&) = delete;

  const mdp::Module& module() const { return module_; }
  const mdp::CardType& card() const { return *module_.card; }
  std::span<InputChannel> inputs() { return inputs_; }
  std::span<const InputChannel> inputs() const { return inputs_; }
  std::span<OutputChannel> outputs() { return outputs_; }
  std::span<const OutputChannel> outputs() const { return outputs_; }
  // Input i's signal source (never null).
  const Source& source(size_t i) const { return *sources_[i]; }
  // Input i samples `source` (not null) from the next cycle on. Rack file, control API, RIM
  // links: never the cyclic path.
  void set_source(size_t i, std::unique_ptr<Source> source);

  // OP, valid output data: take the 0x7nnX values and drive them.
  virtual void read_outputs() {}
  // Sample the sources at t (seconds since start); dt is the time since the previous call
  // (oversampled cards spread their samples over it). Writes 0x6nnX (and 0x5nn4, 0x5nn6...).
  virtual void write_inputs(double t, double dt) = 0;
  // Leaving OP: drive the 0x4nnX substitute values.
  virtual void apply_safe_state() {}
  // Whether read_outputs() and write_inputs() depend on nothing but the 0x7nnX values and the
  // inputs' sources, every source affine in a value only a cycle's outputs move (a constant, a
  // loopback): then a cycle that repeats the last one's output data repeats its inputs too,
  // and the device may skip it (mdp::CycleListener::repeats_cycle). False by default: time,
  // oversampling, a filter, a queue fed by another thread.
  virtual bool time_invariant() const { return false; }
  // Drive every output to 0 (power-on before the first valid data, RIM offline: the RIM
  // drives its outputs to the TÜV-safe de-energised level).
  void de_energise();
  // The RIM is offline: its input process data reads 0.
  virtual void clear_inputs() = 0;
  // Substitute values of the inputs (mdp/substitute_values.hpp), after write_inputs() or
  // clear_inputs(): a channel whose source is missing (`rim_offline`, or its sensor open)
  // reports what 0x4nnA/0x4nnB say and sets its bit in 0x4nnC; a present one remembers its
  // code as the last valid one. Cyclic path: no allocation.
  void substitute_inputs(bool rim_offline);
  // The substitute reaction of output i (0x4nn8:i+1; the guide's rule without the object).
  uint16_t output_reaction(size_t i) const;

  // Physical units for `rackcat ctl list`.
  virtual const char* input_unit() const { return ""; }
  virtual const char* output_unit() const { return ""; }
  // Which faults can be injected.
  virtual bool detects_wiring_faults() const { return false; }
  virtual bool has_sensor_break() const { return false; }

  // Fault injection: a wiring fault on output i (the wire level follows at once).
  void set_wiring_fault(size_t i, WiringFault fault);
  // Card parameters from the rack file / control API (thermocouple: "cold_junction_c").
  // False when the card has no such parameter.
  virtual bool set_parameter(std::string_view /*key*/, double /*value*/) { return false; }

  // Wiring-fault details for 0xF382:n (safe) and 0xF384:n (unsafe): bit n = channel n.
  uint32_t safe_wiring_faults() const;
  uint32_t unsafe_wiring_faults() const;

 protected:
  coe::Object* object(uint16_t area_base, uint8_t nibble);
  // Update driven value, wire level and code of output i (inline: every output, every cycle).
  void drive(size_t i, double value, uint32_t code) {
    ++drive_epoch_;
    OutputChannel& o = outputs_[i];
    o.driven = value;
    o.code = code;
    switch (o.fault) {
      case WiringFault::None:
        o.wire = value;
        break;
      case WiringFault::ShortToGround:
        o.wire = 0.0;
        break;
      case WiringFault::ShortToSupply:
        o.wire = 1.0;
        break;
    }
  }
  // read_outputs()'s shortcut (issue 16: no per-channel work while the master repeats its
  // output data): true when `word` is what the last outputs_taken() recorded and nothing has
  // driven an output since (safe state, RIM loss, wiring fault, de-energise all go through
  // drive()). The 0x7nnX word itself is read every cycle, so SDO writes are seen too.
  bool outputs_current(uint32_t word) const {
    return word == taken_word_ && drive_epoch_ == taken_epoch_;
  }
  void outputs_taken(uint32_t word) {
    taken_word_ = word;
    taken_epoch_ = drive_epoch_;
  }
  // Puts `code` as input i's process-data value (every sample of an oversampled card).
  virtual void put_input_code(size_t /*i*/, uint32_t /*code*/) {}
  // Input i's source at t: an affine source from the driver's own copy of its three values,
  // any other through sample() (inline: every input, every cycle).
  double sample(size_t i, double t) {
    const Source::Affine& a = affine_[i];
    return a.x != nullptr ? a.value() : sources_[i]->sample(t);
  }
  // Whether any input's source varies within a cycle (Source::varies_within_cycle), kept by
  // set_source.
  bool sources_vary() const { return sources_vary_; }
  // Whether every input's source is affine (Source::affine: sampled from the driver's copy).
  bool sources_affine() const {
    for (const Source::Affine& a : affine_) {
      if (a.x == nullptr) return false;
    }
    return true;
  }
  // Set by write_inputs() of a driver that knows: every input code is what it was at the
  // previous cycle, and no input can be open (a digital input card whose word repeats).
  // substitute_inputs() then skips its channels while its last pass found none missing.
  bool codes_repeated_ = false;

  // What every cycle reads comes first, the set-up references last (issue 16: a line of racks
  // is bound by the cache lines each driver's round touches; a derived driver's own per-cycle
  // fields follow these).
  // Each array from a cache line: 8 channels are 4 lines (3 for the affine copies), not 5.
  base::CacheLineVector<InputChannel> inputs_;
  base::CacheLineVector<Source::Affine> affine_;  // per input: its source's affine()
  base::CacheLineVector<OutputChannel> outputs_;
  coe::Object* input_reaction_ = nullptr;  // 0x4nnA
  // Cyclic path: the channels 0x4nnA has entries for, and 0x4nnC's value slot.
  size_t reaction_channels_ = 0;
  coe::EntrySlot input_status_slot_;

 private:
  uint64_t drive_epoch_ = 1;  // counts drive() calls
  uint64_t taken_epoch_ = 0;  // drive_epoch_ at outputs_taken() (0: never)
  uint32_t taken_word_ = 0;
  bool sources_vary_ = false;
  bool none_missing_ = false;  // substitute_inputs()' last pass found no input missing
  std::vector<std::unique_ptr<Source>> sources_;  // per input, never null

 protected:
  coe::Object* output_reaction_ = nullptr;  // 0x4nn8
  coe::Object* input_value_ = nullptr;      // 0x4nnB
  const mdp::Module& module_;
  coe::ObjectDictionary& od_;
};

// The driver for a module's card (by the catalogue's Signal); every input starts with a
// constant 0 source.
std::unique_ptr<CardDriver> make_driver(const mdp::Module& module, coe::ObjectDictionary& od);

}  // namespace rackcat::modules
