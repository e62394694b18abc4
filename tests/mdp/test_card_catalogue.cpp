// The catalogue covers every card of the guide's Table 3 and every ident of Table 5, and its
// strings fit the objects that carry them.
#include "mdp/card_catalogue.hpp"

#include <gtest/gtest.h>

namespace rackcat::mdp {
namespace {

TEST(CardCatalogue, EveryTable3CardIdIsFound) {
  // Guide Table 3, in order.
  for (uint16_t id :
       {0x3000, 0x4000, 0x5000, 0x7000, 0x9000, 0xA000, 0xB000, 0xC000, 0xD000, 0xE000, 0xF011,
        0xF015, 0xF081, 0xF085, 0xF012, 0xF013, 0xF014, 0xF022, 0xF210}) {
    const CardType* c = find_card(id);
    ASSERT_NE(c, nullptr) << std::hex << id;
    EXPECT_TRUE(c->in_table3);
    EXPECT_EQ(c->samples, 1);
  }
}

TEST(CardCatalogue, EveryTable5IdentIsFound) {
  for (uint32_t ident :
       {0x0064C004u, 0x0064C104u, 0x0064C108u, 0x0064D004u, 0x0064D008u, 0x0064D016u, 0x0064D108u,
        0x0064D808u, 0x0064D116u, 0x0064D816u, 0x0064DD08u, 0x0064A008u, 0x0064A016u, 0x0064A108u,
        0x0064A808u, 0x0064A116u, 0x0064A816u}) {
    EXPECT_NE(find_card_by_ident(ident), nullptr) << std::hex << ident;
  }
}

TEST(CardCatalogue, StringsFitTheirObjectsAndLayoutsExist) {
  for (const CardType& c : card_catalogue()) {
    SCOPED_TRACE(std::string(c.name));
    EXPECT_LE(c.io_card_type().size(), 8u);  // 0x3nn1:01 string(8)
    EXPECT_LE(c.description.size(), 32u);    // 0x3nn1:02 string(32)
    EXPECT_LT(c.min_voltage, c.max_voltage);
    EXPECT_TRUE(c.input || c.output);
    EXPECT_TRUE(!c.input || io_layout(*c.input, false) != nullptr);
    EXPECT_TRUE(!c.output || io_layout(*c.output, true) != nullptr);
    // The encoder's output is a control word, not a terminal: no safe state (docs/ENCODER.md).
    EXPECT_EQ(c.safe_state.has_value(), c.output.has_value() && !c.encoder());
    EXPECT_EQ(find_card(c.name), &c);
  }
}

TEST(CardCatalogue, OversampledVariantsKeepTheirCardId) {
  const CardType* base = find_card("CDI-10");
  ASSERT_NE(base, nullptr);
  const CardType* x8 = oversampled_variant(*base);
  ASSERT_NE(x8, nullptr);
  EXPECT_EQ(x8->card_id, 0xD000);
  EXPECT_EQ(x8->module_ident, 0x0064D816u);
  EXPECT_EQ(x8->samples, 8);
  EXPECT_EQ(oversampled_variant(*find_card("CDO-10")), nullptr);
}

TEST(CardCatalogue, IndexRules) {
  EXPECT_EQ(module_index(0x6000, 1, 0x0), 0x6000);
  EXPECT_EQ(module_index(0x3000, 3, 0x1), 0x3021);
  EXPECT_EQ(module_index(0x7000, 255, 0xB), 0x7FEB);
  EXPECT_EQ(rim_info_index(1), 0x2011);
  EXPECT_EQ(rim_info_index(5), 0x2051);
}

}  // namespace
}  // namespace rackcat::mdp
