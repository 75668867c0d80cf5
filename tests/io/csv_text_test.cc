#include "io/csv_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "rotorid/core/error.h"

namespace rotorid::internal {
namespace {

// Wall-clock stamps keep every digit the text gives through the subtraction of the first stamp: the
// offsets are those of the same stamps without the epoch (a double alone resolves 1.7e9 s to 2.4e-7 s).
TEST(CsvText, WallClockStampsBecomeExactOffsetsFromTheFirst) {
  std::vector<TimeStamp> stamps;
  for (const char* cell : {"1772681685.527483940", "1772681685.537483931", "1772681686.5"})
    stamps.push_back(*ParseTimeStamp(cell, 1.0, 1.0));
  EXPECT_EQ(stamps[0].coarse_s, 1772681685.0);
  std::map<std::string, std::string> metadata;
  const Eigen::VectorXd t = TimesFromStamps(stamps, &metadata);
  EXPECT_EQ(t[0], 0.0);
  EXPECT_NEAR(t[1], 0.009999991, 1e-15);
  EXPECT_NEAR(t[2], 0.97251606, 1e-15);
  EXPECT_EQ(metadata.at("time_origin_s"), "1772681685.527483940");
  // Milliseconds and an exponent form; the sign of a negative stamp goes to both parts.
  const TimeStamp ms = *ParseTimeStamp("1700000000005.25", 1.0, 1e-3);
  EXPECT_EQ(ms.coarse_s, 1700000000.0);
  EXPECT_NEAR(ms.fine_s, 0.00525, 1e-18);
  const TimeStamp exponent = *ParseTimeStamp("1.7000000000125e9", 1.0, 1.0);
  EXPECT_EQ(exponent.coarse_s, 1700000000.0);
  EXPECT_NEAR(exponent.fine_s, 0.0125, 1e-9);
  const TimeStamp negative = *ParseTimeStamp("-2000000.75", 1.0, 1.0);
  EXPECT_EQ(negative.coarse_s, -2000000.0);
  EXPECT_EQ(negative.fine_s, -0.75);
  // Times since boot stay as they are, with no origin.
  metadata.clear();
  EXPECT_EQ(TimesFromStamps({*ParseTimeStamp("12.345", 1.0, 1.0)}, &metadata)[0], 12.345);
  EXPECT_TRUE(metadata.empty());
  EXPECT_FALSE(ParseTimeStamp("nan", 1.0, 1.0));
  EXPECT_FALSE(ParseTimeStamp("12 s", 1.0, 1.0));
}

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
