// Entry descriptions are shared between identically described objects of different
// dictionaries (coe/shared_entries.hpp); values stay per dictionary, and a later
// add() to one object never changes another's description.
#include <gtest/gtest.h>

#include "coe/object_dictionary.hpp"
#include "coe/shared_entries.hpp"
#include "tests/coe/test_dictionary.hpp"

namespace rackcat::coe {
namespace {

TEST(SharedEntries, IdenticalDictionariesShareDescriptionsButNotValues) {
  ObjectDictionary a = test::make_test_dictionary();
  ObjectDictionary b = test::make_test_dictionary();
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 0u);
  for (size_t i = 0; i < a.size(); ++i) {
    if (a.at(i).entries().empty()) continue;
    EXPECT_EQ(a.at(i).entries().data(), b.at(i).entries().data()) << std::hex << a.at(i).index();
    EXPECT_NE(a.at(i).image().data(), b.at(i).image().data());
  }
  Object& oa = a.at(0);
  Object& ob = b.at(0);
  const uint64_t before = ob.get_u(oa.entries().back().subindex);
  oa.set_u(oa.entries().back().subindex, before ^ 1u);
  EXPECT_EQ(ob.get_u(oa.entries().back().subindex), before);
}

TEST(SharedEntries, AddAfterSharingCopiesFirst) {
  auto make = [] {
    Object o(0x2100, ObjectCode::Record, "rec");
    o.add(test::entry(0, "n", DataType::Unsigned8, 8, access::kReadAll));
    o.add(test::entry(1, "x", DataType::Unsigned16, 16, access::kReadAll));
    return o;
  };
  ObjectDictionary a, b;
  Object& oa = a.add(make());
  Object& ob = b.add(make());
  ASSERT_EQ(oa.entries().data(), ob.entries().data());
  oa.add(test::entry(2, "y", DataType::Unsigned32, 32, access::kReadAll));
  oa.finalize();
  EXPECT_EQ(oa.entries().size(), 3u);
  EXPECT_EQ(ob.entries().size(), 2u);
  EXPECT_EQ(ob.max_subindex(), 1);
}

TEST(SharedEntries, DifferentDescriptionsAreNotShared) {
  ObjectDictionary a, b;
  Object x(0x2200, ObjectCode::Var, "v");
  x.add(test::entry(0, "v", DataType::Unsigned16, 16, access::kReadAll));
  Object y(0x2200, ObjectCode::Var, "v");
  Entry e = test::entry(0, "v", DataType::Unsigned16, 16, access::kReadAll);
  e.max = 100;  // a limit is part of the description
  y.add(e);
  const Object& ox = a.add(x);
  const Object& oy = b.add(y);
  EXPECT_NE(ox.entries().data(), oy.entries().data());
  EXPECT_EQ(oy.entries().front().max, 100);
}

}  // namespace
}  // namespace rackcat::coe
