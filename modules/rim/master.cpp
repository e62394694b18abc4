#include "modules/rim/master.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "coe/bits.hpp"
#include "modules/canopen/emcy.hpp"

namespace rackcat::modules::canopen {

namespace {

// What the control module reads from a RIM before starting it, in order.
struct Check {
  uint16_t index;
  uint8_t subindex;
  const char* what;
};
constexpr Check kChecks[] = {
    {0x1018, 1, "vendor ID"},
    {0x1018, 2, "product code"},
    {kCardListIndex, 0, "card list"},
};

// CiA 301 Table 21: 0x81xx = CAN communication errors (overrun, error passive, heartbeat,
// bus-off recovered); 0x7500 is the rack's own "RIM communication error" (modules/rack/events.hpp).
bool is_comm_error(uint16_t code) {
  return (code & 0xFF00) == 0x8100 || code == emcy::kRimComm;
}

std::string hex_bytes(const std::vector<uint8_t>& b) {
  std::string s;
  for (uint8_t x : b) s += fmt::format("{:02x}", x);
  return s;
}

}  // namespace

RimMaster::RimMaster(const mdp::RackConfig& rack, CanBus& bus, RimMasterOptions options,
                     std::vector<uint8_t> rims)
    : bus_(bus), options_(options), own_heartbeat_(options.heartbeat_period_us) {
  if (rims.empty()) {
    for (const mdp::Rim& r : rack.rims) rims.push_back(r.number);
  }
  for (uint8_t r : rims) {
    Link l;
    l.profile = rim_profile(rack, r);
    l.sdo = std::make_unique<SdoClient>(r, options_.sdo_timeout_us);
    l.inputs.assign(l.profile.inputs.size(), 0.0);
    l.outputs.assign(l.profile.outputs.size(), nullptr);
    l.tx.assign(l.profile.tpdo_count() * kPdoBytes, 0);
    l.rx.assign(l.profile.rpdo_count() * kPdoBytes, 0);
    links_.emplace(r, std::move(l));
    heartbeat_.watch(r, options_.heartbeat_timeout_us);
  }
}

RimMaster::Link* RimMaster::link(uint8_t rim) {
  auto it = links_.find(rim);
  return it == links_.end() ? nullptr : &it->second;
}
const RimMaster::Link* RimMaster::link(uint8_t rim) const {
  auto it = links_.find(rim);
  return it == links_.end() ? nullptr : &it->second;
}

std::vector<uint8_t> RimMaster::rims() const {
  std::vector<uint8_t> out;
  for (const auto& [r, l] : links_) out.push_back(r);
  return out;
}

void RimMaster::step(Micros now) {
  CanFrame f;
  while (bus_.receive(f)) {
    handle(f, now);
  }
  if (own_heartbeat_.poll(now, kControlModuleNode, NmtState::Operational, f)) {
    bus_.send(f);
  }
  while (auto lost = heartbeat_.poll_lost(now)) {
    Link& l = *link(*lost);
    l.phase = Phase::Absent;
    l.sdo_failures = 0;
    l.reason = "heartbeat lost";
    l.lost = true;
    std::fill(l.inputs.begin(), l.inputs.end(), 0.0);
  }
  for (auto& [r, l] : links_) {
    CanFrame abort;
    if (l.sdo->poll(now, abort)) {
      bus_.send(abort);
      sdo_failed(l, now, true);
    }
    const auto* hb = heartbeat_.node(r);
    if (hb->alive && (l.phase == Phase::Failed) && now >= l.retry_at) {
      start_check(l, now);
    }
    evaluate(l);
    if (l.state == RimState::Online && now >= l.next_rpdo && l.profile.rpdo_count()) {
      send_rpdos(l);
      l.next_rpdo += options_.pdo_period_us;
      if (l.next_rpdo <= now) l.next_rpdo = now + options_.pdo_period_us;
    }
  }
}

void RimMaster::handle(const CanFrame& f, Micros now) {
  switch (heartbeat_.on_frame(f, now)) {
    case HeartbeatConsumer::Event::BootUp: {
      // A (re)booted RIM is checked from scratch.
      Link& l = *link(cob::node(f.id));
      l.comm_emcy = false;
      start_check(l, now);
      return;
    }
    case HeartbeatConsumer::Event::StateChanged: {
      Link& l = *link(cob::node(f.id));
      if (l.phase == Phase::Absent) {
        start_check(l, now);  // joined without a boot-up we saw (we started after it)
      }
      return;
    }
    case HeartbeatConsumer::Event::None:
      break;
  }
  if (f.id >= cob::kSdoTx && f.id < cob::kSdoTx + 0x80) {
    if (Link* l = link(cob::node(f.id))) {
      CanFrame next;
      bool has_next = false;
      if (l->sdo->on_frame(f, now, next, has_next)) {
        if (has_next) bus_.send(next);
        switch (l->sdo->status()) {
          case SdoClient::Status::Done:
            check_done(*l, now);
            break;
          case SdoClient::Status::Aborted:
            sdo_failed(*l, now, false);
            break;
          default:
            break;
        }
      }
    }
    return;
  }
  if (auto e = decode_emcy(f)) {
    if (Link* l = link(cob::node(f.id))) {
      if (is_comm_error(e->error_code)) {
        l->comm_emcy = true;
      } else if (e->error_code == 0x0000) {
        l->comm_emcy = false;  // error reset / no error (CiA 301 Table 21)
      }
      if (on_emergency_) on_emergency_(cob::node(f.id), *e);
    }
    return;
  }
  for (auto& [r, l] : links_) {
    const int k = pdo_number(true, f.id, r);
    if (k < 0 || static_cast<size_t>(k) >= l.profile.tpdo_count()) continue;
    const size_t at = static_cast<size_t>(k) * kPdoBytes;
    const size_t n = std::min<size_t>(f.len, l.profile.tx_bytes - at);
    std::copy_n(f.data.begin(), n, l.tx.begin() + static_cast<ptrdiff_t>(at));
    for (size_t i = 0; i < l.profile.inputs.size(); ++i) {
      const RimChannel& c = l.profile.inputs[i];
      if (c.offset >= at && c.offset < at + n) l.inputs[i] = get_channel(l.tx, c);
    }
    l.last_input = now;
    return;
  }
}

void RimMaster::start_check(Link& l, Micros now) {
  l.phase = Phase::Checking;
  l.lost = false;
  l.check_step = 0;
  l.reason = "checking identity and card list";
  next_check(l, now);
}

void RimMaster::next_check(Link& l, Micros now) {
  while (l.check_step < std::size(kChecks) && kChecks[l.check_step].index == kCardListIndex &&
         l.profile.card_list.empty()) {
    ++l.check_step;  // an empty RIM has no card list to compare
  }
  if (l.check_step == std::size(kChecks)) {
    l.phase = Phase::Verified;
    l.sdo_failures = 0;
    l.reason = "";
    bus_.send(nmt_frame(NmtCommand::Start, l.profile.rim));
    return;
  }
  const Check& c = kChecks[l.check_step];
  bus_.send(l.sdo->start_upload(c.index, c.subindex, now));
}

void RimMaster::check_done(Link& l, Micros now) {
  if (l.phase != Phase::Checking) return;
  const Check& c = kChecks[l.check_step];
  const std::vector<uint8_t>& got = l.sdo->data();
  l.sdo_failures = 0;
  bool ok = true;
  std::string expected, actual;
  if (c.index == 0x1018) {
    const uint32_t want =
        c.subindex == 1 ? l.profile.identity.vendor_id : l.profile.identity.product_code;
    const uint32_t have = got.size() == 4 ? le::get32(got.data()) : ~want;
    ok = have == want;
    expected = fmt::format("0x{:08x}", want);
    actual = got.size() == 4 ? fmt::format("0x{:08x}", have) : "a value of wrong size";
  } else {
    ok = got == l.profile.card_list;
    expected = hex_bytes(l.profile.card_list);
    actual = hex_bytes(got);
  }
  if (!ok) {
    l.phase = Phase::Mismatch;
    l.reason = fmt::format("{} mismatch: rack file {}, RIM {}", c.what, expected, actual);
    return;
  }
  ++l.check_step;
  next_check(l, now);
}

void RimMaster::sdo_failed(Link& l, Micros now, bool timeout) {
  if (l.phase != Phase::Checking) return;
  const Check& c = kChecks[l.check_step];
  if (!timeout) {
    // The RIM answered, but has no such object: not a RIM of this rack (CONNECTED).
    l.phase = Phase::Mismatch;
    l.reason =
        fmt::format("{} (0x{:04x}:{:02x}) aborted: 0x{:08x} {}", c.what, c.index, c.subindex,
                    static_cast<uint32_t>(l.sdo->abort_code()), coe::describe(l.sdo->abort_code()));
    return;
  }
  ++l.sdo_failures;
  l.phase = Phase::Failed;
  l.retry_at = now + options_.sdo_retry_us;
  l.reason = fmt::format("{} SDO timeout(s) reading the {}", l.sdo_failures, c.what);
}

void RimMaster::evaluate(Link& l) {
  const auto* hb = heartbeat_.node(l.profile.rim);
  const BusStatus& bus = bus_.status();
  RimState s;
  bool comm_error = false;
  // A communication error on the bus, or one the node reports (repeated SDO failures, a
  // communication Emergency while alive).
  if (bus.bus_off || bus.error_passive || l.sdo_failures >= options_.max_sdo_failures ||
      (hb->alive && l.comm_emcy)) {
    s = RimState::Error;
    comm_error = true;
  } else if (!hb->alive) {
    s = RimState::Offline;
    comm_error = l.lost;
  } else if (l.phase == Phase::Verified && hb->state == NmtState::Operational) {
    s = RimState::Online;
  } else {
    s = RimState::Connected;
  }
  if (s != l.state || comm_error != l.comm_error) {
    l.state = s;
    l.comm_error = comm_error;
    if (s == RimState::Online) l.next_rpdo = 0;
    if (on_state_) on_state_(l.profile.rim, s, comm_error);
  }
}

void RimMaster::send_rpdos(Link& l) {
  for (size_t i = 0; i < l.profile.outputs.size(); ++i) {
    put_channel(l.rx, l.profile.outputs[i], l.outputs[i] ? *l.outputs[i] : 0.0);
  }
  for (size_t k = 0; k < l.profile.rpdo_count(); ++k) {
    const size_t at = k * kPdoBytes;
    const size_t n = std::min(kPdoBytes, l.profile.rx_bytes - at);
    bus_.send(CanFrame::make(pdo_cob_id(false, k, l.profile.rim), std::span(l.rx).subspan(at, n)));
  }
}

RimState RimMaster::state(uint8_t rim) const {
  const Link* l = link(rim);
  return l ? l->state : RimState::Offline;
}

const std::string& RimMaster::reason(uint8_t rim) const {
  static const std::string unknown = "not a RIM of this link";
  const Link* l = link(rim);
  return l ? l->reason : unknown;
}

const double* RimMaster::input_ptr(uint8_t rim, uint8_t slot, uint8_t channel) const {
  const Link* l = link(rim);
  if (!l) return nullptr;
  for (size_t i = 0; i < l->profile.inputs.size(); ++i) {
    if (l->profile.inputs[i].slot == slot && l->profile.inputs[i].channel == channel) {
      return &l->inputs[i];
    }
  }
  return nullptr;
}

bool RimMaster::bind_output(uint8_t rim, uint8_t slot, uint8_t channel, const double* value) {
  Link* l = link(rim);
  if (!l) return false;
  for (size_t i = 0; i < l->profile.outputs.size(); ++i) {
    if (l->profile.outputs[i].slot == slot && l->profile.outputs[i].channel == channel) {
      l->outputs[i] = value;
      return true;
    }
  }
  return false;
}

Micros RimMaster::last_input_time(uint8_t rim) const {
  const Link* l = link(rim);
  return l ? l->last_input : -1;
}

const RimProfile* RimMaster::profile(uint8_t rim) const {
  const Link* l = link(rim);
  return l ? &l->profile : nullptr;
}

}  // namespace rackcat::modules::canopen
