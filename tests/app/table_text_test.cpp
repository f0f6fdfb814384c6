// The rules every table reader and number list shares (app/table_text.hpp).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "app/table_text.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {
namespace {

TEST(TableText, ReadsDecimalNumbersWhole) {
  EXPECT_EQ(parseDecimal("0.25"), 0.25);
  EXPECT_EQ(parseDecimal("-3e-2"), -0.03);
  EXPECT_EQ(parseDecimal("+7"), 7.0);
  EXPECT_EQ(parseDecimal("1E3"), 1000.0);
  EXPECT_EQ(parseDecimal("1e308"), 1e308);  // in range; the readers judge the magnitude themselves
  EXPECT_EQ(parseDecimal("1e-400"), 0.0);   // below the smallest double: zero, not "no number"
  EXPECT_EQ(parseDecimal("2.5e-310"), 2.5e-310);  // a subnormal double
}

TEST(TableText, RefusesWhatIsNotOneFiniteDecimalNumber) {
  for (const std::string& field : std::vector<std::string>{"", " ", "abc", "1.5m", "1,5", "0x1", "0X1P3", "1e999", "-1e999", "inf", "-inf", "nan",
                                  "NaN", "+-5", "++5", "-+5", "- 5", std::string("0.4\0", 4)}) {
    EXPECT_FALSE(parseDecimal(field).has_value()) << "'" << printable(field) << "'";
  }
}

TEST(TableText, SplitsFieldsTrimmedKeepingEmptyOnes) {
  EXPECT_EQ(splitCommaFields(" a , b\t,c\r"), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(splitCommaFields("a,"), (std::vector<std::string>{"a", ""}));
  EXPECT_EQ(splitCommaFields(",,"), (std::vector<std::string>{"", "", ""}));
  EXPECT_EQ(splitCommaFields(""), (std::vector<std::string>{""}));
  EXPECT_EQ(trimmed(" \t\r "), "");
  EXPECT_EQ(lowercase("Qw,X"), "qw,x");
}

TEST(TableText, ReadsPastAByteOrderMarkAndRefusesCarriageReturnsAloneAsLineEnds) {
  std::string marked = "\xEF\xBB\xBFx,y,z";
  prepareFirstLine(marked, "data.csv");
  EXPECT_EQ(marked, "x,y,z");
  std::string windows = "x,y,z\r";  // CRLF: getline leaves the CR at the end
  EXPECT_NO_THROW(prepareFirstLine(windows, "data.csv"));
  std::string mac = "x,y,z\r0,0,0\r";
  try {
    prepareFirstLine(mac, "data.csv");
    FAIL() << "read a classic Mac file as one header line";
  } catch (const InputError& error) {
    EXPECT_STREQ(error.what(), "data.csv: lines end in a carriage return alone; expected LF or CRLF line ends");
  }
}

}  // namespace
}  // namespace flexirob::app
