// The slot-card catalogue: one table row per EtherCAT module type the rack can hold, linking the
// guide's Table 3 card IDs (0x2rr1:06) to Table 5 module idents (0x3000, 0xF030/0xF050), the
// Table 6 card names and descriptions (0x3nn1:01/02), the channel count, the voltage range
// (0x3nn1:08/09), the process-data object kinds of Appendix A (0x6nnX inputs, 0x7nnX outputs),
// the safe-state object (0x4nn0..0x4nn3) and the thermocouple/UART objects (0x5nnX).
//
// Everything that builds objects, PDOs, the ESI modules or slot-card drivers reads this table:
// nothing else knows what a card is. Decisions where the guide leaves gaps are in docs/MDP.md.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "coe/data_type.hpp"

namespace rackcat::mdp {

// Process-data object kinds: the low nibble X of 0x6nnX (inputs) / 0x7nnX (outputs), named
// as in Appendix A. The same nibble selects the guide's template mapping object 0x160X/0x1A0X.
enum class IoKind : uint8_t {
  DinX16 = 0x0,    // 0x6nn0 DINx16 / 0x7nn0 DOUTx16
  DinX8 = 0x1,     // 0x6nn1 DINx8  / 0x7nn1 DOUTx8
  AinX8 = 0x2,     // 0x6nn2 AINx8  / 0x7nn2 AOUTx8
  AinX16 = 0x3,    // 0x6nn3 AINx16 / 0x7nn3 AOUTx16
  TcX8 = 0x4,      // 0x6nn4 Thermocouplex8
  DinX16x8 = 0x5,  // 0x6nn5 DINx16 (x8 samples)
  DinX8x8 = 0x6,   // 0x6nn6 DINx8 (x8 samples)
  AinX16x8 = 0x7,  // 0x6nn7 AINx16 (x8 samples)
  AinX8x8 = 0x8,   // 0x6nn8 AINx8 (x8 samples)
  RtdX4 = 0x9,     // 0x6nn9 RTDx4
  UartX4 = 0xA,    // 0x6nnA UARTx4 status words
  DinX4 = 0xB,     // 0x6nnB DINx4 / 0x7nnB DOUTx4 (BIT4 + 4-bit pad)
  DioX8 = 0xC,     // 0x6nnC DIOx8 (DIN + readback)
  Encoder = 0xD,   // 0x6nnD / 0x7nnD absolute encoder telegram (docs/ENCODER.md), not Appendix A
};

// One mapped entry of a layout whose entries differ in size and type (the encoder's telegram:
// encoder guide "Standard Telegram 83", signals ZSW2_ENC, G1_ZSW1, G1_XIST1, G1_XIST2, NIST_B).
struct IoField {
  std::string_view name;
  coe::DataType type;
  uint16_t bits;
};

// Layout of one 0x6nnX / 0x7nnX object and of the module's PDO mapping object: `entries`
// mapped subindices 1..entries of `entry_bits` bits each; `pad_bits` > 0 adds a padding
// subindex (entries+1) so the object fills whole bytes (DINx4/DOUTx4: BIT4 + pad_4).
struct IoLayout {
  IoKind kind;
  bool output;                 // 0x7nnX (RxPDO) rather than 0x6nnX (TxPDO)
  std::string_view name;       // "DINx16 (inputs)" — Appendix A object name
  std::string_view pdo_name;   // "TxPDO Mapping (DINx16)" — Appendix A mapping name
  uint8_t entries;             // mapped subindices 1..entries
  uint16_t entry_bits;         // bit length of each mapped entry
  coe::DataType entry_type;    // UINT, USINT (guide: BYTE), BIT4, OCTET_STRING for sample arrays
  uint8_t pad_bits;            // trailing padding subindex, 0 = none
  std::string_view entry_fmt;  // entry name: "DIN[15..0]", "AIN[{}]", "TC[{}]" ({} = index)
  uint8_t entry_name_base;     // first value substituted for {} (0 or 1, as the guide numbers)

