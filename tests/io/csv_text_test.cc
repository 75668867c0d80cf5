#include "io/csv_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <string_view>

#include "rotorid/core/error.h"

namespace rotorid::internal {
namespace {

TEST(CsvText, TrimSpacesKeepsInnerBlanksAndDropsTrailingCarriageReturns) {
  EXPECT_EQ(TrimSpaces(" \t a b \t\r\r"), "a b");
  EXPECT_EQ(TrimSpaces("\ra\r"), "\ra");  // '\r' only goes at the end
  EXPECT_EQ(TrimSpaces(" \t\r"), "");
}

TEST(CsvText, NextLineCountsLinesAndDropsOneCarriageReturn) {
  std::string_view rest = "a,b\r\n\nlast\r\r";
  int number = 0;
  TextLine line;
  ASSERT_TRUE(NextLine(&rest, &number, &line));
  EXPECT_EQ(line.text, "a,b");
  EXPECT_EQ(line.number, 1);
  ASSERT_TRUE(NextLine(&rest, &number, &line));
  EXPECT_EQ(line.text, "");
  EXPECT_EQ(line.number, 2);
  ASSERT_TRUE(NextLine(&rest, &number, &line));
  EXPECT_EQ(line.text, "last\r");
  EXPECT_EQ(line.number, 3);
  EXPECT_FALSE(NextLine(&rest, &number, &line));
  EXPECT_EQ(number, 3);
}

TEST(CsvText, NumbersMustFillTheCell) {
  EXPECT_EQ(ParseNumber("-1.5e3"), -1500.0);
  EXPECT_EQ(ParseNumber("0.1"), 0.1);
  EXPECT_FALSE(ParseNumber(""));
  EXPECT_FALSE(ParseNumber("1.5x"));
  EXPECT_FALSE(ParseNumber(" 1"));
  EXPECT_FALSE(ParseNumber("abc"));
  EXPECT_TRUE(std::isinf(*ParseNumber("inf")));
  EXPECT_TRUE(std::isnan(*ParseNumber("nan")));
  EXPECT_TRUE(std::isinf(*ParseNumber("1e400")));  // out of range: infinity, not an error
  EXPECT_EQ(ParseFiniteNumber("2.25"), 2.25);
  EXPECT_FALSE(ParseFiniteNumber("inf"));
  EXPECT_FALSE(ParseFiniteNumber("-nan"));
  EXPECT_FALSE(ParseFiniteNumber("1e400"));
}

TEST(CsvText, FirstNonIncreasingTimeFindsRepeatsDropsAndNan) {
  Eigen::VectorXd t(5);
  t << 0.0, 0.01, 0.02, 0.03, 0.04;
  EXPECT_FALSE(FirstNonIncreasingTime(t));
  t[3] = 0.02;  // a repeat
  EXPECT_EQ(FirstNonIncreasingTime(t), 3);
  t[3] = 0.03;
  t[1] = -1.0;  // a drop
  EXPECT_EQ(FirstNonIncreasingTime(t), 1);
  t[1] = 0.01;
  t[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(FirstNonIncreasingTime(t), 4);
  EXPECT_FALSE(FirstNonIncreasingTime(Eigen::VectorXd()));
}

TEST(CsvText, TooFewSamplesNamesTheSource) {
  EXPECT_NO_THROW(RequireMinFlightSamples("f.csv", 20));
  try {
    RequireMinFlightSamples("f.csv", 19);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "f.csv: too few samples (19); at least 20 are needed");
  }
}

}  // namespace
}  // namespace rotorid::internal
