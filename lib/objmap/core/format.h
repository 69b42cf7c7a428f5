#pragma once
#include <string>

// Number text for messages and tables.
namespace objmap {

// Shortest text that reads back to the same double ("0.02", "1e-06").
std::string number_text(double value);
// Fixed-point text with `decimals` digits after the point ("0.013473").
std::string fixed_text(double value, int decimals);

}  // namespace objmap
