#pragma once
// Numbers in messages as Python's repr() writes them, so that a value reads
// the same whether it entered through Python, the command line or C++.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace sorpia {
namespace detail {

// Shortest round-trip digits, fixed notation for exponents in [-4, 16) with
// at least one decimal ("2.0", "0.001"), scientific otherwise ("1e-10",
// "1.5e+16"); "nan", "inf", "-inf".
inline std::string repr(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[40];
  for (int p = 1; p <= 17; ++p) {
    std::snprintf(buf, sizeof buf, "%.*e", p - 1, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  // buf is [-]d[.ddd]e[+-]XX: split into sign, digits and exponent.
  std::string s(buf), sign, digits;
  std::size_t k = 0;
  if (s[k] == '-') sign = "-", ++k;
  for (; s[k] != 'e'; ++k)
    if (s[k] != '.') digits += s[k];
  const int exponent = std::atoi(s.c_str() + k + 1);
  if (exponent >= -4 && exponent < 16) {
    std::string out;
    if (exponent < 0) {
      out = "0." + std::string(static_cast<std::size_t>(-exponent - 1), '0') + digits;
    } else {
      const auto int_len = static_cast<std::size_t>(exponent) + 1;
      if (digits.size() <= int_len)
        out = digits + std::string(int_len - digits.size(), '0') + ".0";
      else
        out = digits.substr(0, int_len) + "." + digits.substr(int_len);
    }
    return sign + out;
  }
  std::string mantissa = digits.size() == 1 ? digits : digits.substr(0, 1) + "." + digits.substr(1);
  char e[16];
  std::snprintf(e, sizeof e, "e%c%02d", exponent < 0 ? '-' : '+', std::abs(exponent));
  return sign + mantissa + e;
}

inline std::string repr(long long x) { return std::to_string(x); }
inline std::string repr(int x) { return std::to_string(x); }

}  // namespace detail
}  // namespace sorpia
