#pragma once
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "objmap/core/types.h"

// A tiny SVG writer for the report's plots: every element is written with its attributes quoted and
// every text escaped, so the document is well-formed XML (it parses standalone as an .svg file and
// inline in an HTML page). No ids are written, so several plots can share one page.
namespace objmap::report {

// Text for XML/HTML content and attribute values: & < > " ' as entities; control characters other
// than tab, newline and carriage return (not allowed in XML 1.0) are dropped.
std::string xml_escape(std::string_view text);

// "#rrggbb".
std::string hex_color(const Rgb& color);

// One attribute: name (written as is: use literal names) and value (escaped when written).
using SvgAttributes = std::vector<std::pair<std::string, std::string>>;

// Number text for coordinates: fixed point with at most `decimals` digits, trailing zeros dropped.
std::string svg_number(double value, int decimals = 2);

class Svg {
 public:
  // A canvas of width × height user units (= CSS pixels), origin top-left, y down.
  Svg(double width, double height);

  double width() const { return width_; }
  double height() const { return height_; }

  void line(double x1, double y1, double x2, double y2, const SvgAttributes& attributes);
  void polyline(const std::vector<std::pair<double, double>>& points,
                const SvgAttributes& attributes);
  void rect(double x, double y, double width, double height, const SvgAttributes& attributes);
  void circle(double cx, double cy, double r, const SvgAttributes& attributes);
  void text(double x, double y, std::string_view text, const SvgAttributes& attributes);
  // A <title> child of the last opened group (a tooltip in browsers).
  void title(std::string_view text);
  void open_group(const SvgAttributes& attributes);
  void close_group();

  // The document: <svg xmlns=... width height viewBox> ... </svg>, groups closed.
  std::string str() const;

 private:
  void element(const std::string& name, const SvgAttributes& attributes);
  double width_, height_;
  std::string body_;
  int open_groups_ = 0;
};

}  // namespace objmap::report
