#pragma once
#include <cstdio>
#include <string>

namespace objmap::sim {

// A number for a message: "%g" (2, 0.125, 1e-05), not std::to_string's "2.000000".
inline std::string num(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

}  // namespace objmap::sim