  uint16_t object_bits() const;
  uint16_t object_bytes() const { return static_cast<uint16_t>((object_bits() + 7) / 8); }
  // Name, bit length and data type of mapped subindex `sub` (1..entries): entry_fmt /
  // entry_bits / entry_type, or the kind's own field (fields()) where the entries differ.
  std::string entry_name(uint8_t sub) const;
  uint16_t bits_of(uint8_t sub) const;
  coe::DataType type_of(uint8_t sub) const;
  // The per-entry fields of a mixed layout (IoKind::Encoder); empty for the uniform ones.
  std::span<const IoField> fields() const;
};

// Layout of an input (output = false) or output kind; nullopt for combinations Appendix A
// does not define (e.g. outputs of kind TcX8).
const IoLayout* io_layout(IoKind kind, bool output);
// All layouts in Appendix A order (inputs 0x6nn0..C, then outputs 0x7nn0..3, 0x7nnB).
std::span<const IoLayout> io_layouts();

// Safe-state object kinds 0x4nn0..0x4nn3 (guide §2.5, Tables 7-10).
enum class SafeStateKind : uint8_t {
  DoutX16 = 0,  // 0x4nn0: UINT enable / action / value
  DoutX8 = 1,   // 0x4nn1: USINT enable / action / value
  AoutX8 = 2,   // 0x4nn2: USINT enable / action, UINT value[1..8]
  AoutX16 = 3,  // 0x4nn3: UINT enable / action, UINT value[1..16]
};

// Channel classes for 0x3nn1:06/07: "each card type has its own range that starts from 0"
// (guide Table 6). Thermocouple and RTD channels are analog inputs (glossary "AIN").
enum class ChannelClass : uint8_t {
  DigitalOutput,
  DigitalInput,
  AnalogOutput,
  AnalogInput,
  Serial
};

// Physical meaning of the channels, for the slot-card drivers (modules/).
enum class Signal : uint8_t {
  DigitalIn,          // 24 V / 5 V digital inputs
  DigitalInInverted,  // inverted digital inputs (0xD... inverted logic)
  DigitalOutSource,   // sourcing safety outputs with wire readback (SOUT, wiring faults)
  DigitalOutSink,
  DigitalOutOpto,
  Relay,             // SPST relay contacts
  RelayForceGuided,  // force-guided relay with feedback contacts (read back through 0x6nnB)
  DigitalInOut,      // E84: 8 inputs + 8 outputs with readback
  AnalogIn,
  AnalogOut,
  Thermocouple,
  Rtd,
  Uart,
  Encoder,  // absolute rotary encoder: the channel's source is the shaft angle in revolutions
};

struct CardType {
  uint16_t card_id;              // Table 3 I/O card ID as reported in 0x2rr1:06
  std::string_view name;         // Table 6 card type, 0x3nn1:01 (string(8)), e.g. "CDI-10"
  std::string_view description;  // 0x3nn1:02 (string(32)), e.g. "16xDin 24V"
  std::string_view
      slot_card_type;     // Table 3 / Table 5 wording, e.g. "16-Channel 24 V Digital Input"
  uint32_t module_ident;  // Table 5 ident, 0x3000:n / 0xF030 / 0xF050 / ESI ModuleIdent
  uint8_t channels;       // 0x3nn1:03
  float min_voltage;      // 0x3nn1:09 (guide Table 6 subindex 8/9 wording, see MDP.md)
  float max_voltage;
  ChannelClass channel_class;  // 0x3nn1:06/07 numbering
  Signal signal;
  uint8_t samples;               // samples per channel per PD cycle (8 for the x8 variants)
  char thermocouple_type;        // 'K', 'J', 'R' for thermocouple cards, 0 otherwise
  std::optional<IoKind> input;   // 0x6nnX kind, TxPDO 0x1A00+n-1
  std::optional<IoKind> output;  // 0x7nnX kind, RxPDO 0x1600+n-1
  std::optional<SafeStateKind> safe_state;  // 0x4nnX
  bool thermocouple_ohms;                   // 0x5nn4
  bool uart;                                // 0x5nn5..0x5nnE
  // Absolute rotary encoder settings 0x8nn0/0x8nn1 and information 0x9nn0 (docs/ENCODER.md).
  bool encoder() const { return signal == Signal::Encoder; }
  // 0x3nn1:01: the physical card's type, the name without a "/X8" variant suffix.
  std::string_view io_card_type() const { return name.substr(0, name.find('/')); }
  // False for the rows that exist only in Table 5 (variants a config selects by name or by
  // card ID plus `oversampling: 8`, and the 8-channel digital input without a Table 3 ID).
  bool in_table3;
};

// The whole catalogue in table order.
std::span<const CardType> card_catalogue();
// Lookup by Table 3 card ID (the base card, never an oversampled variant), by Table 6 name
// ("CDI-10", case-insensitive), or by module ident. nullptr when unknown.
const CardType* find_card(uint16_t card_id);
const CardType* find_card(std::string_view name);
const CardType* find_card_by_ident(uint32_t module_ident);
// The 8x-oversampled variant of a card (CDI-10 -> CDI-10/X8); nullptr if it has none.
const CardType* oversampled_variant(const CardType& card);

// Index rules of the Modular Device Profile (ETG.5001.1 §4, guide §1 "nn = module number - 1").
inline constexpr uint16_t kIndexDistance = 0x10;  // 0xF000:01
inline constexpr uint16_t kMaxModules = 255;      // 0xF000:02
inline constexpr uint8_t kMaxRims = 5;
// 0xAnnX for module number n (1..255) and object nibble x: base | (n-1)*0x10 | x.
constexpr uint16_t module_index(uint16_t area_base, uint16_t module_number, uint8_t nibble) {
  return static_cast<uint16_t>(area_base + (module_number - 1) * kIndexDistance + nibble);
}
// 0x2rr1 for RIM rr (1..5): "rr = rim number" (guide Appendix A).
constexpr uint16_t rim_info_index(uint8_t rim) {
  return static_cast<uint16_t>(0x2000 + rim * kIndexDistance + 1);
}

}  // namespace rackcat::mdp
