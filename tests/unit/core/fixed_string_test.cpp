#include "core/fixed_string.hpp"

#include <gtest/gtest.h>

#include <string>
#include <type_traits>

namespace fixed_string_test {

using Name = rtfuse::FixedString<8>;

static_assert(std::is_trivially_copyable_v<Name>, "names must fit in trivially copyable records");

TEST(CoreFixedString, DefaultIsEmpty) {
  Name n;
  EXPECT_TRUE(n.empty());
  EXPECT_EQ(n.size(), 0U);
  EXPECT_STREQ(n.c_str(), "");
}

TEST(CoreFixedString, AssignRejectsTooLongAndKeepsOldValue) {
  Name n("base");
  EXPECT_TRUE(n.assign("12345678"));  // exactly MaxLen
  EXPECT_EQ(n.view(), "12345678");
  EXPECT_FALSE(n.assign("123456789"));
  EXPECT_EQ(n.view(), "12345678");
  EXPECT_TRUE(n.assign(std::string_view()));  // null data, zero size
  EXPECT_TRUE(n.empty());
}

TEST(CoreFixedString, ConstructorTruncatesAsDocumented) {
  Name n("imu_link_long");
  EXPECT_EQ(n.view(), "imu_link");
  EXPECT_EQ(Name(std::string_view("abcdefghijk")).view(), "abcdefgh");
  EXPECT_TRUE(Name(static_cast<const char*>(nullptr)).empty());
}

TEST(CoreFixedString, ComparesWithLiteralsViewsAndStrings) {
  const Name n("odom");
  const std::string s = "odom";
  const std::string_view v = "odom";
  EXPECT_TRUE(n == "odom");
  EXPECT_TRUE("odom" == n);
  EXPECT_TRUE(n != "map");
  EXPECT_TRUE("map" != n);
  EXPECT_TRUE(n == v);
  EXPECT_TRUE(v == n);
  EXPECT_TRUE(n == s);
  EXPECT_TRUE(s == n);
  EXPECT_TRUE(n == Name("odom"));
  EXPECT_FALSE(n == Name("odo"));
}

}  // namespace fixed_string_test
