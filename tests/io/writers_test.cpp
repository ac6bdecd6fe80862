// The number formatting of the result files (io/writers.h): the shortest text that reads back
// as the same double, in CSV rows and JSON numbers.
#include "screwfem/io/writers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace screwfem::writers_test {
namespace {

std::uint64_t Bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Every finite double (random bit patterns from a fixed seed, and the edge cases) reads back
// bit-identical, in no more characters than %.17g.
TEST(AppendShortest, ReadsBackBitIdenticalAndIsNoLongerThanSeventeenDigits) {
  std::vector<double> values = {0.0,
                                -0.0,
                                0.1,
                                1.0 / 3.0,
                                -2.5e-3,
                                1e15,
                                std::numeric_limits<double>::min(),
                                std::numeric_limits<double>::denorm_min(),
                                std::numeric_limits<double>::max(),
                                -std::numeric_limits<double>::max(),
                                std::numeric_limits<double>::epsilon()};
  std::mt19937_64 random(20261202);
  while (values.size() < 200000) {
    const std::uint64_t b = random();
    double x;
    std::memcpy(&x, &b, sizeof x);
    if (std::isfinite(x)) values.push_back(x);
  }
  for (double x : values) {
    std::string text;
    AppendShortest(&text, x);
    ASSERT_EQ(Bits(std::strtod(text.c_str(), nullptr)), Bits(x)) << text;
    char printf_text[40];
    std::snprintf(printf_text, sizeof printf_text, "%.17g", x);
    ASSERT_LE(text.size(), std::strlen(printf_text)) << text << " vs " << printf_text;
  }
  std::string text;
  AppendShortest(&text, 0.1);
  EXPECT_EQ(text, "0.1");
}

TEST(JsonWriter, NumbersAreShortestAndNonFiniteOnesNull) {
  JsonWriter j;
  j.BeginArray().Number(0.1).Number(1e-300).Number(NAN).Number(-INFINITY).EndArray();
  EXPECT_EQ(j.str(), "[\n  0.1,\n  1e-300,\n  null,\n  null\n]\n");
}

}  // namespace
}  // namespace screwfem::writers_test
