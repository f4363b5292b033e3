#include "io/number_format.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace lash {

namespace {

/// 10^k for k = 0..22: every one exact in a double.
constexpr double kPow10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                               1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

char* slow(double v, char* out) {
  return std::to_chars(out, out + kG9MaxChars, v, std::chars_format::general, 9).ptr;
}

/// a · 10^(8 − e), i.e. a scaled to [1e8, 1e9) when e is a's decimal exponent, with one
/// rounding (the power is exact); false when 8 − e is outside ±22.
bool scale(double a, int e, double& m) {
  const int k = 8 - e;
  if (k >= 0 && k <= 22) return m = a * kPow10[k], true;
  if (k < 0 && k >= -22) return m = a / kPow10[-k], true;
  return false;
}

}  // namespace

char* format_g9(double v, char* out) {
  const double a = std::fabs(v);
  if (a == 0.0) {  // many columns hold exact zeros (a guide's y, a ground-fixed angle)
    char* p = out;
    if (std::signbit(v)) *p++ = '-';
    *p++ = '0';
    return p;
  }
  if (!(a >= 1e-14 && a < 1e31)) return slow(v, out);  // also inf, NaN
  // Decimal exponent estimate from the binary one (a is normal here): floor(log10(2)·e2),
  // corrected below when it is one off.
  std::uint64_t bits;
  std::memcpy(&bits, &a, sizeof bits);
  const int e2 = static_cast<int>(bits >> 52) - 1023;  // a = 1.f·2^e2
  int e = (e2 * 78913) >> 18;                          // 78913 / 2^18 ≈ log10(2)
  double m;
  if (!scale(a, e, m)) return slow(v, out);
  if (m >= 1e9) {
    ++e;
    if (!scale(a, e, m)) return slow(v, out);
  } else if (m < 1e8) {
    --e;
    if (!scale(a, e, m)) return slow(v, out);
  }
  if (!(m >= 1e8 && m < 1e9)) return slow(v, out);
  // m carries one rounding: |error| ≤ 2^-53·1e9 ≈ 1.1e-7, and its own spacing is 1.2e-7. Away
  // from a tie that cannot change which way it rounds; near one, take the exact path.
  auto digits = static_cast<std::uint32_t>(m);  // m > 0: truncation is floor
  const double frac = m - digits;
  if (std::fabs(frac - 0.5) < 1e-6) return slow(v, out);
  digits += frac > 0.5 ? 1u : 0u;
  if (digits == 1000000000u) digits = 100000000u, ++e;
  // The nine digits, two at a time, then without trailing zeros (%g drops them).
  static constexpr char kPairs[] =
      "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
      "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
      "8081828384858687888990919293949596979899";
  char d[9];
  for (int i = 7; i > 0; i -= 2) {
    std::memcpy(d + i, kPairs + 2 * (digits % 100), 2);
    digits /= 100;
  }
  d[0] = static_cast<char>('0' + digits);
  int nd = 9;
  while (nd > 1 && d[nd - 1] == '0') --nd;
  char* p = out;
  if (v < 0) *p++ = '-';
  if (e >= -4 && e < 9) {  // fixed notation
    if (e >= 0) {
      const int int_digits = e + 1;
      std::memcpy(p, d, int_digits);
      p += int_digits;
      if (nd > int_digits) {
        *p++ = '.';
        std::memcpy(p, d + int_digits, nd - int_digits);
        p += nd - int_digits;
      }
    } else {
      *p++ = '0';
      *p++ = '.';
      for (int i = 0; i < -e - 1; ++i) *p++ = '0';
      std::memcpy(p, d, nd);
      p += nd;
    }
    return p;
  }
  *p++ = d[0];  // scientific notation, an exponent of at least two digits
  if (nd > 1) {
    *p++ = '.';
    std::memcpy(p, d + 1, nd - 1);
    p += nd - 1;
  }
  *p++ = 'e';
  *p++ = e < 0 ? '-' : '+';
  const int x = e < 0 ? -e : e;
  if (x >= 100) *p++ = static_cast<char>('0' + x / 100);
  *p++ = static_cast<char>('0' + x / 10 % 10);
  *p++ = static_cast<char>('0' + x % 10);
  return p;
}

std::string shortest_number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
    return buf;
  }
  // The fewest significant digits that read back as v, written as %g writes them: the count
  // from the shortest round-trip form (std::to_chars), checked, and raised in the rare case
  // where the shortest digits are not the correctly rounded ones (next to a power of two).
  const std::to_chars_result shortest =
      std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific);
  int digits = 0;
  for (const char* c = buf; c != shortest.ptr && *c != 'e'; ++c) digits += *c >= '0' && *c <= '9';
  for (int p = std::max(digits, 1); p <= 17; ++p) {
    char* end = std::to_chars(buf, buf + sizeof buf - 1, v, std::chars_format::general, p).ptr;
    double back = 0.0;
    std::from_chars(buf, end, back);
    if (back == v || p == 17) return std::string(buf, end);
  }
  return buf;
}

}  // namespace lash
