#include "modules/rack/exception_tree.hpp"

#include <bit>

#include "mdp/card_catalogue.hpp"

namespace rackcat::modules {
namespace {

constexpr uint16_t kActiveSummary = 0xF380;
constexpr uint16_t kActiveMfgWarning = 0xF382;
constexpr uint16_t kActiveMfgError = 0xF384;
constexpr uint16_t kActiveGlobalWarning = 0xF386;
constexpr uint16_t kActiveGlobalError = 0xF388;
constexpr uint16_t kLatchedOffset = 0x10;  // 0xF38x -> 0xF39x
constexpr uint16_t kMaskMfgWarning = 0xF3A2;
constexpr uint16_t kMaskMfgError = 0xF3A4;
constexpr uint16_t kMaskGlobalWarning = 0xF3A6;  // Appendix A (Table 19 says 0xF3A5)
constexpr uint16_t kMaskGlobalWarningAlt = 0xF3A5;
constexpr uint16_t kMaskGlobalError = 0xF3A8;

constexpr uint32_t kSummaryMfgWarning = 1u << 1;  // guide Table 14
constexpr uint32_t kSummaryMfgError = 1u << 3;

void set_if(coe::Object* o, uint8_t sub, uint64_t v) {
  if (o != nullptr && o->entry(sub) != nullptr) o->set_u(sub, v);
}

struct Code {
  uint16_t code;
  uint8_t reg;
};

// Emergency code for a newly active RIM event bit.
Code rim_event_code(unsigned bit) {
  const uint32_t b = 1u << bit;
  using namespace rim_event;
  if (b & (kStateWarning | kStateError))
    return {emcy::kModuleMissing, emcy::kRegGeneric | emcy::kRegCommunication};
  if (b & kCommError) return {emcy::kRimComm, emcy::kRegGeneric | emcy::kRegCommunication};
  if (b & (kSlotFanWarning | kSlotFanError | kSlotFanFailure | kPsFanWarning | kPsFanError |
           kPsFanFailure))
    return {emcy::kFan, emcy::kRegGeneric | emcy::kRegTemperature};
  return {emcy::kSafetyMcu, emcy::kRegGeneric | emcy::kRegManufacturer};
}

}  // namespace

ExceptionTree::ExceptionTree(coe::ObjectDictionary& od, size_t modules, EmergencySink sink)
    : od_(od), sink_(std::move(sink)), modules_(modules + 1) {}

void ExceptionTree::set_rim_state(uint8_t rim, RimState state, bool comm_error) {
  if (rim < 1 || rim > 5) return;
  rims_[rim].state = state;
  rims_[rim].comm_error = comm_error;
}

void ExceptionTree::set_rim_events(uint8_t rim, uint32_t bits) {
  if (rim < 1 || rim > 5) return;
  rims_[rim].other = bits & ~(rim_event::kStateBits | rim_event::kStateWarning |
                              rim_event::kStateError | rim_event::kCommError);
}

void ExceptionTree::set_device_events(uint32_t bits) {
  device_.active = bits;
}

void ExceptionTree::set_module_faults(uint16_t module, uint32_t safe_bits, uint32_t unsafe_bits) {
  if (module == 0 || module >= modules_.size()) return;
  modules_[module].warn.active = safe_bits & 0xFFFF;  // guide Tables 17/18: bits 15..0
  modules_[module].err.active = unsafe_bits & 0xFFFF;
}

uint32_t ExceptionTree::rim_active(const Rim& r) const {
  uint32_t bits = r.other;
  switch (r.state) {
    case RimState::Online:
      break;
    case RimState::Connected:
      bits |= rim_event::kStateWarning;
      break;
    case RimState::Offline:
    case RimState::Error:
      bits |= rim_event::kStateError;
      break;
  }
  if (r.comm_error) bits |= rim_event::kCommError;
  return bits;
}

uint32_t ExceptionTree::rim_event_status(uint8_t rim) const {
  const Rim& r = rims_[rim];
  return ((r.ev.latched | r.ev.active) & ~rim_event::kStateBits) | static_cast<uint32_t>(r.state);
}

uint32_t ExceptionTree::module_warnings(uint16_t m, bool latched) const {
  if (m == 0 || m >= modules_.size()) return 0;
  return latched ? modules_[m].warn.latched : modules_[m].warn.active;
}

uint32_t ExceptionTree::module_errors(uint16_t m, bool latched) const {
  if (m == 0 || m >= modules_.size()) return 0;
  return latched ? modules_[m].err.latched : modules_[m].err.active;
}

uint32_t ExceptionTree::mask_of(uint16_t index, uint8_t sub) const {
  const coe::Object* o = od_.find(index);
  if (o == nullptr || o->entry(sub) == nullptr) return 0xFFFFFFFFu;  // no mask: all reported
  return static_cast<uint32_t>(o->get_u(sub));
}

void ExceptionTree::update() {
  for (uint8_t rr = 1; rr <= 5; ++rr) {
    Rim& r = rims_[rr];
    r.ev.active = rim_active(r);
    r.ev.latched |= r.ev.active;
  }
  device_.latched |= device_.active;
  for (auto& m : modules_) {
    m.warn.latched |= m.warn.active;
    m.err.latched |= m.err.active;
  }
  publish();
  announce();
}

void ExceptionTree::reset_latched() {
  for (uint8_t rr = 1; rr <= 5; ++rr) rims_[rr].ev.latched = rim_active(rims_[rr]);
  device_.latched = device_.active;
  for (auto& m : modules_) {
    m.warn.latched = m.warn.active;
    m.err.latched = m.err.active;
  }
  update();
}

void ExceptionTree::publish() {
  // Event status objects.
  const uint32_t dev_mask = mask_of(0x2000, 0x09);
  if (coe::Object* o = od_.find(0x2000)) set_if(o, 0x0A, device_event_status());
  uint32_t gw[2] = {0, 0}, ge[2] = {0, 0};  // [active, latched]
  const uint32_t dev_bits[2] = {device_.active & dev_mask, device_.latched & dev_mask};
  for (int l = 0; l < 2; ++l) {
    if (dev_bits[l] & device_event::kWarnings) gw[l] |= 1u;
    if (dev_bits[l] & device_event::kErrors) ge[l] |= 1u;
  }
  for (uint8_t rr = 1; rr <= 5; ++rr) {
    coe::Object* info = od_.find(mdp::rim_info_index(rr));
    if (info == nullptr) continue;
    set_if(info, 0x08, rim_event_status(rr));
    const uint32_t mask = mask_of(mdp::rim_info_index(rr), 0x07);
    const uint32_t bits[2] = {rims_[rr].ev.active & mask, rims_[rr].ev.latched & mask};
    for (int l = 0; l < 2; ++l) {
      if (bits[l] & rim_event::kWarnings) gw[l] |= 1u << rr;  // bit rr for RIM rr (Table 19)
      if (bits[l] & rim_event::kErrors) ge[l] |= 1u << rr;    // (Table 20)
    }
  }
  gw_active_ = gw[0];
  gw_latched_ = gw[1];
  ge_active_ = ge[0];
  ge_latched_ = ge[1];

  const uint16_t gw_mask_index =
      od_.find(kMaskGlobalWarning) ? kMaskGlobalWarning : kMaskGlobalWarningAlt;
  const uint32_t gw_mask = mask_of(gw_mask_index, 1);
  const uint32_t ge_mask = mask_of(kMaskGlobalError, 1);
  uint32_t summary[2] = {0, 0};
  for (int l = 0; l < 2; ++l) {
    const uint16_t off = l ? kLatchedOffset : 0;
    set_if(od_.find(kActiveGlobalWarning + off), 1, gw[l]);
    set_if(od_.find(kActiveGlobalError + off), 1, ge[l]);
    if (gw[l] & gw_mask) summary[l] |= kSummaryMfgWarning;
    if (ge[l] & ge_mask) summary[l] |= kSummaryMfgError;
    coe::Object* w = od_.find(kActiveMfgWarning + off);
    coe::Object* e = od_.find(kActiveMfgError + off);
    for (size_t n = 1; n < modules_.size() && n <= 255; ++n) {
      const auto sub = static_cast<uint8_t>(n);
      const uint32_t wb = l ? modules_[n].warn.latched : modules_[n].warn.active;
      const uint32_t eb = l ? modules_[n].err.latched : modules_[n].err.active;
      set_if(w, sub, wb);
      set_if(e, sub, eb);
      if (wb & mask_of(kMaskMfgWarning, sub)) summary[l] |= kSummaryMfgWarning;
      if (eb & mask_of(kMaskMfgError, sub)) summary[l] |= kSummaryMfgError;
    }
    if (coe::Object* o = od_.find(kActiveSummary + off)) {
      set_if(o, o->code() == coe::ObjectCode::Var ? 0 : 1, summary[l]);
    }
  }
  summary_active_ = summary[0];
  summary_latched_ = summary[1];
}

void ExceptionTree::announce() {
  if (!sink_.raise) return;
  auto send = [this](uint16_t code, uint8_t reg, uint8_t rim, uint16_t module, uint8_t bit,
                     uint16_t channels) {
    const uint8_t data[5] = {rim, static_cast<uint8_t>(module), bit, static_cast<uint8_t>(channels),
                             static_cast<uint8_t>(channels >> 8)};
    sink_.raise(code, reg, data);
  };
  const uint8_t remaining = (summary_active_ & kSummaryMfgError) ? emcy::kRegGeneric : 0;
  for (uint8_t rr = 1; rr <= 5; ++rr) {
    Events& ev = rims_[rr].ev;
    const uint32_t changed = (ev.active ^ ev.reported) & ~rim_event::kStateBits;
    for (unsigned bit = 2; bit < 32; ++bit) {
      if (!(changed & (1u << bit))) continue;
      if (ev.active & (1u << bit)) {
        const Code c = rim_event_code(bit);
        send(c.code, c.reg, rr, 0, static_cast<uint8_t>(bit), 0);
      } else {
        send(emcy::kNoError, remaining, rr, 0, static_cast<uint8_t>(bit), 0);
      }
    }
    ev.reported = ev.active;
  }
  const uint32_t dchanged = device_.active ^ device_.reported;
  for (unsigned bit = 0; bit < 32; ++bit) {
    if (!(dchanged & (1u << bit))) continue;
    if (device_.active & (1u << bit)) {
      send(emcy::kFan, emcy::kRegGeneric | emcy::kRegTemperature, 0, 0, static_cast<uint8_t>(bit),
           0);
    } else {
      send(emcy::kNoError, remaining, 0, 0, static_cast<uint8_t>(bit), 0);
    }
  }
  device_.reported = device_.active;
  for (size_t n = 1; n < modules_.size(); ++n) {
    ModuleFaults& m = modules_[n];
    const auto mod = static_cast<uint16_t>(n);
    const uint32_t wrise = m.warn.active & ~m.warn.reported;
    const uint32_t erise = m.err.active & ~m.err.reported;
    const uint32_t fall = (m.warn.reported & ~m.warn.active) | (m.err.reported & ~m.err.active);
    // One Emergency (and 0x10F3 message) per channel, so each names its channel.
    for (unsigned ch = 0; ch < 16; ++ch) {
      const uint32_t b = 1u << ch;
      const auto mask = static_cast<uint16_t>(b);
      if (wrise & b) {
        send(emcy::kSafeWiring, emcy::kRegGeneric | emcy::kRegCurrent | emcy::kRegManufacturer, 0,
             mod, 0xFF, mask);
      }
      if (erise & b) {
        send(emcy::kUnsafeWiring, emcy::kRegGeneric | emcy::kRegCurrent | emcy::kRegManufacturer, 0,
             mod, 0xFF, mask);
      }
      if (fall & b) send(emcy::kNoError, remaining, 0, mod, 0xFF, mask);
    }
    m.warn.reported = m.warn.active;
    m.err.reported = m.err.active;
  }
}

}  // namespace rackcat::modules
