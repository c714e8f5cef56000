#pragma once
// Counts in messages: "1 body", "2 bodies", "every 2nd snapshot".
#include <string>

namespace mbsflow {

// "N thing" or "N things" (the plural given where it is not thing + "s").
inline std::string count_of(long long n, const std::string& one, const std::string& many = "") {
  return std::to_string(n) + " " + (n == 1 ? one : many.empty() ? one + "s" : many);
}

// "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", ...
inline std::string ordinal(long long n) {
  const long long tens = n % 100, units = n % 10;
  const char* suffix = tens >= 11 && tens <= 13 ? "th" : units == 1 ? "st" : units == 2 ? "nd" : units == 3 ? "rd" : "th";
  return std::to_string(n) + suffix;
}

}  // namespace mbsflow
