// The dictionary contract the other areas build on: types, access notation, layouts.
#include <gtest/gtest.h>

#include "coe/abort_code.hpp"
#include "coe/access.hpp"
#include "coe/data_type.hpp"
#include "coe/object_dictionary.hpp"
#include "tests/coe/test_dictionary.hpp"

namespace rackcat::coe {
namespace {

using test::entry;
using test::le;

TEST(DataType, BasicTypesHaveTheirSpecSizesAndNames) {
  // ETG.1000.6 Table 63.
  EXPECT_EQ(fixed_bit_size(DataType::Boolean), 1);
  EXPECT_EQ(fixed_bit_size(DataType::Integer24), 24);
  EXPECT_EQ(fixed_bit_size(DataType::Unsigned64), 64);
  EXPECT_EQ(fixed_bit_size(DataType::Real64), 64);
  EXPECT_EQ(fixed_bit_size(DataType::Bit7), 7);
  EXPECT_FALSE(fixed_bit_size(DataType::VisibleString).has_value());
  EXPECT_EQ(type_name(DataType::Unsigned16), "UINT");
  EXPECT_EQ(type_name(DataType::Integer32), "DINT");
  EXPECT_EQ(type_name(DataType::Real32), "REAL");
  EXPECT_EQ(type_name(DataType::Bit3), "BIT3");
  EXPECT_TRUE(is_signed(DataType::Integer64));
  EXPECT_FALSE(is_signed(DataType::Unsigned8));
  EXPECT_TRUE(is_real(DataType::Real32));
  EXPECT_TRUE(is_string(DataType::OctetString));
  EXPECT_TRUE(is_enum_type(0x0800));
  EXPECT_FALSE(is_enum_type(0x0007));
}

TEST(Access, GuideNotationMapsToPerStateBits) {
  using namespace access;
  EXPECT_EQ(from_guide("ro"), kReadPreOp | kReadSafeOp | kReadOp);
  EXPECT_EQ(from_guide("rw"), kReadAll | kWriteAll);
  EXPECT_EQ(from_guide("ro,wr_preop"), kReadAll | kWritePreOp);
  EXPECT_EQ(from_guide("ro, wr_preop"), kReadAll | kWritePreOp);  // as the guide prints it
  EXPECT_EQ(from_guide("ro,wr_op"), kReadAll | kWriteOp);
  EXPECT_EQ(from_guide("RO"), kRo);
  EXPECT_EQ(from_guide("wo"), kWriteAll);
  EXPECT_FALSE(from_guide("rx").has_value());

  EXPECT_TRUE(can_write(kRoWrPreOp, EsmState::PreOp));
  EXPECT_FALSE(can_write(kRoWrPreOp, EsmState::SafeOp));
  EXPECT_FALSE(can_write(kRoWrPreOp, EsmState::Op));
  EXPECT_TRUE(can_write(kRoWrOp, EsmState::Op));
  EXPECT_FALSE(can_write(kRoWrOp, EsmState::PreOp));
  EXPECT_TRUE(can_read(kRo, EsmState::SafeOp));
  EXPECT_FALSE(can_read(kRo, EsmState::Init));
  EXPECT_FALSE(can_read(kWo, EsmState::PreOp));
}

TEST(AbortCode, DescriptionsFollowTheGuideTable) {
  EXPECT_EQ(describe(AbortCode::ToggleBit), "Toggle bit not changed");
  EXPECT_EQ(describe(AbortCode::ObjectNotFound),
            "The object does not exist in the object dictionary");
  EXPECT_EQ(static_cast<uint32_t>(AbortCode::DeviceState), 0x08000022u);
}

TEST(Object, ArraySubindexZeroTakesSixteenBits) {
  Object o = test::array(0x1C12, "assign", DataType::Unsigned16, 16, 2, access::kRw, access::kRw,
                         {0x1600}, 1);
  EXPECT_EQ(o.entry(0)->bit_offset, 0);
  EXPECT_EQ(o.entry(1)->bit_offset, 16);
  EXPECT_EQ(o.entry(2)->bit_offset, 32);
  EXPECT_EQ(o.image().size(), 6u);
  EXPECT_EQ(o.sub0(), 1);
  EXPECT_EQ(o.get_u(1), 0x1600u);
  EXPECT_EQ(o.max_subindex(), 2);
}

TEST(Object, BitsPackAndWiderEntriesAlignUnlessPacked) {
  Object a(0x6000, ObjectCode::Record, "aligned");
  a.add(entry(0, "n", DataType::Unsigned8, 8, access::kRo));
  a.add(entry(1, "b", DataType::Boolean, 1, access::kRo));
  a.add(entry(2, "w", DataType::Unsigned16, 16, access::kRo));
  a.finalize();
  EXPECT_EQ(a.entry(1)->bit_offset, 16);
  EXPECT_EQ(a.entry(2)->bit_offset, 24);

  Object p(0x6001, ObjectCode::Record, "packed");
  p.set_packed(true);
  p.add(entry(0, "n", DataType::Unsigned8, 8, access::kRo));
  p.add(entry(1, "b", DataType::Boolean, 1, access::kRo));
  p.add(entry(2, "w", DataType::Unsigned16, 16, access::kRo));
  p.finalize();
  EXPECT_EQ(p.entry(2)->bit_offset, 17);
  p.set_u(2, 0xBEEF);
  EXPECT_EQ(p.get_u(2), 0xBEEFu);
  EXPECT_EQ(p.get_u(1), 0u);
}

TEST(Object, TypedHelpersAndDefaults) {
  Object o(0x2000, ObjectCode::Record, "r");
  o.add(entry(0, "n", DataType::Unsigned8, 8, access::kRo));
  o.add(entry(1, "i", DataType::Integer16, 16, access::kRw, le(0xFFFE, 2)));
  o.add(entry(2, "s", DataType::VisibleString, 64, access::kRw));
  o.finalize();
  EXPECT_EQ(o.sub0(), 2);  // no default for subindex 0: all entries in use
  EXPECT_EQ(o.get_i(1), -2);
  o.set_string(2, "hello");
  EXPECT_EQ(o.get_string(2), "hello");
  o.set_u(1, 7);
  o.load_defaults();
  EXPECT_EQ(o.get_i(1), -2);
  EXPECT_EQ(o.get_string(2), "");
  EXPECT_TRUE(o.bytes(9).empty());
}

TEST(Object, RejectsOutOfOrderAndOverlappingEntries) {
  Object o(0x2000, ObjectCode::Record, "r");
  o.add(entry(0, "n", DataType::Unsigned8, 8, access::kRo));
  o.add(entry(2, "a", DataType::Unsigned8, 8, access::kRo));
  EXPECT_THROW(o.add(entry(1, "b", DataType::Unsigned8, 8, access::kRo)), std::logic_error);
  Entry overlap = entry(3, "c", DataType::Unsigned8, 8, access::kRo);
  overlap.bit_offset = 8;
  EXPECT_THROW(o.add(overlap), std::logic_error);
}

TEST(ObjectDictionary, SortedLookupAndStableReferences) {
  ObjectDictionary od;
  Object& b = od.add(test::var(0x2000, "b", DataType::Unsigned8, 8, access::kRw));
  od.add(test::var(0x1000, "a", DataType::Unsigned32, 32, access::kRo));
  for (uint16_t i = 0; i < 100; ++i)
    od.add(test::var(static_cast<uint16_t>(0x3000 + i), "x", DataType::Unsigned8, 8, access::kRo));
  EXPECT_EQ(&b, od.find(0x2000));  // still valid after later adds
  EXPECT_EQ(od.find(0x1001), nullptr);
  EXPECT_EQ(od.size(), 102u);
  EXPECT_EQ(od.at(0).index(), 0x1000);
  EXPECT_EQ(od.at(od.lower_bound(0x2001)).index(), 0x3000);
  std::vector<uint16_t> order;
  od.for_each([&](const Object& o) { order.push_back(o.index()); });
  EXPECT_TRUE(std::is_sorted(order.begin(), order.end()));
  EXPECT_THROW(od.add(test::var(0x1000, "dup", DataType::Unsigned8, 8, access::kRo)),
               std::logic_error);
  EXPECT_TRUE(od.remove(0x3000));
  EXPECT_EQ(od.find(0x3000), nullptr);

  ObjectDictionary copy = od;
  ASSERT_NE(copy.find(0x2000), nullptr);
  EXPECT_NE(copy.find(0x2000), od.find(0x2000));
}

TEST(ObjectDictionary, AddFinalizesAnUnfinalizedObject) {
  ObjectDictionary od;
  Object o(0x2000, ObjectCode::Var, "v", static_cast<uint16_t>(DataType::Unsigned16));
  o.add(entry(0, "v", DataType::Unsigned16, 16, access::kRw, le(0x1234, 2)));
  Object& added = od.add(std::move(o));
  EXPECT_EQ(added.get_u(0), 0x1234u);
}

// Most objects of a device have no hooks: they hold none (one pointer, no three empty
// std::function), so a slave's dictionary costs what its values need (issue 16: memory per
// slave). An object is then one cache line.
TEST(Object, WithoutHooksHoldsNoHookStorage) {
  static_assert(sizeof(Object) <= 64);
  Object o = test::var(0x2000, "v", DataType::Unsigned8, 8, access::kRw);
  EXPECT_FALSE(o.hooks().before_read);
  EXPECT_FALSE(o.hooks().validate_write);
  EXPECT_FALSE(o.hooks().after_write);
  int reads = 0;
  o.edit_hooks().before_read = [&reads](Object&, int) { ++reads; };
  EXPECT_TRUE(o.hooks().before_read);
  EXPECT_FALSE(o.hooks().after_write);
}

// A copied dictionary (a device's defaults, the ESI's view) keeps each object's hooks, and the
// copy's hooks are its own: replacing one side's leaves the other's alone.
TEST(ObjectDictionary, CopyKeepsHooksOfItsOwn) {
  ObjectDictionary od;
  int original_reads = 0;
  od.add(test::var(0x2000, "v", DataType::Unsigned8, 8, access::kRw)).edit_hooks().before_read =
      [&original_reads](Object&, int) { ++original_reads; };
  od.add(test::var(0x2001, "w", DataType::Unsigned8, 8, access::kRw));
  ObjectDictionary copy = od;
  Object& copied = *copy.find(0x2000);
  ASSERT_TRUE(copied.hooks().before_read);
  copied.hooks().before_read(copied, 0);
  EXPECT_EQ(original_reads, 1);
  int copy_reads = 0;
  copied.edit_hooks().before_read = [&copy_reads](Object&, int) { ++copy_reads; };
  Object& original = *od.find(0x2000);
  original.hooks().before_read(original, 0);
  EXPECT_EQ(original_reads, 2);
  EXPECT_EQ(copy_reads, 0);
  EXPECT_FALSE(copy.find(0x2001)->hooks().before_read);
}

}  // namespace
}  // namespace rackcat::coe

namespace rackcat::coe {
namespace {

TEST(Access, ToGuideSpellsTheGuideColumn) {
  using namespace access;
  EXPECT_EQ(to_guide(kRo | kTxPdoMappable), "ro");
  EXPECT_EQ(to_guide(kRoWrPreOp), "ro,wr_preop");
  EXPECT_EQ(to_guide(kRoWrOp | kBackup), "ro,wr_op");
  EXPECT_EQ(to_guide(kRw), "rw");
  EXPECT_EQ(to_guide(kReadAll | kWriteSafeOp), "");
}

}  // namespace
}  // namespace rackcat::coe
