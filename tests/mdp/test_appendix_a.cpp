// Every object of the guide's Appendix A against a table transcribed from it: presence, data
// type, bit size, access, PDO mapping flag and default. "nn" rows apply to every module whose
// card has the object, "rr" rows to every RIM. Deviations decided in docs/MDP.md are marked
// "decision:" and tested as decided.
#include <gtest/gtest.h>

#include <optional>
#include <set>
#include <string>

#include "coe/access.hpp"
#include "mdp/device.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/sync_manager_layout.hpp"

namespace rackcat::mdp {
namespace {

using coe::DataType;
constexpr DataType U8 = DataType::Unsigned8;
constexpr DataType U16 = DataType::Unsigned16;
constexpr DataType U32 = DataType::Unsigned32;
constexpr DataType U64 = DataType::Unsigned64;
constexpr DataType I8 = DataType::Integer8;
constexpr DataType I16 = DataType::Integer16;
constexpr DataType R32 = DataType::Real32;
constexpr DataType STR = DataType::VisibleString;
constexpr DataType OCT = DataType::OctetString;
constexpr DataType B1 = DataType::Bit1;
constexpr DataType B4 = DataType::Bit4;

struct Row {
  const char* index;  // "0x2000", "0x2rr1", "0x3nn1"
  int sub_first;
  int sub_last;
  uint16_t type;  // DataType or enum index
  uint16_t bits;
  const char* access;  // guide notation
  const char* pdo;     // "", "tx", "rx", "rx,tx"
  std::optional<uint64_t> def;
};
constexpr uint16_t T(DataType t) {
  return static_cast<uint16_t>(t);
}

// Appendix A, object by object. Strings: bits = 8 x the guide's STRING(n).
const Row kAppendixA[] = {
    {"0x100B", 0, 0, T(STR), 48, "ro", "", std::nullopt},
    {"0x1C12", 1, 255, T(U16), 16, "ro,wr_preop", "", std::nullopt},
    {"0x1C13", 1, 255, T(U16), 16, "ro,wr_preop", "", std::nullopt},
    {"0x2000", 1, 1, T(STR), 512, "ro", "", std::nullopt},
    {"0x2000", 2, 2, T(STR), 32, "ro", "", std::nullopt},
    {"0x2000", 3, 3, T(STR), 192, "ro", "", std::nullopt},
    {"0x2000", 4, 4, T(STR), 128, "ro,wr_preop", "", std::nullopt},
    {"0x2000", 5, 5, T(STR), 192, "ro", "", std::nullopt},
    {"0x2000", 6, 6, T(STR), 192, "ro", "", std::nullopt},
    {"0x2000", 7, 7, T(STR), 128, "ro", "", std::nullopt},
    {"0x2000", 8, 8, T(STR), 256, "ro,wr_preop", "", std::nullopt},
    {"0x2000", 9, 9, T(U32), 32, "rw", "", std::nullopt},
    {"0x2000", 0x0A, 0x0A, T(U32), 32, "ro", "tx", std::nullopt},
    {"0x2000", 0x0B, 0x0B, T(B1), 1, "ro,wr_preop", "", 1},
    {"0x2000", 0x0D, 0x0F, T(R32), 32, "ro", "tx", std::nullopt},
    {"0x2rr1", 1, 1, T(STR), 512, "ro", "", std::nullopt},
    {"0x2rr1", 2, 2, T(STR), 32, "ro", "", std::nullopt},
    {"0x2rr1", 3, 4, T(STR), 192, "ro", "", std::nullopt},
    {"0x2rr1", 5, 5, T(STR), 256, "ro", "", std::nullopt},
    {"0x2rr1", 6, 6, T(OCT), 384, "ro", "", std::nullopt},  // decision: ARRAY [0..23] OF UINT
    {"0x2rr1", 7, 7, T(U32), 32, "rw", "", std::nullopt},
    {"0x2rr1", 8, 8, T(U32), 32, "ro", "tx", std::nullopt},
    {"0x2rr1", 0x0A, 0x0D, T(R32), 32, "ro", "tx", std::nullopt},
    {"0x3000", 1, 0, T(U32), 32, "ro", "", std::nullopt},  // 1..modules
    {"0x3nn1", 1, 1, T(STR), 64, "ro", "", std::nullopt},
    {"0x3nn1", 2, 2, T(STR), 256, "ro", "", std::nullopt},
    {"0x3nn1", 3, 3, T(I16), 16, "ro", "", std::nullopt},
    {"0x3nn1", 4, 5, T(I8), 8, "ro", "", std::nullopt},
    {"0x3nn1", 6, 7, T(I16), 16, "ro", "", std::nullopt},
    {"0x3nn1", 8, 9, T(R32), 32, "ro", "", std::nullopt},
    {"0x4nn0", 1, 3, T(U16), 16, "ro,wr_op", "", 0},
    {"0x4nn1", 1, 3, T(U8), 8, "ro,wr_op", "", 0},
    {"0x4nn2", 1, 2, T(U8), 8, "ro,wr_op", "", 0},
    {"0x4nn2", 3, 0x0A, T(U16), 16, "ro,wr_op", "", 0},
    {"0x4nn3", 1, 2, T(U16), 16, "ro,wr_op", "", 0},
    {"0x4nn3", 3, 0x12, T(U16), 16, "ro,wr_op", "", 0},
    {"0x5nn4", 1, 8, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x5nn6", 1, 4, T(U8), 8, "rw", "", std::nullopt},
    {"0x5nn6", 5, 8, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x5nn6", 9, 0x0C, T(U8), 8, "ro", "tx", std::nullopt},
    {"0x5nn7", 1, 255, T(U8), 8, "rw", "", std::nullopt},
    {"0x5nn8", 1, 255, T(U8), 8, "rw", "", std::nullopt},
    {"0x5nn9", 1, 255, T(U8), 8, "rw", "", std::nullopt},
    {"0x5nnA", 1, 255, T(U8), 8, "rw", "", std::nullopt},
    {"0x5nnB", 1, 255, T(U8), 8, "ro", "", std::nullopt},  // decision: Rx data read-only
    {"0x5nnC", 1, 255, T(U8), 8, "ro", "", std::nullopt},
    {"0x5nnD", 1, 255, T(U8), 8, "ro", "", std::nullopt},
    {"0x5nnE", 1, 255, T(U8), 8, "ro", "", std::nullopt},
    {"0x6nn0", 1, 1, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x6nn1", 1, 1, T(U8), 8, "ro", "tx", std::nullopt},  // BYTE
    {"0x6nn2", 1, 8, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x6nn3", 1, 16, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x6nn4", 1, 8, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x6nn5", 1, 1, T(OCT), 128, "ro", "tx", std::nullopt},  // ARRAY [0..7] OF UINT
    {"0x6nn6", 1, 1, T(OCT), 64, "ro", "tx", std::nullopt},   // ARRAY [0..7] OF BYTE
    {"0x6nn7", 1, 16, T(OCT), 128, "ro", "tx", std::nullopt},
    {"0x6nn8", 1, 8, T(OCT), 128, "ro", "tx", std::nullopt},
    {"0x6nn9", 1, 4, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x6nnA", 1, 4, T(U16), 16, "ro", "tx", std::nullopt},
    {"0x6nnB", 1, 1, T(B4), 4, "ro", "tx", std::nullopt},
    {"0x6nnC", 1, 2, T(U8), 8, "ro", "tx", std::nullopt},
    {"0x7nn0", 1, 1, T(U16), 16, "rw", "rx", std::nullopt},
    {"0x7nn1", 1, 1, T(U8), 8, "rw", "rx", std::nullopt},
    {"0x7nn2", 1, 8, T(U16), 16, "rw", "rx", std::nullopt},
    {"0x7nn3", 1, 16, T(U16), 16, "rw", "rx", std::nullopt},
    {"0x7nnB", 1, 1, T(B4), 4, "rw", "rx", std::nullopt},
    {"0xF000", 1, 1, T(U16), 16, "ro", "tx", 0x10},
    {"0xF000", 2, 2, T(U16), 16, "ro", "tx", 0xFF},
    {"0xF002", 1, 1, T(OCT), 32, "ro,wr_preop", "", std::nullopt},
    {"0xF002", 2, 2, T(U8), 8, "ro", "", std::nullopt},
    {"0xF010", 1, 0, T(U32), 32, "ro", "", std::nullopt},
    {"0xF030", 1, 255, T(U32), 32, "ro,wr_preop", "", std::nullopt},
    {"0xF050", 1, 0, T(U32), 32, "ro", "", std::nullopt},
    {"0xF380", 0, 0, T(U8), 8, "ro", "tx", 0},
    {"0xF381", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF382", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF383", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF384", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF386", 1, 1, T(U32), 32, "ro", "tx", 0},
    {"0xF388", 1, 1, T(U32), 32, "ro", "tx", 0},
    {"0xF390", 0, 0, T(U8), 8, "ro", "tx", 0},
    {"0xF391", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF392", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF393", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF394", 1, 0, T(U32), 32, "ro", "tx", 0},
    {"0xF396", 1, 1, T(U32), 32, "ro", "tx", 0},
    {"0xF398", 1, 1, T(U32), 32, "ro", "tx", 0},
    {"0xF3A1", 1, 0, T(U32), 32, "rw", "", 0xFFFFFFFF},
    {"0xF3A2", 1, 0, T(U32), 32, "rw", "", 0xFFFFFFFF},
    {"0xF3A3", 1, 0, T(U32), 32, "rw", "", 0xFFFFFFFF},
    {"0xF3A4", 1, 0, T(U32), 32, "rw", "", 0xFFFFFFFF},
    {"0xF3A6", 1, 1, T(U32), 32, "rw", "", 0xFFFFFFFF},
    {"0xF3A8", 1, 1, T(U32), 32, "rw", "", 0xFFFFFFFF},
    {"0xF6F0", 1, 0, T(U32), 32, "ro", "tx", std::nullopt},
    {"0xF6F2", 1, 0, T(U64), 64, "ro", "tx", std::nullopt},
    {"0xF9F0", 0, 0, T(STR), 192, "ro", "", std::nullopt},  // decision: STRING(24), not (16)
    {"0xF9F1", 1, 1, T(U32), 32, "ro", "", 0x02},
    {"0xF9F2", 1, 0, T(U32), 32, "ro", "", std::nullopt},
    {"0xF9F3", 0, 0, T(STR), 128, "ro", "", std::nullopt},
    {"0xF9F4", 1, 0, T(U32), 32, "ro", "", 0x412F4E},
    {"0xF9F5", 1, 0, T(U8), 8, "rw", "rx,tx", std::nullopt},
    {"0xF9F6", 0, 0, T(U32), 32, "ro", "", std::nullopt},
    {"0xF9F8", 0, 0, T(U32), 32, "ro", "", 0x01},
    {"0xFBF0", 1, 1, T(OCT), 48, "rw", "", std::nullopt},
    {"0xFBF0", 2, 2, T(U8), 8, "ro", "", std::nullopt},
    {"0xFBF0", 3, 3, T(OCT), 16, "ro", "", std::nullopt},
    {"0xFBF1", 1, 1, T(OCT), 40, "rw", "", std::nullopt},
    {"0xFBF1", 2, 2, T(U8), 8, "ro", "", std::nullopt},
    {"0xFBF1", 3, 3, T(OCT), 16, "ro", "", std::nullopt},
    {"0xFBF2", 1, 1, T(OCT), 32, "rw", "", 0x00000001},  // bytes 01 00 00 00
    {"0xFBF2", 2, 2, T(U8), 8, "ro", "", std::nullopt},
    {"0xFBF2", 3, 3, T(OCT), 16, "ro", "", std::nullopt},
    {"0xFBF3", 1, 1, T(OCT), 32, "rw", "", 0x0000000F},  // decision: CRC-32 | MD5 | SHA-1
    {"0xFBF3", 2, 2, T(U8), 8, "ro", "", std::nullopt},
    {"0xFBF3", 3, 3, T(OCT), 176, "ro", "", std::nullopt},  // decision: [0..21] fits SHA-1
    {"0xFBF4", 1, 1, T(OCT), 32, "rw", "", 0x00000001},
};

// UART configuration 0x5nn5: 4 channels x (interface, baud, parity, data, stop, flow) + pad_3.
struct UartRow {
  uint16_t type;
  uint16_t bits;
  uint64_t def;
};
const UartRow kUart[] = {{0x0804, 2, 0}, {0x0800, 4, 3}, {0x0801, 2, 0},
                         {0x0803, 2, 3}, {0x0802, 1, 0}, {0x0805, 2, 0}};

std::vector<uint16_t> resolve(const RackConfig& cfg, const coe::ObjectDictionary& od,
                              const std::string& text) {
  std::vector<uint16_t> out;
  if (text.find("rr") != std::string::npos) {
    const uint16_t low =
        static_cast<uint16_t>(std::stoul(text.substr(text.size() - 1), nullptr, 16));
    for (const auto& r : cfg.rims)
      out.push_back(static_cast<uint16_t>(0x2000 + r.number * 0x10 + low));
  } else if (text.find("nn") != std::string::npos) {
    const uint16_t area = static_cast<uint16_t>(std::stoul(text.substr(2, 1), nullptr, 16) << 12);
    const uint8_t nibble =
        static_cast<uint8_t>(std::stoul(text.substr(text.size() - 1), nullptr, 16));
    for (const auto& m : cfg.modules) {
      const uint16_t idx = m.index(area, nibble);
      if (od.find(idx)) out.push_back(idx);
    }
  } else {
    out.push_back(static_cast<uint16_t>(std::stoul(text, nullptr, 16)));
  }
  return out;
}

class AppendixA : public ::testing::Test {
 protected:
  void SetUp() override {
    DeviceOptions opt;
    opt.load_stored_parameters = false;
    opt.state_dir = ::testing::TempDir() + "/appendix_a";
    device = std::make_unique<Device>(default_rack(), opt);
  }
  std::unique_ptr<Device> device;
};

TEST_F(AppendixA, EveryListedObjectHasTheGuidesTypeAccessPdoFlagAndDefault) {
  const auto& od = device->dictionary();
  const auto& cfg = device->config();
  for (const Row& row : kAppendixA) {
    const auto indices = resolve(cfg, od, row.index);
    ASSERT_FALSE(indices.empty()) << row.index << " has no instance in the default rack";
    for (uint16_t idx : indices) {
      const coe::Object* o = od.find(idx);
      ASSERT_NE(o, nullptr) << row.index << " -> " << std::hex << idx;
      const int last = row.sub_last == 0 && row.sub_first == 1 ? o->max_subindex() : row.sub_last;
      if (row.sub_first == 1 && row.sub_last == 0) {
        EXPECT_EQ(o->max_subindex(), cfg.modules.size()) << std::hex << idx;
      }
      for (int s = row.sub_first; s <= last; ++s) {
        const coe::Entry* e = o->entry(static_cast<uint8_t>(s));
        ASSERT_NE(e, nullptr) << std::hex << idx << ":" << s;
        SCOPED_TRACE(::testing::Message() << std::hex << "0x" << idx << ":" << s << " " << e->name);
        EXPECT_EQ(e->data_type, row.type);
        EXPECT_EQ(e->bit_length, row.bits);
        const uint16_t want = *coe::access::from_guide(row.access);
        EXPECT_EQ(e->access & (coe::access::kReadAll | coe::access::kWriteAll), want);
        const std::string pdo = row.pdo;
        EXPECT_EQ((e->access & coe::access::kTxPdoMappable) != 0,
                  pdo.find("tx") != std::string::npos);
        EXPECT_EQ((e->access & coe::access::kRxPdoMappable) != 0,
                  pdo.find("rx") != std::string::npos);
        if (row.def) {
          EXPECT_EQ(o->get_u(static_cast<uint8_t>(s)), *row.def);
        }
      }
    }
  }
}

TEST_F(AppendixA, UartConfigurationPacksSixteenBitsPerChannelWithGuideDefaults) {
  const auto& cfg = device->config();
  const auto uarts = resolve(cfg, device->dictionary(), "0x5nn5");
  ASSERT_FALSE(uarts.empty());
  for (uint16_t idx : uarts) {
    const coe::Object* o = device->dictionary().find(idx);
    uint8_t sub = 1;
    for (int ch = 0; ch < 4; ++ch) {
      for (const UartRow& r : kUart) {
        const coe::Entry* e = o->entry(sub);
        ASSERT_NE(e, nullptr);
        EXPECT_EQ(e->data_type, r.type) << int(sub);
        EXPECT_EQ(e->bit_length, r.bits) << int(sub);
        EXPECT_EQ(e->bit_offset, 16 + 16 * ch + (e->bit_offset - 16 - 16 * ch)) << int(sub);
        EXPECT_EQ(e->access & 0x3F, coe::access::kRoWrPreOp);
        EXPECT_EQ(o->get_u(sub), r.def) << int(sub);
        ++sub;
      }
      if (ch < 3) {
        ASSERT_TRUE(o->entry(sub)->padding);
        EXPECT_EQ(o->entry(sub)->bit_length, 3);
        ++sub;
      }
    }
    // Channel n starts at bit 16 + 16 n (subindex 0 takes 16 bits in complete access).
    EXPECT_EQ(o->entry(0x08)->bit_offset, 32);
    EXPECT_EQ(o->entry(0x16)->bit_offset, 64);
  }
}

TEST_F(AppendixA, EnumerationsCarryTheGuidesValues) {
  const auto& od = device->dictionary();
  struct E {
    uint16_t index;
    const char* name;
    uint16_t bits;
    size_t count;
    const char* first;
    const char* last;
  };
  for (const E& e : {E{0x0800, "DT0800EN04", 4, 9, "1200 Baud", "115200 Baud"},
                     E{0x0801, "DT0801EN02", 2, 3, "No Parity", "Even Parity"},
                     E{0x0802, "DT0802EN01", 1, 2, "1 Stop Bit", "2 Stop Bits"},
                     E{0x0803, "DT0803EN02", 2, 4, "5 Bits", "8 Bits"},
                     E{0x0804, "DT0804EN02", 2, 3, "RS-232", "RS-485 with Termination Resistor"},
                     E{0x0805, "DT0805EN02", 2, 3, "None", "RTS/CTS"}}) {
    const coe::EnumType* t = od.find_enum(e.index);
    ASSERT_NE(t, nullptr) << e.name;
    EXPECT_EQ(t->name, e.name);
    EXPECT_EQ(t->bit_size, e.bits);
    ASSERT_EQ(t->values.size(), e.count);
    EXPECT_EQ(t->values.front().name, e.first);
    EXPECT_EQ(t->values.front().value, 0);
    EXPECT_EQ(t->values.back().name, e.last);
    EXPECT_EQ(t->values.back().value, static_cast<int64_t>(e.count - 1));
  }
}

// The guide's template mapping objects (0x160X/0x1A0X for module 1, nn = 00): each module's
// mapping object holds the same entries with nn substituted.
struct Template {
  IoKind kind;
  bool output;
  std::vector<uint32_t> entries;
};
std::vector<uint32_t> seq(uint32_t first, int n, uint32_t step = 0x100) {
  std::vector<uint32_t> v;
  for (int i = 0; i < n; ++i) v.push_back(first + step * i);
  return v;
}

TEST_F(AppendixA, MappingObjectsFollowTheGuidesTemplatesPerModule) {
  const std::vector<Template> templates = {
      {IoKind::DinX16, true, {0x70000110}},
      {IoKind::DinX8, true, {0x70010108}},
      {IoKind::AinX8, true, seq(0x70020110, 8)},
      {IoKind::AinX16, true, seq(0x70030110, 16)},
      // decision: the pad of DOUTx4/DINx4 is mapped as ETG padding 0x00000004, not 0x700B0204.
      {IoKind::DinX4, true, {0x700B0104}},
      {IoKind::DinX16, false, {0x60000110}},
      {IoKind::DinX8, false, {0x60010108}},
      {IoKind::AinX8, false, seq(0x60020110, 8)},
      {IoKind::AinX16, false, seq(0x60030110, 16)},
      {IoKind::TcX8, false, seq(0x60040110, 8)},
      {IoKind::DinX16x8, false, {0x60050180}},
      {IoKind::DinX8x8, false, {0x60060140}},
      {IoKind::AinX16x8, false, seq(0x60070180, 16)},
      {IoKind::AinX8x8, false, seq(0x60080180, 8)},
      {IoKind::RtdX4, false, seq(0x60090110, 4)},
      {IoKind::UartX4, false, seq(0x600A0110, 4)},
      {IoKind::DinX4, false, {0x600B0104}},
      {IoKind::DioX8, false, {0x600C0108, 0x600C0208}},
  };
  const auto& od = device->dictionary();
  std::set<std::pair<int, bool>> seen;
  for (const auto& m : device->modules()) {
    for (const Template& t : templates) {
      const auto kind = t.output ? m.card->output : m.card->input;
      if (!kind || *kind != t.kind) continue;
      seen.insert({static_cast<int>(t.kind), t.output});
      const uint16_t pdo = t.output ? sm::rx_pdo_index(m.number) : sm::tx_pdo_index(m.number);
      const coe::Object* o = od.find(pdo);
      ASSERT_NE(o, nullptr) << std::hex << pdo;
      const uint32_t shift = static_cast<uint32_t>(m.nn()) * 0x10u << 16;
      for (size_t i = 0; i < t.entries.size(); ++i) {
        EXPECT_EQ(o->get_u(static_cast<uint8_t>(i + 1)), t.entries[i] + shift)
            << std::hex << pdo << ":" << i + 1;
      }
      if (t.kind == IoKind::DinX4) {
        EXPECT_EQ(o->sub0(), 2);
        EXPECT_EQ(o->get_u(2), 0x00000004u);
      } else {
        EXPECT_EQ(o->sub0(), t.entries.size());
      }
    }
  }
  EXPECT_EQ(seen.size(), templates.size()) << "the default rack exercises every template";
}

TEST_F(AppendixA, CommunicationAreaObjects) {
  const auto& od = device->dictionary();
  EXPECT_EQ(od.find(0x1000)->get_u(0), 0x00001389u);    // ETG.5001 MDP device type
  EXPECT_EQ(od.find(0x100B)->get_string(0), "1.09.0");  // guide default 0x302e39302e31
  const coe::Object* id = od.find(0x1018);
  EXPECT_EQ(id->sub0(), 4);
  EXPECT_EQ(id->get_u(1), device->config().control.vendor_id);
  const coe::Object* smt = od.find(0x1C00);
  EXPECT_EQ(smt->get_u(1), 1u);
  EXPECT_EQ(smt->get_u(2), 2u);
  EXPECT_EQ(smt->get_u(3), 3u);
  EXPECT_EQ(smt->get_u(4), 4u);
  for (uint16_t idx : {0x1C32, 0x1C33}) {
    const coe::Object* o = od.find(idx);
    EXPECT_EQ(o->sub0(), 0x20);
    EXPECT_EQ(o->get_u(0x04), kSyncTypesSupported);
    EXPECT_EQ(o->entry(0x01)->access & 0x3F, coe::access::kRoWrPreOp);
    EXPECT_EQ(o->entry(0x0B)->data_type, T(U16));
    EXPECT_EQ(o->entry(0x0C)->data_type, T(U16));
    EXPECT_EQ(o->entry(0x20)->data_type, T(DataType::Boolean));
  }
  // Default assignment: every module's PDO in module order.
  const coe::Object* rx = od.find(0x1C12);
  size_t n = 0;
  for (const auto& m : device->modules()) {
    if (m.card->output) {
      ++n;
      EXPECT_EQ(rx->get_u(static_cast<uint8_t>(n)), sm::rx_pdo_index(m.number));
    }
  }
  EXPECT_EQ(rx->sub0(), n);
}

TEST_F(AppendixA, ModuleObjectsExistExactlyWhereTheCardNeedsThem) {
  const auto& od = device->dictionary();
  for (const auto& m : device->modules()) {
    SCOPED_TRACE(std::string(m.card->name));
    EXPECT_TRUE(od.find(m.index(0x3000, 1)));
    for (uint8_t k = 0; k < 4; ++k) {
      const bool want = m.card->safe_state && static_cast<uint8_t>(*m.card->safe_state) == k;
      EXPECT_EQ(od.find(m.index(0x4000, k)) != nullptr, want) << int(k);
    }
    EXPECT_EQ(od.find(m.index(0x5000, 4)) != nullptr, m.card->thermocouple_ohms);
    for (uint8_t k = 5; k <= 0xE; ++k)
      EXPECT_EQ(od.find(m.index(0x5000, k)) != nullptr, m.card->uart);
    for (uint8_t k = 0; k <= 0xC; ++k) {
      EXPECT_EQ(od.find(m.index(0x6000, k)) != nullptr,
                m.card->input && static_cast<uint8_t>(*m.card->input) == k);
      EXPECT_EQ(od.find(m.index(0x7000, k)) != nullptr,
                m.card->output && static_cast<uint8_t>(*m.card->output) == k);
    }
    EXPECT_EQ(od.find(sm::rx_pdo_index(m.number)) != nullptr, m.card->output.has_value());
    EXPECT_EQ(od.find(sm::tx_pdo_index(m.number)) != nullptr, m.card->input.has_value());
    // 0x3000 / 0xF050 / 0xF030 name the module's ident; 0x3nn1 its place.
    EXPECT_EQ(od.find(0x3000)->get_u(static_cast<uint8_t>(m.number)), m.card->module_ident);
    EXPECT_EQ(od.find(0xF050)->get_u(static_cast<uint8_t>(m.number)), m.card->module_ident);
    EXPECT_EQ(od.find(0xF030)->get_u(static_cast<uint8_t>(m.number)), m.card->module_ident);
    const coe::Object* info = od.find(m.index(0x3000, 1));
    EXPECT_EQ(info->get_string(1), m.card->io_card_type());
    EXPECT_LE(info->get_string(1).size(), 8u);
    EXPECT_EQ(info->get_string(2), m.card->description);
    EXPECT_EQ(info->get_u(3), m.card->channels);
    EXPECT_EQ(info->get_u(4), m.rim);
    EXPECT_EQ(info->get_u(5), m.slot);
  }
}

}  // namespace
}  // namespace rackcat::mdp
