#include "modules/cards/thermocouple.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>

namespace rackcat::modules {
namespace {

// One polynomial piece valid on [lo, hi] of its argument, coefficients c0..cn.
struct Piece {
  double lo;
  double hi;
  std::span<const double> c;
};

double horner(std::span<const double> c, double x) {
  double y = 0.0;
  for (size_t i = c.size(); i-- > 0;) y = y * x + c[i];
  return y;
}

// ---- Reference functions E(t), NIST Monograph 175 / ITS-90 database (°C -> mV) ----------

// Type K, -270 °C .. 0 °C.
constexpr std::array<double, 11> kK_neg{
    0.000000000000E+00,  0.394501280250E-01,  0.236223735980E-04,  -0.328589067840E-06,
    -0.499048287770E-08, -0.675090591730E-10, -0.574103274280E-12, -0.310888728940E-14,
    -0.104516093650E-16, -0.198892668780E-19, -0.163226974860E-22};
// Type K, 0 °C .. 1372 °C; plus a0 * exp(a1 * (t - a2)^2).
constexpr std::array<double, 10> kK_pos{
    -0.176004136860E-01, 0.389212049750E-01,  0.185587700320E-04, -0.994575928740E-07,
    0.318409457190E-09,  -0.560728448890E-12, 0.560750590590E-15, -0.320207200030E-18,
    0.971511471520E-22,  -0.121047212750E-25};
constexpr double kK_a0 = 0.118597600000E+00;
constexpr double kK_a1 = -0.118343200000E-03;
constexpr double kK_a2 = 0.126968600000E+03;

// Type J, -210 °C .. 760 °C and 760 °C .. 1200 °C.
constexpr std::array<double, 9> kJ_lo{0.000000000000E+00,  0.503811878150E-01,  0.304758369300E-04,
                                      -0.856810657200E-07, 0.132281952950E-09,  -0.170529583370E-12,
                                      0.209480906970E-15,  -0.125383953360E-18, 0.156317256970E-22};
constexpr std::array<double, 6> kJ_hi{0.296456256810E+03, -0.149761277860E+01,
                                      0.317871039240E-02, -0.318476867010E-05,
                                      0.157208190040E-08, -0.306913690560E-12};

// Type R, -50 .. 1064.18 °C, 1064.18 .. 1664.5 °C, 1664.5 .. 1768.1 °C.
constexpr std::array<double, 10> kR_lo{
    0.000000000000E+00, 0.528961729765E-02,  0.139166589782E-04, -0.238855693017E-07,
    0.356916001063E-10, -0.462347666298E-13, 0.500777441034E-16, -0.373105886191E-19,
    0.157716482367E-22, -0.281038625251E-26};
constexpr std::array<double, 6> kR_mid{0.295157925316E+01, -0.252061251332E-02,
                                       0.159564501865E-04, -0.764085947576E-08,
                                       0.205305291024E-11, -0.293359668173E-15};
constexpr std::array<double, 5> kR_hi{0.152232118209E+03, -0.268819888545E+00, 0.171280280471E-03,
                                      -0.345895706453E-07, -0.934633971046E-14};

// ---- Inverse functions t(E), NIST Monograph 175 / ITS-90 database (mV -> °C) ------------

constexpr std::array<double, 9> kK_inv_neg{0.0,
                                           2.5173462E+01,
                                           -1.1662878E+00,
                                           -1.0833638E+00,
                                           -8.9773540E-01,
                                           -3.7342377E-01,
                                           -8.6632643E-02,
                                           -1.0450598E-02,
                                           -5.1920577E-04};
constexpr std::array<double, 10> kK_inv_mid{
    0.0,           2.508355E+01, 7.860106E-02,  -2.503131E-01, 8.315270E-02,
    -1.228034E-02, 9.804036E-04, -4.413030E-05, 1.057734E-06,  -1.052755E-08};
constexpr std::array<double, 7> kK_inv_hi{-1.318058E+02, 4.830222E+01, -1.646031E+00, 5.464731E-02,
                                          -9.650715E-04, 8.802193E-06, -3.110810E-08};

constexpr std::array<double, 9> kJ_inv_neg{0.0,
                                           1.9528268E+01,
                                           -1.2286185E+00,
                                           -1.0752178E+00,
                                           -5.9086933E-01,
                                           -1.7256713E-01,
                                           -2.8131513E-02,
                                           -2.3963370E-03,
                                           -8.3823321E-05};
constexpr std::array<double, 8> kJ_inv_mid{0.0,           1.978425E+01,  -2.001204E-01,
                                           1.036969E-02,  -2.549687E-04, 3.585153E-06,
                                           -5.344285E-08, 5.099890E-10};
constexpr std::array<double, 6> kJ_inv_hi{-3.11358187E+03, 3.00543684E+02,  -9.94773230E+00,
                                          1.70276630E-01,  -1.43033468E-03, 4.73886084E-06};

constexpr std::array<double, 11> kR_inv_a{
    0.0,           1.8891380E+02,  -9.3835290E+01, 1.3068619E+02,  -2.2703580E+02,
    3.5145659E+02, -3.8953900E+02, 2.8239471E+02,  -1.2607281E+02, 3.1353611E+01,
    -3.3187769E+00};
constexpr std::array<double, 10> kR_inv_b{
    1.334584505E+01, 1.472644573E+02,  -1.844024844E+01, 4.031129726E+00,  -6.249428360E-01,
    6.468412046E-02, -4.458750426E-03, 1.994710149E-04,  -5.313401790E-06, 6.481976217E-08};
constexpr std::array<double, 6> kR_inv_c{-8.199599416E+01, 1.553962042E+02,  -8.342197663E+00,
                                         4.279433549E-01,  -1.191577910E-02, 1.492290091E-04};
constexpr std::array<double, 5> kR_inv_d{3.406177836E+04, -7.023729171E+03, 5.582903813E+02,
                                         -1.952394635E+01, 2.560740231E-01};

// EMF breakpoints of the inverse subranges (mV), from the same tables.
constexpr double kK_e_500 = 20.644;
constexpr double kJ_e_760 = 42.919;
constexpr double kR_e_250 = 1.923;
constexpr double kR_e_1064 = 11.361;
constexpr double kR_e_1664 = 19.739;

// Pieces are ordered; the first piece whose upper end is >= x applies, the outer pieces
// extend past their ends (the callers clamp to the function's range).
double evaluate(std::span<const Piece> pieces, double x) {
  for (const Piece& p : pieces) {
    if (x <= p.hi) return horner(p.c, x);
  }
  return horner(pieces.back().c, x);
}

const std::array<Piece, 2> kJ_ref{{{-210.0, 760.0, kJ_lo}, {760.0, 1200.0, kJ_hi}}};
const std::array<Piece, 3> kR_ref{
    {{-50.0, 1064.18, kR_lo}, {1064.18, 1664.5, kR_mid}, {1664.5, 1768.1, kR_hi}}};

const std::array<Piece, 3> kK_inv{
    {{-5.891, 0.0, kK_inv_neg}, {0.0, kK_e_500, kK_inv_mid}, {kK_e_500, 54.886, kK_inv_hi}}};
const std::array<Piece, 3> kJ_inv{
    {{-8.095, 0.0, kJ_inv_neg}, {0.0, kJ_e_760, kJ_inv_mid}, {kJ_e_760, 69.553, kJ_inv_hi}}};
// The NIST R subranges 250..1200 °C and 1064..1664.5 °C overlap; switch at 1064 °C.
const std::array<Piece, 4> kR_inv{{{-0.226, kR_e_250, kR_inv_a},
                                   {kR_e_250, kR_e_1064, kR_inv_b},
                                   {kR_e_1064, kR_e_1664, kR_inv_c},
                                   {kR_e_1664, 21.103, kR_inv_d}}};

}  // namespace

TcRange tc_reference_range(TcType type) {
  switch (type) {
    case TcType::K:
      return {-270.0, 1372.0};
    case TcType::J:
      return {-210.0, 1200.0};
    case TcType::R:
      return {-50.0, 1768.1};
  }
  return {0.0, 0.0};
}

TcRange tc_inverse_range(TcType type) {
  switch (type) {
    case TcType::K:
      return {-200.0, 1372.0};
    case TcType::J:
      return {-210.0, 1200.0};
    case TcType::R:
      return {-50.0, 1768.1};
  }
  return {0.0, 0.0};
}

double tc_emf_mv(TcType type, double t) {
  const TcRange r = tc_reference_range(type);
  t = std::clamp(t, r.min_c, r.max_c);
  switch (type) {
    case TcType::K:
      if (t < 0.0) return horner(kK_neg, t);
      return horner(kK_pos, t) + kK_a0 * std::exp(kK_a1 * (t - kK_a2) * (t - kK_a2));
    case TcType::J:
      return evaluate(kJ_ref, t);
    case TcType::R:
      return evaluate(kR_ref, t);
  }
  return 0.0;
}

double tc_temperature_c(TcType type, double e) {
  // Clamp to the EMF of the range ends themselves (the tabulated 1 µV-rounded breakpoints
  // would cut off up to 0.15 °C at the ends).
  const TcRange r = tc_inverse_range(type);
  e = std::clamp(e, tc_emf_mv(type, r.min_c), tc_emf_mv(type, r.max_c));
  switch (type) {
    case TcType::K:
      return evaluate(kK_inv, e);
    case TcType::J:
      return evaluate(kJ_inv, e);
    case TcType::R:
      return evaluate(kR_inv, e);
  }
  return 0.0;
}

TcMeasurement tc_measure(TcType type, double t_hot_c, double t_cj_c, bool open) {
  TcMeasurement m;
  if (open) {
    m.open_circuit = true;
    return m;
  }
  const double e_cj = tc_emf_mv(type, t_cj_c);
  m.loop_emf_mv = tc_emf_mv(type, t_hot_c) - e_cj;
  m.temperature_c = tc_temperature_c(type, m.loop_emf_mv + e_cj);
  return m;
}

}  // namespace rackcat::modules
