#include "apps/slave_link.hpp"

#include "base/little_endian.hpp"
#include "ecat/al_status_code.hpp"
#include "ecat/registers.hpp"

namespace rackcat::apps {
namespace {

uint16_t u16(std::span<const uint8_t> m, size_t at) {
  return at + 1 < m.size() ? le::get16(&m[at]) : 0;
}
uint32_t u32(std::span<const uint8_t> m, size_t at) {
  return static_cast<uint32_t>(u16(m, at)) | static_cast<uint32_t>(u16(m, at + 2)) << 16;
}

}  // namespace

modules::SlaveLinkFn slave_link(ecat::Segment& segment, ecat::EventLoop& loop) {
  return [&segment, &loop](size_t slave, modules::SlaveLink& out) {
    if (slave >= segment.size()) return;
    out.position = static_cast<uint16_t>(slave);
    const ecat::Esc& esc = segment.slave(slave).esc();
    const auto mem = esc.memory();
    namespace reg = ecat::reg;
    out.station_address = u16(mem, reg::kStationAddress);
    out.al_status = mem[reg::kAlStatus];
    out.al_status_code = u16(mem, reg::kAlStatusCode);
    // al_status_code_name returns a view of a static string literal (NUL-terminated).
    out.al_status_text = ecat::al_status_code_name(out.al_status_code).data();
    out.pd_watchdog_running = (mem[reg::kWatchdogStatusProcessData] & 0x01) != 0;
    out.pd_watchdog_expiries = mem[reg::kWatchdogCounterProcessData];
    uint32_t errors = 0;
    for (size_t a = reg::kRxErrorCounter; a < reg::kRxErrorCounter + 8; ++a) errors += mem[a];
    errors += mem[reg::kProcessingUnitError];
    out.rx_errors = errors;
    out.frames = loop.frames_handled();
    // SII words 0x0008.. (byte 0x10..): vendor ID, product code, revision number.
    const auto sii = esc.eeprom();
    out.vendor_id = u32(sii, 0x10);
    out.product_code = u32(sii, 0x14);
    out.revision = u32(sii, 0x18);
  };
}

}  // namespace rackcat::apps
