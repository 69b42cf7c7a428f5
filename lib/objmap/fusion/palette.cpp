#include "objmap/fusion/palette.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

namespace {

// HSV (h in [0,1), s, v in [0,1]) to 8-bit RGB.
Rgb hsv(double h, double s, double v) {
  const double h6 = h * 6.0;
  const int i = static_cast<int>(std::floor(h6)) % 6;
  const double f = h6 - std::floor(h6);
  const double p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r = 0, g = 0, b = 0;
  switch (i) {
    case 0:
      r = v, g = t, b = p;
      break;
    case 1:
      r = q, g = v, b = p;
      break;
    case 2:
      r = p, g = v, b = t;
      break;
    case 3:
      r = p, g = q, b = v;
      break;
    case 4:
      r = t, g = p, b = v;
      break;
    default:
      r = v, g = p, b = q;
      break;
  }
  auto byte = [](double x) { return static_cast<std::uint8_t>(std::lround(x * 255.0)); };
  return {byte(r), byte(g), byte(b)};
}

const std::map<std::string, Rgb>& palette() {
  static const std::map<std::string, Rgb> table = [] {
    std::map<std::string, Rgb> t;
    const auto& names = segmentation::coco80_names();
    for (std::size_t i = 0; i < names.size(); ++i) {
      const double hue = std::fmod(0.11 + 0.618033988749895 * static_cast<double>(i), 1.0);
      t[names[i]] = hsv(hue, 0.65, 0.9);
    }
    // The eight classes of the desk/office scenes: hand-picked, well separated.
    t["person"] = {220, 20, 60};       // crimson
    t["chair"] = {255, 127, 14};       // orange
    t["tv monitor"] = {31, 119, 180};  // blue
    t["keyboard"] = {148, 103, 189};   // purple
    t["mouse"] = {23, 190, 207};       // cyan
    t["cup"] = {44, 160, 44};          // green
    t["book"] = {188, 189, 34};        // olive
    t["teddy bear"] = {140, 86, 75};   // brown
    return t;
  }();
  return table;
}

}  // namespace

Rgb class_color(const std::string& class_name) {
  const auto& t = palette();
  const auto it = t.find(segmentation::canonical_class(class_name));
  return it == t.end() ? Rgb{128, 128, 128} : it->second;
}

}  // namespace objmap::fusion
