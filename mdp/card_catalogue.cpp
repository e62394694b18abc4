// The slot-card table (guide Tables 3, 5 and 6; Appendix A object kinds). Assignments the guide
// does not state (which Table 6 name belongs to which Table 3 card, the voltage ranges of the
// digital cards, the E84 card's output kind) are decided in docs/MDP.md "Card catalogue".
#include "mdp/card_catalogue.hpp"

#include <algorithm>
#include <array>
#include <cctype>

namespace rackcat::mdp {
namespace {

using coe::DataType;

// Appendix A: 0x6nn0..0x6nnC and 0x7nn0..0x7nn3, 0x7nnB with their mapping objects 0x1A0X /
// 0x160X. Sample arrays ("ARRAY [0..7] OF UINT") are OCTET_STRING entries of the array's size.
constexpr std::array<IoLayout, 20> kLayouts{{
    {IoKind::DinX16, false, "DINx16 (inputs)", "TxPDO Mapping (DINx16)", 1, 16,
     DataType::Unsigned16, 0, "DIN[15..0]", 0},
    {IoKind::DinX8, false, "DINx8 (inputs)", "TxPDO Mapping (DINx8)", 1, 8, DataType::Unsigned8, 0,
     "DIN[7..0]", 0},
    {IoKind::AinX8, false, "AINx8 (inputs)", "TxPDO Mapping (AINx8)", 8, 16, DataType::Unsigned16,
     0, "AIN[{}]", 0},
    {IoKind::AinX16, false, "AINx16 (inputs)", "TxPDO Mapping (AINx16)", 16, 16,
     DataType::Unsigned16, 0, "AIN[{}]", 0},
    {IoKind::TcX8, false, "Thermocouplex8 (inputs)", "TxPDO Mapping (TCx8)", 8, 16,
     DataType::Unsigned16, 0, "TC[{}]", 1},
    {IoKind::DinX16x8, false, "DINx16 (x8samples)", "TxPDO Mapping (DINx16x8)", 1, 128,
     DataType::OctetString, 0, "DIN[15..0]", 0},
    {IoKind::DinX8x8, false, "DINx8 (x8samples)", "TxPDO Mapping (DINx8x8)", 1, 64,
     DataType::OctetString, 0, "DIN[7..0]", 0},
    {IoKind::AinX16x8, false, "AINx16 (x8samples)", "TxPDO Mapping (AINx16x8)", 16, 128,
     DataType::OctetString, 0, "AIN[{}]", 0},
    {IoKind::AinX8x8, false, "AINx8 (x8samples)", "TxPDO Mapping (AINx8x8)", 8, 128,
     DataType::OctetString, 0, "AIN[{}]", 0},
    {IoKind::RtdX4, false, "RTDx4 (inputs)", "TxPDO Mapping (AINx4)", 4, 16, DataType::Unsigned16,
     0, "AIN[{}]", 1},
    {IoKind::UartX4, false, "UARTx4 (inputs)", "TxPDO Mapping (UARTx4)", 4, 16,
     DataType::Unsigned16, 0, "Status[{}]", 0},
    {IoKind::DinX4, false, "DINx4 (inputs)", "TxPDO Mapping (DINx4)", 1, 4, DataType::Bit4, 4,
     "DIN[3..0]", 0},
    {IoKind::DioX8, false, "DIOx8 (inputs)", "TxPDO Mapping (DIOx8)", 2, 8, DataType::Unsigned8, 0,
     "", 0},
    {IoKind::DinX16, true, "DOUTx16 (outputs)", "RxPDO Mapping (DOUTx16)", 1, 16,
     DataType::Unsigned16, 0, "DOUT[15..0]", 0},
    {IoKind::DinX8, true, "DOUTx8 (outputs)", "RxPDO Mapping (DOUTx8)", 1, 8, DataType::Unsigned8,
     0, "DOUT[7..0]", 0},
    {IoKind::AinX8, true, "AOUTx8 (outputs)", "RxPDO Mapping (AOUTx8)", 8, 16, DataType::Unsigned16,
     0, "AOUT[{}]", 0},
    {IoKind::AinX16, true, "AOUTx16 (outputs)", "RxPDO Mapping (AOUTx16)", 16, 16,
     DataType::Unsigned16, 0, "AOUT[{}]", 0},
    {IoKind::DinX4, true, "DOUTx4 (outputs)", "RxPDO Mapping (DOUTx4)", 1, 4, DataType::Bit4, 4,
     "DOUT[3..0]", 0},
    // Not Appendix A: the absolute encoder's fixed telegram (fields below, docs/ENCODER.md).
    {IoKind::Encoder, false, "ENC (inputs)", "TxPDO Mapping (ENC)", 5, 0, DataType{}, 0, "", 0},
    {IoKind::Encoder, true, "ENC (outputs)", "RxPDO Mapping (ENC)", 2, 0, DataType{}, 0, "", 0},
}};

// Encoder guide "Standard Telegram 83" (signal list "Signal list for Cyclic Data Transmission":
// lengths and signs): actual values ZSW2_ENC, G1_ZSW1, G1_XIST1, G1_XIST2, NIST_B; setpoints
// STW2_ENC, G1_STW1. Little-endian CoE entries instead of PROFINET's big-endian words.
constexpr std::array<IoField, 5> kEncoderInputs{{
    {"ZSW2_ENC", DataType::Unsigned16, 16},
    {"G1_ZSW1", DataType::Unsigned16, 16},
    {"G1_XIST1", DataType::Unsigned32, 32},
    {"G1_XIST2", DataType::Unsigned32, 32},
    {"NIST_B", DataType::Integer32, 32},
}};
constexpr std::array<IoField, 2> kEncoderOutputs{{
    {"STW2_ENC", DataType::Unsigned16, 16},
    {"G1_STW1", DataType::Unsigned16, 16},
}};

constexpr auto DO = ChannelClass::DigitalOutput;
constexpr auto DI = ChannelClass::DigitalInput;
constexpr auto AO = ChannelClass::AnalogOutput;
constexpr auto AI = ChannelClass::AnalogInput;
constexpr auto SER = ChannelClass::Serial;
constexpr std::optional<IoKind> kNone = std::nullopt;
constexpr std::optional<SafeStateKind> kNoSafe = std::nullopt;

// Columns: card ID, name, description, Table 3/5 wording, module ident, channels, min V, max V,
// channel class, signal, samples, TC type, input kind, output kind, safe state, ohms, uart,
// in Table 3.
const std::array<CardType, 26> kCards{{
    // Table 3 cards, in Table 3 order.
    {0x3000, "CRS-14", "4xDout FG Relay", "4-Channel Force Guided Relay", 0x0064D004, 4, 0.0f,
     24.0f, DO, Signal::RelayForceGuided, 1, 0, IoKind::DinX4, IoKind::DinX4, SafeStateKind::DoutX8,
     false, false, true},
    {0x4000, "CIO-10", "8xDin 8xDout E84", "E84 Communication (8 Digital Input & 8 Digital Output)",
     0x0064DD08, 8, 0.0f, 24.0f, DI, Signal::DigitalInOut, 1, 0, IoKind::DioX8, IoKind::DinX8,
     SafeStateKind::DoutX8, false, false, true},
    {0x5000, "CDO-11", "16xDout Sink", "16-Channel Sinking Digital Output", 0x0064D016, 16, 0.0f,
     24.0f, DO, Signal::DigitalOutSink, 1, 0, kNone, IoKind::DinX16, SafeStateKind::DoutX16, false,
     false, true},
    {0x7000, "CRS-10", "8xDout Relay", "8-Channel SPST Relay", 0x0064D008, 8, 0.0f, 24.0f, DO,
     Signal::Relay, 1, 0, kNone, IoKind::DinX8, SafeStateKind::DoutX8, false, false, true},
    {0x9000, "CDI-12", "16xInverted Din", "16-Channel Inverted Digital Input", 0x0064D116, 16, 0.0f,
     24.0f, DI, Signal::DigitalInInverted, 1, 0, IoKind::DinX16, kNone, kNoSafe, false, false,
     true},
    {0xA000, "COO-10", "16xDout Opto", "16-Channel Opto-Isolated Digital Output", 0x0064D016, 16,
     0.0f, 24.0f, DO, Signal::DigitalOutOpto, 1, 0, kNone, IoKind::DinX16, SafeStateKind::DoutX16,
     false, false, true},
    {0xB000, "COO-11", "8xDout Opto", "8-Channel Opto-Isolated Digital Output", 0x0064D008, 8, 0.0f,
     24.0f, DO, Signal::DigitalOutOpto, 1, 0, kNone, IoKind::DinX8, SafeStateKind::DoutX8, false,
     false, true},
    {0xC000, "CDI-11", "16xDin 5V", "16-Channel 5 V Digital Input", 0x0064D116, 16, 0.0f, 5.0f, DI,
     Signal::DigitalIn, 1, 0, IoKind::DinX16, kNone, kNoSafe, false, false, true},
    {0xD000, "CDI-10", "16xDin 24V", "16-Channel 24 V Digital Input", 0x0064D116, 16, 0.0f, 24.0f,
     DI, Signal::DigitalIn, 1, 0, IoKind::DinX16, kNone, kNoSafe, false, false, true},
    {0xE000, "CDO-10", "16xDout Source", "16-Channel Sourcing Digital Output", 0x0064D016, 16, 0.0f,
     24.0f, DO, Signal::DigitalOutSource, 1, 0, kNone, IoKind::DinX16, SafeStateKind::DoutX16,
     false, false, true},
    {0xF011, "CAO-15", "8xAout 16 bit -10 to 10", "8-Channel Analog Output -10 V to 10 V",
     0x0064A008, 8, -10.0f, 10.0f, AO, Signal::AnalogOut, 1, 0, kNone, IoKind::AinX8,
     SafeStateKind::AoutX8, false, false, true},
    {0xF015, "CAO-17", "16xAout 16 bit -10 to 10", "16-Channel Analog Output -10 V to 10 V",
     0x0064A016, 16, -10.0f, 10.0f, AO, Signal::AnalogOut, 1, 0, kNone, IoKind::AinX16,
     SafeStateKind::AoutX16, false, false, true},
    {0xF081, "CAI-11", "8xAin 16-bit Open reads 0", "8-Channel Analog Input -10 V to 10 V",
     0x0064A108, 8, -10.0f, 10.0f, AI, Signal::AnalogIn, 1, 0, IoKind::AinX8, kNone, kNoSafe, false,
     false, true},
    {0xF085, "CAI-15", "16xAin 16 bit Open read 0", "16-Channel Analog Input -10 V to 10 V",
     0x0064A116, 16, -10.0f, 10.0f, AI, Signal::AnalogIn, 1, 0, IoKind::AinX16, kNone, kNoSafe,
     false, false, true},
    {0xF012, "CTP-11", "8xThermocouple K-type", "8-Channel K-type Thermocouple", 0x0064C108, 8,
     -0.01f, 0.08f, AI, Signal::Thermocouple, 1, 'K', IoKind::TcX8, kNone, kNoSafe, true, false,
     true},
    {0xF013, "CTP-12", "8xThermocouple J-type", "8-Channel J-type Thermocouple", 0x0064C108, 8,
     -0.01f, 0.08f, AI, Signal::Thermocouple, 1, 'J', IoKind::TcX8, kNone, kNoSafe, true, false,
     true},
    {0xF014, "CTP-13", "8xThermocouple R-type", "8-Channel R-type Thermocouple", 0x0064C108, 8,
     -0.01f, 0.08f, AI, Signal::Thermocouple, 1, 'R', IoKind::TcX8, kNone, kNoSafe, true, false,
     true},
    {0xF022, "CTP-14", "4xRTD -10 to 10", "4-Channel RTD", 0x0064C104, 4, -10.0f, 10.0f, AI,
     Signal::Rtd, 1, 0, IoKind::RtdX4, kNone, kNoSafe, false, false, true},
    {0xF210, "CUR-12", "4xUART RS232/RS485", "4-Channel UART", 0x0064C004, 4, -12.0f, 12.0f, SER,
     Signal::Uart, 1, 0, IoKind::UartX4, kNone, kNoSafe, false, true, true},
    // Table 5 idents without a card of their own in Table 3: the 8x-oversampled variants of the
    // digital and analog input cards, and the 8-channel digital input (card ID 0x8000 chosen by
    // rackcat; Table 3 lists none).
    {0x8000, "CDI-13", "8xDin 24V", "8-Channel Digital Input", 0x0064D108, 8, 0.0f, 24.0f, DI,
     Signal::DigitalIn, 1, 0, IoKind::DinX8, kNone, kNoSafe, false, false, false},
    {0x8000, "CDI-13/X8", "8xDin 24V 8x oversampled", "8-Channel Digital Input 8x Oversampled",
     0x0064D808, 8, 0.0f, 24.0f, DI, Signal::DigitalIn, 8, 0, IoKind::DinX8x8, kNone, kNoSafe,
     false, false, false},
    {0xD000, "CDI-10/X8", "16xDin 24V 8x oversampled", "16-Channel Digital Input 8x Oversampled",
     0x0064D816, 16, 0.0f, 24.0f, DI, Signal::DigitalIn, 8, 0, IoKind::DinX16x8, kNone, kNoSafe,
     false, false, false},
    {0xF081, "CAI-11/X8", "8xAin 16-bit 8x oversampled", "8-Channel Analog Input 8x Oversampled",
     0x0064A808, 8, -10.0f, 10.0f, AI, Signal::AnalogIn, 8, 0, IoKind::AinX8x8, kNone, kNoSafe,
     false, false, false},
    {0xF085, "CAI-15/X8", "16xAin 16-bit 8x oversampled", "16-Channel Analog Input 8x Oversampled",
     0x0064A816, 16, -10.0f, 10.0f, AI, Signal::AnalogIn, 8, 0, IoKind::AinX16x8, kNone, kNoSafe,
     false, false, false},
    // The 5 V and inverted 16-channel inputs oversample like the 24 V card.
    {0xC000, "CDI-11/X8", "16xDin 5V 8x oversampled", "16-Channel Digital Input 8x Oversampled",
     0x0064D816, 16, 0.0f, 5.0f, DI, Signal::DigitalIn, 8, 0, IoKind::DinX16x8, kNone, kNoSafe,
     false, false, false},
    // Not a Fusion.IO card: an absolute multi-turn rotary encoder interface after the encoder
    // guide (the PROFINET absolute encoder user guide). Card ID 0xF300 and
    // ident family 0xE are rackcat's; the voltage range is the encoder's supply, guide
    // "Connector power supply" US 10 - 30 V DC. One channel: the shaft.
    {0xF300, "CAE-10", "Abs encoder 16+12 bit", "Absolute Rotary Encoder Interface", 0x0064E001, 1,
     10.0f, 30.0f, AI, Signal::Encoder, 1, 0, IoKind::Encoder, IoKind::Encoder, kNoSafe, false,
     false, false},
}};

bool iequal(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

std::span<const IoField> IoLayout::fields() const {
  if (kind != IoKind::Encoder) return {};
  if (output) return kEncoderOutputs;
  return kEncoderInputs;
}

uint16_t IoLayout::object_bits() const {
  const auto f = fields();
  if (f.empty()) return static_cast<uint16_t>(entries * entry_bits + pad_bits);
  uint16_t bits = 0;
  for (const IoField& x : f) bits = static_cast<uint16_t>(bits + x.bits);
  return bits;
}

uint16_t IoLayout::bits_of(uint8_t sub) const {
  const auto f = fields();
  return f.empty() ? entry_bits : f[sub - 1].bits;
}

coe::DataType IoLayout::type_of(uint8_t sub) const {
  const auto f = fields();
  return f.empty() ? entry_type : f[sub - 1].type;
}

std::string IoLayout::entry_name(uint8_t sub) const {
  if (kind == IoKind::DioX8) return sub == 1 ? "DIN[7..0]" : "DIN RB[7..0]";
  if (const auto f = fields(); !f.empty()) return std::string(f[sub - 1].name);
  std::string out(entry_fmt);
  const auto pos = out.find("{}");
  if (pos != std::string::npos) {
    out.replace(pos, 2, std::to_string(sub - 1 + entry_name_base));
  }
  return out;
}

const IoLayout* io_layout(IoKind kind, bool output) {
  for (const auto& l : kLayouts) {
    if (l.kind == kind && l.output == output) return &l;
  }
  return nullptr;
}

std::span<const IoLayout> io_layouts() {
  return kLayouts;
}

std::span<const CardType> card_catalogue() {
  return kCards;
}

const CardType* find_card(uint16_t card_id) {
  for (const auto& c : kCards) {
    if (c.card_id == card_id && c.samples == 1) return &c;
  }
  return nullptr;
}

const CardType* find_card(std::string_view name) {
  for (const auto& c : kCards) {
    if (iequal(c.name, name)) return &c;
  }
  return nullptr;
}

const CardType* find_card_by_ident(uint32_t module_ident) {
  for (const auto& c : kCards) {
    if (c.module_ident == module_ident) return &c;
  }
  return nullptr;
}

const CardType* oversampled_variant(const CardType& card) {
  if (card.samples != 1) return nullptr;
  for (const auto& c : kCards) {
    if (c.samples == 8 && c.card_id == card.card_id) return &c;
  }
  return nullptr;
}

}  // namespace rackcat::mdp
