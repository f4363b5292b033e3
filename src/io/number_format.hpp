#pragma once
/// @file number_format.hpp
/// The CSV's number format, fast: `printf("%.9g")` byte for byte (the same bytes as
/// `std::to_chars(..., std::chars_format::general, 9)`), at a fraction of its cost. Formatting
/// was most of the cost of a CSV row (bench/README.md, "Whole process").

#include <string>

namespace lash {

/// Longest text format_g9 writes ("-1.23456789e-308" and the like), without a terminator.
constexpr int kG9MaxChars = 24;

/// Writes `v` as `%.9g` at `out` (room for kG9MaxChars) and returns the end. Values whose
/// 9-digit rounding the fast path cannot decide with certainty (within 1e-6 of a tie), values
/// outside 1e-14 ≤ |v| < 1e31, zeros, infinities and NaN go through std::to_chars.
char* format_g9(double v, char* out);

/// The shortest text that reads back to exactly `v`, whole numbers below 1e15 without an
/// exponent ("3000", not "3e+03"; "0.00015"); "nan", "inf", "-inf" otherwise. For texts a user
/// reads and a program reads back: override values of studies, study CSV exports.
std::string shortest_number(double v);

}  // namespace lash
