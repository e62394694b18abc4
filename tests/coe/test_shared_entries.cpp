// Object and entry descriptions are shared between identically described objects of different
// dictionaries (coe/shared_entries.hpp); values stay per dictionary, and a later
// add() to one object never changes another's description. Also the object image's inline
// and heap storage (coe/object_image.hpp).
#include <gtest/gtest.h>

#include "coe/object_dictionary.hpp"
#include "coe/object_image.hpp"
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

TEST(SharedEntries, IdenticalDictionariesShareNamesAndEntriesAcrossNames) {
  ObjectDictionary a = test::make_test_dictionary();
  ObjectDictionary b = test::make_test_dictionary();
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.at(i).name().data(), b.at(i).name().data()) << std::hex << a.at(i).index();
  }
  // Objects with different names but identical entries (one per module slot) share the list.
  auto make = [](uint16_t index, const char* name) {
    Object o(index, ObjectCode::Record, name);
    o.add(test::entry(0, "n", DataType::Unsigned8, 8, access::kReadAll));
    o.add(test::entry(1, "x", DataType::Unsigned16, 16, access::kReadAll));
    return o;
  };
  ObjectDictionary c;
  const Object& first = c.add(make(0x4010, "Module 1"));
  const Object& second = c.add(make(0x4020, "Module 2"));
  EXPECT_EQ(first.entries().data(), second.entries().data());
  EXPECT_NE(first.name(), second.name());
}

TEST(SharedEntries, ChangingASharedObjectCopiesItsDescriptionFirst) {
  auto make = [] {
    Object o(0x2300, ObjectCode::Record, "rec");
    o.add(test::entry(0, "n", DataType::Unsigned8, 8, access::kReadAll));
    o.add(test::entry(1, "x", DataType::Unsigned16, 16, access::kReadAll, {0x34, 0x12}));
    return o;
  };
  ObjectDictionary a, b;
  Object& oa = a.add(make());
  Object& ob = b.add(make());
  ASSERT_EQ(oa.name().data(), ob.name().data());
  oa.set_packed(true);
  EXPECT_TRUE(oa.packed());
  EXPECT_FALSE(ob.packed());
  const uint8_t v[2] = {0x78, 0x56};
  EXPECT_TRUE(oa.set_default(1, v));
  oa.load_defaults();
  ob.load_defaults();
  EXPECT_EQ(oa.get_u(1), 0x5678u);
  EXPECT_EQ(ob.get_u(1), 0x1234u);
  // A copied dictionary shares descriptions and copies values.
  ObjectDictionary c = b;
  EXPECT_EQ(c.find(0x2300)->entries().data(), ob.entries().data());
  EXPECT_NE(c.find(0x2300)->image().data(), ob.image().data());
  c.find(0x2300)->set_u(1, 7);
  EXPECT_EQ(ob.get_u(1), 0x1234u);
}

TEST(ObjectImage, SmallImagesInlineLargeOnesOnTheHeapCopiesAndMovesKeepBytes) {
  for (size_t n :
       {size_t{0}, size_t{1}, ObjectImage::kInline, ObjectImage::kInline + 1, size_t{300}}) {
    ObjectImage img;
    img.assign_zero(n);
    ASSERT_EQ(img.size(), n);
    for (size_t i = 0; i < n; ++i) {
      EXPECT_EQ(img[i], 0u);
      img[i] = static_cast<uint8_t>(i + 1);
    }
    ObjectImage copy(img);
    ObjectImage assigned;
    assigned.assign_zero(20);
    assigned = copy;
    ObjectImage moved(std::move(copy));
    EXPECT_EQ(copy.size(), 0u);  // NOLINT(bugprone-use-after-move): moved-from is empty
    for (const ObjectImage* o : {&img, &assigned, &moved}) {
      ASSERT_EQ(o->size(), n);
      for (size_t i = 0; i < n; ++i) EXPECT_EQ((*o)[i], static_cast<uint8_t>(i + 1));
    }
    if (n > 0) {
      EXPECT_NE(moved.data(), img.data());
    }
    ObjectImage target;
    target = std::move(moved);
    EXPECT_EQ(target.size(), n);
    if (n > 0) {
      EXPECT_EQ(target[n - 1], static_cast<uint8_t>(n));
    }
  }
}

}  // namespace
}  // namespace rackcat::coe
