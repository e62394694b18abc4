// Temperature slot cards: 8-channel thermocouples K/J/R (guide Table 3 0xF012/0xF013/0xF014,
// 0x6nn4 and the loop resistance 0x5nn4, guide §2.6) and the 4-channel Pt100 RTD (0xF022,
// 0x6nn9). Channel sources give the sensor temperature in °C; the word is
// modules/cards/temperature_scale.hpp (0.1 °C per bit, 0x7FFF open circuit).
#include <algorithm>
#include <cmath>

#include "coe/entry_slot.hpp"
#include "modules/cards/drivers.hpp"
#include "modules/cards/rtd.hpp"
#include "modules/cards/temperature_scale.hpp"
#include "modules/cards/thermocouple.hpp"

namespace rackcat::modules {
namespace {

TcType tc_type(char c) {
  switch (c) {
    case 'J':
      return TcType::J;
    case 'R':
      return TcType::R;
    default:
      return TcType::K;
  }
}

class ThermocoupleDriver final : public CardDriver {
 public:
  ThermocoupleDriver(const mdp::Module& m, coe::ObjectDictionary& od)
      : CardDriver(m, od, m.card->channels, 0),
        obj_(require_object(od, m.index(0x6000, static_cast<uint8_t>(*m.card->input)), m)),
        ohms_(m.card->thermocouple_ohms ? od.find(m.index(0x5000, 4)) : nullptr),
        type_(tc_type(m.card->thermocouple_type)),
        cache_(inputs_.size()) {
    for (size_t i = 0; i < inputs_.size(); ++i) {
      slots_.emplace_back(obj_, static_cast<uint8_t>(i + 1));
      if (ohms_ != nullptr) ohm_slots_.emplace_back(*ohms_, static_cast<uint8_t>(i + 1));
    }
  }

  void write_inputs(double t, double) override {
    for (size_t i = 0; i < inputs_.size(); ++i) {
      InputChannel& in = inputs_[i];
      in.value = sample(i, t);
      // The conversion is a pure function of (temperature, cold junction, open): skip the
      // polynomials while neither changed.
      Cache& c = cache_[i];
      if (!c.valid || c.value != in.value || c.open != in.open || c.cj != cold_junction_c_) {
        const TcMeasurement m = tc_measure(type_, in.value, cold_junction_c_, in.open);
        c.code = static_cast<uint16_t>(m.open_circuit ? kTempOpenCircuit
                                                      : encode_temperature(m.temperature_c));
        c = {true, in.open, in.value, cold_junction_c_, c.code};
      }
      in.code = c.code;
      slots_[i].set(in.code);
      if (ohms_ != nullptr) {
        // 0x5nn4 "Ohms[n]" UINT in ohms; an open loop reads full scale.
        const double r = in.open ? 65535.0 : std::clamp(std::round(in.loop_ohms), 0.0, 65534.0);
        ohm_slots_[i].set(static_cast<uint32_t>(r));
      }
    }
  }

  void clear_inputs() override {
    for (size_t i = 0; i < inputs_.size(); ++i) {
      inputs_[i].code = 0;
      obj_.set_u(static_cast<uint8_t>(i + 1), 0);
      if (ohms_ != nullptr) ohms_->set_u(static_cast<uint8_t>(i + 1), 0);
    }
  }
  const char* input_unit() const override { return "degC"; }
  bool has_sensor_break() const override { return true; }

 protected:
  void put_input_code(size_t i, uint32_t code) override { slots_[i].set(code); }

 public:
  bool set_parameter(std::string_view key, double value) override {
    if (key != "cold_junction_c") return false;
    cold_junction_c_ = value;
    return true;
  }

 private:
  coe::Object& obj_;
  coe::Object* ohms_;
  TcType type_;
  struct Cache {
    bool valid = false;
    bool open = false;
    double value = 0.0, cj = 0.0;
    uint16_t code = 0;
  };
  std::vector<Cache> cache_;
  std::vector<coe::EntrySlot> slots_, ohm_slots_;
  double cold_junction_c_ = 25.0;  // terminal block temperature
};

class RtdDriver final : public CardDriver {
 public:
  RtdDriver(const mdp::Module& m, coe::ObjectDictionary& od)
      : CardDriver(m, od, m.card->channels, 0),
        obj_(require_object(od, m.index(0x6000, static_cast<uint8_t>(*m.card->input)), m)) {
    for (size_t i = 0; i < inputs_.size(); ++i)
      slots_.emplace_back(obj_, static_cast<uint8_t>(i + 1));
  }

  void write_inputs(double t, double) override {
    for (size_t i = 0; i < inputs_.size(); ++i) {
      InputChannel& in = inputs_[i];
      in.value = sample(i, t);
      int16_t code = kTempOpenCircuit;
      if (!in.open) {
        // The card measures the element's resistance and linearises it (Callendar-Van Dusen).
        code = encode_temperature(rtd_temperature(rtd_resistance(in.value)));
      }
      in.code = static_cast<uint16_t>(code);
      slots_[i].set(in.code);
    }
  }
  void clear_inputs() override {
    for (size_t i = 0; i < inputs_.size(); ++i) {
      inputs_[i].code = 0;
      obj_.set_u(static_cast<uint8_t>(i + 1), 0);
    }
  }
  const char* input_unit() const override { return "degC"; }
  bool has_sensor_break() const override { return true; }

 protected:
  void put_input_code(size_t i, uint32_t code) override { slots_[i].set(code); }

 public:
 private:
  coe::Object& obj_;
  std::vector<coe::EntrySlot> slots_;
};

}  // namespace

std::unique_ptr<CardDriver> make_thermocouple_driver(const mdp::Module& m,
                                                     coe::ObjectDictionary& od) {
  return std::make_unique<ThermocoupleDriver>(m, od);
}
std::unique_ptr<CardDriver> make_rtd_driver(const mdp::Module& m, coe::ObjectDictionary& od) {
  return std::make_unique<RtdDriver>(m, od);
}

}  // namespace rackcat::modules
