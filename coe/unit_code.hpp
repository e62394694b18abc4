// Physical units of object entries as ETG.1004 unit codes: the 32-bit value an ESI carries in
// ObjectInfoType/Unit (ETG.2000, EtherCATBase.xsd) next to the UnitTypes that name its notation
// indices.
//
// ETG.1004 is not in ../shared/reference. It follows CiA 303-2 ("Representation of SI units and
// prefixes"); what is used here and where it was established:
//  - Layout (CiA 303-2 §3.2 "prefix, numerator and denominator", as CiA 402's SI unit objects
//    0x60A8/0x60A9 pack it): bits 31-24 prefix, bits 23-16 numerator notation index, bits 15-8
//    denominator notation index (0 = none), bits 7-0 reserved (0). CiA 402's default velocity
//    unit 0x00B44700 is "revolution / minute", 0xFDB44700 is 0.001 of it.
//  - Prefix: the power of ten as a signed byte (CiA 303-2 §5 prefix table: mega 06, giga 09;
//    0xFD = 10^-3, 0xFF = 10^-1).
//  - Notation indices (CiA DRP-303-2 §4 code tables: ampere 04, hertz 20 .. watt 24 in SI
//    brochure order, which continues coulomb 25, volt 26, farad 27, ohm 28, siemens 29,
//    weber 2A, tesla 2B, henry 2C, degree Celsius 2D; the non-SI units minute 47 and the motion
//    units revolution B4 as CiA 402's 0x00B44700 uses them).
// Only entries whose unit the guide (or docs/MODULES.md for rackcat's temperature word) states
// get one (docs/MDP.md "Units").
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace rackcat::coe::unit {

// CiA 303-2 notation indices used by rackcat.
inline constexpr uint8_t kNone = 0x00;
inline constexpr uint8_t kVolt = 0x26;
inline constexpr uint8_t kOhm = 0x28;
inline constexpr uint8_t kDegreeCelsius = 0x2D;
inline constexpr uint8_t kMinute = 0x47;
inline constexpr uint8_t kRevolution = 0xB4;

// The 32-bit unit code: prefix = power of ten, numerator / denominator = notation indices.
constexpr uint32_t code(int8_t prefix, uint8_t numerator, uint8_t denominator = kNone) {
  return (static_cast<uint32_t>(static_cast<uint8_t>(prefix)) << 24) |
         (static_cast<uint32_t>(numerator) << 16) | (static_cast<uint32_t>(denominator) << 8);
}
constexpr uint8_t numerator(uint32_t c) {
  return static_cast<uint8_t>(c >> 16);
}
constexpr uint8_t denominator(uint32_t c) {
  return static_cast<uint8_t>(c >> 8);
}

// The codes of the guide's entries.
inline constexpr uint32_t kVolts = code(0, kVolt);                  // 0x3nn1:08/09
inline constexpr uint32_t kOhms = code(0, kOhm);                    // 0x5nn4 (guide §2.6)
inline constexpr uint32_t kCelsius = code(0, kDegreeCelsius);       // 0x2000:0F (§4.8)
inline constexpr uint32_t kDeciCelsius = code(-1, kDegreeCelsius);  // TC/RTD words, 0.1 °C
inline constexpr uint32_t kRpm = code(0, kRevolution, kMinute);     // fan RPM, 0x00B44700

// The ESI UnitType (NotationIndex, Name, Symbol) of a notation index rackcat uses.
struct Notation {
  uint8_t index;
  std::string_view name;
  std::string_view symbol;
};

inline constexpr Notation kNotations[] = {
    {kVolt, "volt", "V"},
    {kOhm, "ohm", "\xCE\xA9"},  // U+03A9
    {kDegreeCelsius, "degree Celsius",
     "\xC2\xB0"
     "C"},  // U+00B0 C
    {kMinute, "minute", "min"},
    {kRevolution, "revolution", "rev"},
};

constexpr std::optional<Notation> notation(uint8_t index) {
  for (const auto& n : kNotations) {
    if (n.index == index) return n;
  }
  return std::nullopt;
}

}  // namespace rackcat::coe::unit
