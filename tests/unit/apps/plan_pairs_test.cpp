// rtfuse-plan's start/goal pairs: rows of four integers, comments and blank
// lines skipped, everything else refused with the file and line.
#include "apps/plan_pairs.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace plan_pairs_test {

using namespace rtfuse::apps;

std::string refusal(const std::string& text) {
  try {
    parse_plan_pairs(text, "pairs.txt");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(PlanPairs, RowsOfFourCellsWithTheirLines) {
  const std::vector<PlanPair> p = parse_plan_pairs("# sx sy gx gy\n10 20 30 40\n\n\t+1 -2 3 4 \r\n", "pairs.txt");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].sx, 10);
  EXPECT_EQ(p[0].gy, 40);
  EXPECT_EQ(p[0].line, 2u);
  EXPECT_EQ(p[1].sx, 1);
  EXPECT_EQ(p[1].sy, -2);  // outside the map: the planner says so, not the reader
  EXPECT_EQ(p[1].line, 4u);
}

TEST(PlanPairs, AnythingElseIsRefusedWithTheFileAndLine) {
  EXPECT_EQ(refusal("1 2 3\n"), "pairs.txt:1: expected 4 numbers \"sx sy gx gy\", found 3");
  EXPECT_EQ(refusal("1 2 3 4\n1 2 3 4 5\n"), "pairs.txt:2: more than 4 numbers on the line");
  EXPECT_EQ(refusal("1 2.5 3 4\n"), "pairs.txt:1: \"2.5\" is not a number");
  EXPECT_EQ(refusal("1 2 3 99999999999\n"), "pairs.txt:1: number out of range");
  EXPECT_EQ(refusal("a b c d\n"), "pairs.txt:1: \"a\" is not a number");
  EXPECT_TRUE(refusal("").empty());  // an empty file is no error here: no pairs
  EXPECT_THROW(read_plan_pairs("/nonexistent/pairs.txt"), std::runtime_error);
}

}  // namespace plan_pairs_test
