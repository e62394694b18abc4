// Manufacturer-specific device information: 0x2000 Device Information (guide §2.1 Table 1,
// Appendix A), 0x2rr1 RIM Information (§2.2 Table 2), 0x3000 Module Ident Map (§2.3 Table 4) and
// 0x3nn1 Module Information (§2.4 Table 6).
#include <algorithm>
#include <array>
#include <cstdio>
#include <ctime>
#include <string>

#include "mdp/card_catalogue.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;
using coe::AbortCode;

// Seconds of a "YYYY-MM-DD HH:MM:SS" text (UTC), already validated.
int64_t parse_clock(std::string_view s) {
  std::tm tm{};
  std::sscanf(std::string(s).c_str(), "%d-%d-%d %d:%d:%d", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
              &tm.tm_hour, &tm.tm_min, &tm.tm_sec);
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return static_cast<int64_t>(timegm(&tm));
}

// Fans without a measurement read -100 % deviation and 0 RPM (guide Table 2); fitted fans
// start at their nominal speed.
constexpr float kNominalFanRpm = 3000.0f;
constexpr float kNoFanStatus = -100.0f;
constexpr float kInitialCpuTemperature = 40.0f;

Object device_information(const RackConfig& cfg) {
  const ControlModule& cm = cfg.control;
  Object o(0x2000, ObjectCode::Record, "Device Information", 0);
  o.add(sub0(0x0F));
  o.add(str(0x01, "Part Number", 64, acc("ro"), cm.part_number));
  o.add(str(0x02, "FW Version", 4, acc("ro"), cm.firmware_version));
  o.add(str(0x03, "Serial Number", 24, acc("ro"), cm.serial_number));
  o.add(str(0x04, "IPv4 Address", 16, acc("ro,wr_preop"), cm.ipv4));
  o.add(str(0x05, "MAC Address", 24, acc("ro"), cm.mac));
  o.add(str(0x06, "Config MD5", 24, acc("ro"), cm.config_md5));
  o.add(str(0x07, "Config Date", 16, acc("ro"), cm.config_date));
  o.add(str(0x08, "Clock", 32, acc("ro,wr_preop")));
  o.add(num(0x09, "Event Mask", DataType::Unsigned32, acc("rw"), 0xFFFFFFFF));
  o.add(num(0x0A, "Event Status", DataType::Unsigned32, acc("ro") | kTx, 0));
  o.add(num(0x0B, "Detect Modules Override", DataType::Bit1, acc("ro,wr_preop"),
            cfg.detect_modules_override ? 1 : 0));
  o.add(pad(0x0C, 15));
  o.add(real(0x0D, "Fan Status (CPU Zone)", acc("ro") | kTx, 0.0f));
  o.add(with_unit(real(0x0E, "Fan RPM (CPU Zone)", acc("ro") | kTx, kNominalFanRpm),
                  coe::unit::kRpm));
  // Appendix A names it "Temperature (Slot Zone)", Table 1 and §4.8 "CPU zone": CPU it is.
  o.add(with_unit(real(0x0F, "Temperature (CPU Zone)", acc("ro") | kTx, kInitialCpuTemperature),
                  coe::unit::kCelsius));
  o.finalize();
  o.edit_hooks().validate_write = [](const Object& obj, int subindex, std::span<const uint8_t> data,
                                     EsmState) {
    // Only a changed value is checked: a complete access writes back what it read.
    auto changed = [&](uint8_t sub) {
      auto v = written_bytes(obj, sub, subindex, data);
      auto cur = obj.bytes(sub);
      return !v.empty() && !std::equal(v.begin(), v.end(), cur.begin(), cur.end());
    };
    if (changed(0x04) && !is_valid_ipv4(as_text(written_bytes(obj, 0x04, subindex, data)))) {
      return AbortCode::ValueRange;
    }
    if (changed(0x08) && !is_valid_clock(as_text(written_bytes(obj, 0x08, subindex, data)))) {
      return AbortCode::ValueRange;
    }
    return AbortCode::None;
  };
  return o;
}

