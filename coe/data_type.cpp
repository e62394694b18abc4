// ETG.1000.6 §5.6.7.4.4 Table 63: sizes and names of the basic data types, as one table.
#include "coe/data_type.hpp"

#include <array>

namespace rackcat::coe {
namespace {

struct TypeInfo {
  DataType type;
  uint16_t bits;  // 0 = size given per entry (strings)
  std::string_view name;
  bool is_signed;
  bool is_real;
};

constexpr std::array<TypeInfo, 24> kTypes{{
    {DataType::Boolean, 1, "BOOL", false, false},
    {DataType::Integer8, 8, "SINT", true, false},
    {DataType::Integer16, 16, "INT", true, false},
    {DataType::Integer32, 32, "DINT", true, false},
    {DataType::Unsigned8, 8, "USINT", false, false},
    {DataType::Unsigned16, 16, "UINT", false, false},
    {DataType::Unsigned32, 32, "UDINT", false, false},
    {DataType::Real32, 32, "REAL", false, true},
    {DataType::VisibleString, 0, "STRING", false, false},
    {DataType::OctetString, 0, "OCTET_STRING", false, false},
    {DataType::UnicodeString, 0, "UNICODE_STRING", false, false},
    {DataType::Integer24, 24, "INT24", true, false},
    {DataType::Real64, 64, "LREAL", false, true},
    {DataType::Integer64, 64, "LINT", true, false},
    {DataType::Unsigned24, 24, "UINT24", false, false},
    {DataType::Unsigned64, 64, "ULINT", false, false},
    {DataType::Bit1, 1, "BIT1", false, false},
    {DataType::Bit2, 2, "BIT2", false, false},
    {DataType::Bit3, 3, "BIT3", false, false},
    {DataType::Bit4, 4, "BIT4", false, false},
    {DataType::Bit5, 5, "BIT5", false, false},
    {DataType::Bit6, 6, "BIT6", false, false},
    {DataType::Bit7, 7, "BIT7", false, false},
    {DataType::Bit8, 8, "BIT8", false, false},
}};

const TypeInfo* info(DataType t) {
  for (const auto& i : kTypes) {
    if (i.type == t) {
      return &i;
    }
  }
  return nullptr;
}

}  // namespace

std::optional<uint16_t> fixed_bit_size(DataType t) {
  const TypeInfo* i = info(t);
  if (!i || i->bits == 0) {
    return std::nullopt;
  }
  return i->bits;
}

std::string_view type_name(DataType t) {
  const TypeInfo* i = info(t);
  return i ? i->name : std::string_view{};
}

bool is_signed(DataType t) {
  const TypeInfo* i = info(t);
  return i && i->is_signed;
}

bool is_real(DataType t) {
  const TypeInfo* i = info(t);
  return i && i->is_real;
}

bool is_string(DataType t) {
  return t == DataType::VisibleString || t == DataType::OctetString || t == DataType::UnicodeString;
}

}  // namespace rackcat::coe
