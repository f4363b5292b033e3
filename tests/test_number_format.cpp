// The CSV number format (io/number_format.hpp): byte for byte what printf("%.9g") and
// std::to_chars(general, 9) write, on values of every kind, ties and near-ties included.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "io/number_format.hpp"

namespace {

std::string fast(double v) {
  char buf[lash::kG9MaxChars];
  return std::string(buf, lash::format_g9(v, buf));
}

std::string reference(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string via_to_chars(double v) {
  char buf[64];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 9).ptr);
}

}  // namespace

TEST(NumberFormat, KnownValues) {
  EXPECT_EQ(fast(0.17), "0.17");
  EXPECT_EQ(fast(-1.2560737), "-1.2560737");
  EXPECT_EQ(fast(123456789.0), "123456789");
  EXPECT_EQ(fast(1234567890.0), "1.23456789e+09");
  EXPECT_EQ(fast(1e-5), "1e-05");
  EXPECT_EQ(fast(0.0001), "0.0001");
  EXPECT_EQ(fast(6.61e10), "6.61e+10");
  EXPECT_EQ(fast(0.0), "0");
  EXPECT_EQ(fast(-0.0), "-0");
  EXPECT_EQ(fast(999999999.6), "1e+09");
  EXPECT_EQ(fast(123456789.5), reference(123456789.5));  // an exact tie: to even, as printf
  EXPECT_EQ(fast(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(fast(std::nan("")), reference(std::nan("")));
}

TEST(NumberFormat, SameBytesAsPrintfOnMillionsOfValues) {
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-20, 35);
  long checked = 0;
  for (int i = 0; i < 400'000; ++i) {
    // Physical magnitudes, random bit patterns (every exponent), and 9-digit decimals with
    // something below the last digit (ties and near-ties of the rounding).
    const double a = mantissa(rng) * std::pow(10.0, exponent(rng));
    std::uint64_t bits = rng();
    double b;
    std::memcpy(&b, &bits, sizeof b);
    const double c = (static_cast<double>(rng() % 900000000 + 100000000) + 0.5 +
                      static_cast<double>(static_cast<int>(rng() % 3) - 1) * 1e-7) *
                     std::pow(10.0, exponent(rng) - 8);
    for (double v : {a, b, c}) {
      ASSERT_EQ(fast(v), reference(v)) << std::hexfloat << v;
      ++checked;
    }
  }
  // Every power of ten and its neighbours, across the fast path's range and beyond it.
  for (int k = -20; k <= 35; ++k) {
    const double p = std::pow(10.0, k);
    for (double v : {p, std::nextafter(p, 0.0), std::nextafter(p, 1e300), -p, p * 0.9999999995,
                     p * 1.0000000005}) {
      ASSERT_EQ(fast(v), reference(v)) << std::hexfloat << v;
      ASSERT_EQ(fast(v), via_to_chars(v)) << std::hexfloat << v;
    }
  }
  EXPECT_GT(checked, 1'000'000);
}

TEST(NumberFormat, ShortestNumberReadsBackExactly) {
  EXPECT_EQ(lash::shortest_number(3000), "3000");
  EXPECT_EQ(lash::shortest_number(-2), "-2");
  EXPECT_EQ(lash::shortest_number(1e-4), "0.0001");
  EXPECT_EQ(lash::shortest_number(0.00015), "0.00015");
  EXPECT_EQ(lash::shortest_number(std::nan("")), "nan");
  EXPECT_EQ(lash::shortest_number(-INFINITY), "-inf");
  for (double v : {0.1 + 0.2, 3666.6666666666665, 1e-300, 6.02214076e23, 5e15 + 1})
    EXPECT_EQ(std::strtod(lash::shortest_number(v).c_str(), nullptr), v) << lash::shortest_number(v);
}

TEST(NumberFormat, ShortestNumberIsTheFewestDigitsOfPercentG) {
  // The reference: %.pg for p = 1, 2, … until it reads back. shortest_number takes p from the
  // shortest round-trip digits instead; next to a power of two those are not always %g's.
  auto reference = [](double v) {
    char buf[32];
    if (v == std::floor(v) && std::abs(v) < 1e15) {
      std::snprintf(buf, sizeof buf, "%.0f", v);
      return std::string(buf);
    }
    for (int p = 1; p <= 17; ++p) {
      std::snprintf(buf, sizeof buf, "%.*g", p, v);
      if (std::strtod(buf, nullptr) == v) break;
    }
    return std::string(buf);
  };
  std::mt19937_64 bits(7);
  for (int e = -1074; e <= 1023; ++e) {
    const double p = std::ldexp(1.0, e);
    for (double v : {p, std::nextafter(p, 0.0), std::nextafter(p, INFINITY), -p})
      ASSERT_EQ(lash::shortest_number(v), reference(v)) << std::hexfloat << v;
  }
  for (int i = 0; i < 200000; ++i) {
    double v;
    const unsigned long long b = bits();
    std::memcpy(&v, &b, sizeof v);
    if (std::isfinite(v)) ASSERT_EQ(lash::shortest_number(v), reference(v)) << std::hexfloat << v;
  }
}