Object rim_information(const Rim& r) {
  Object o(rim_info_index(r.number), ObjectCode::Record, "RIM Information", 0);
  o.add(sub0(0x0D));
  o.add(str(0x01, "Part Number", 64, acc("ro"), r.part_number));
  o.add(str(0x02, "FW Version", 4, acc("ro"), r.firmware_version));
  o.add(str(0x03, "Serial Number", 24, acc("ro"), r.serial_number));
  o.add(str(0x04, "Type", 24, acc("ro"), rim_type_name(r.type)));
  o.add(str(0x05, "Unit Information", 32, acc("ro"), r.unit_information));
  // "ARRAY [0..23] of UINT": the card ID of each slot, 0 for an empty slot, little-endian.
  std::array<uint8_t, 48> cards{};
  for (const auto& s : r.slots) {
    cards[2 * (s.slot - 1)] = static_cast<uint8_t>(s.card->card_id);
    cards[2 * (s.slot - 1) + 1] = static_cast<uint8_t>(s.card->card_id >> 8);
  }
  o.add(octets(0x06, "IO Slot Cards", 48, acc("ro"), cards));
  o.add(num(0x07, "Event Mask", DataType::Unsigned32, acc("rw"), 0xFFFFFFFF));
  o.add(num(0x08, "Event Status", DataType::Unsigned32, acc("ro") | kTx, 0));
  o.add(pad(0x09, 16));
  o.add(real(0x0A, "Fan Status (Power Supply Zone)", acc("ro") | kTx,
             r.power_supply_fan ? 0.0f : kNoFanStatus));
  o.add(real(0x0B, "Fan Status (Slot Card Zone)", acc("ro") | kTx,
             r.slot_card_fan ? 0.0f : kNoFanStatus));
  o.add(with_unit(real(0x0C, "Fan RPM (Power Supply Zone)", acc("ro") | kTx,
                       r.power_supply_fan ? kNominalFanRpm : 0.0f),
                  coe::unit::kRpm));
  o.add(with_unit(real(0x0D, "Fan RPM (Slot Card Zone)", acc("ro") | kTx,
                       r.slot_card_fan ? kNominalFanRpm : 0.0f),
                  coe::unit::kRpm));
  o.finalize();
  return o;
}

Object module_information(const Module& m) {
  const CardType& c = *m.card;
  Object o(m.index(0x3000, 1), ObjectCode::Record, "Module Information", 0);
  o.add(sub0(9));
  o.add(str(0x01, "IO Card Type", 8, acc("ro"), c.io_card_type()));
  o.add(str(0x02, "Description", 32, acc("ro"), c.description));
  o.add(num(0x03, "Number Of Channels", DataType::Integer16, acc("ro"), c.channels));
  o.add(num(0x04, "RIM Number", DataType::Integer8, acc("ro"), m.rim));
  o.add(num(0x05, "IO card slot", DataType::Integer8, acc("ro"), m.slot));
  o.add(num(0x06, "IO Channel Low", DataType::Integer16, acc("ro"), m.channel_low));
  o.add(num(0x07, "IO Channel High", DataType::Integer16, acc("ro"), m.channel_high));
  // Appendix A order (08 max, 09 min); Table 6 lists them the other way round.
  o.add(with_unit(real(0x08, "Max Voltage", acc("ro"), c.max_voltage), coe::unit::kVolts));
  o.add(with_unit(real(0x09, "Min Voltage", acc("ro"), c.min_voltage), coe::unit::kVolts));
  o.finalize();
  return o;
}

}  // namespace

void add_device_info_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  od.add(device_information(cfg));
  for (const auto& r : cfg.rims) od.add(rim_information(r));

  Object map(0x3000, ObjectCode::Array, "Module Ident Map",
             static_cast<uint16_t>(DataType::Unsigned32));
  map.add(sub0(static_cast<uint8_t>(cfg.modules.size())));
  for (const auto& m : cfg.modules) {
    map.add(num(static_cast<uint8_t>(m.number), "Module " + std::to_string(m.number),
                DataType::Unsigned32, acc("ro"), m.card->module_ident));
  }
  od.add(std::move(map));
  for (const auto& m : cfg.modules) od.add(module_information(m));
}

void attach_device_info_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device) {
  // 0x2000:08 Clock: the system clock plus the offset last written (not kept over a reset).
  Object* o = od.find(0x2000);
  if (o == nullptr) return;
  o->edit_hooks().before_read = [&device](Object& obj, int subindex) {
    if (subindex != 0x08 && subindex != -1) return;
    const std::time_t t = std::time(nullptr) + device.clock_offset_s();
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[80];
    std::snprintf(buf, sizeof buf, "%04d-%02d-%02d %02d:%02d:%02d", tm.tm_year + 1900,
                  tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec);
    obj.set_string(0x08, buf);
  };
  o->edit_hooks().after_write = [&device](Object& obj, int subindex) {
    if (subindex != 0x08 && subindex != -1) return;
    const std::string text = obj.get_string(0x08);
    if (is_valid_clock(text)) device.set_clock_offset_s(parse_clock(text) - std::time(nullptr));
  };
}

}  // namespace rackcat::mdp
