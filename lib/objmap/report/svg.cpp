#include "objmap/report/svg.h"

#include <cmath>
#include <cstdio>

namespace objmap::report {

std::string xml_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20 && ch != '\t' && ch != '\n' && ch != '\r') break;
        out += ch;
    }
  }
  return out;
}

std::string hex_color(const Rgb& color) {
  char s[8];
  std::snprintf(s, sizeof s, "#%02x%02x%02x", color.r, color.g, color.b);
  return s;
}

std::string svg_number(double value, int decimals) {
  if (!std::isfinite(value)) return "0";
  char s[64];
  std::snprintf(s, sizeof s, "%.*f", decimals, value);
  std::string out = s;
  if (out.find('.') != std::string::npos) {
    while (!out.empty() && out.back() == '0') out.pop_back();
    if (!out.empty() && out.back() == '.') out.pop_back();
  }
  if (out == "-0") out = "0";
  return out;
}

Svg::Svg(double width, double height) : width_(width), height_(height) {}

void Svg::element(const std::string& name, const SvgAttributes& attributes) {
  body_ += "<" + name;
  for (const auto& [key, value] : attributes) body_ += " " + key + "=\"" + xml_escape(value) + "\"";
}

void Svg::line(double x1, double y1, double x2, double y2, const SvgAttributes& attributes) {
  SvgAttributes all = {{"x1", svg_number(x1)},
                       {"y1", svg_number(y1)},
                       {"x2", svg_number(x2)},
                       {"y2", svg_number(y2)}};
  all.insert(all.end(), attributes.begin(), attributes.end());
  element("line", all);
  body_ += "/>\n";
}

void Svg::polyline(const std::vector<std::pair<double, double>>& points,
                   const SvgAttributes& attributes) {
  std::string pts;
  for (const auto& [x, y] : points) {
    if (!pts.empty()) pts += ' ';
    pts += svg_number(x) + "," + svg_number(y);
  }
  SvgAttributes all = {{"points", pts}, {"fill", "none"}};
  all.insert(all.end(), attributes.begin(), attributes.end());
  element("polyline", all);
  body_ += "/>\n";
}

void Svg::rect(double x, double y, double width, double height, const SvgAttributes& attributes) {
  SvgAttributes all = {{"x", svg_number(x)},
                       {"y", svg_number(y)},
                       {"width", svg_number(width)},
                       {"height", svg_number(height)}};
  all.insert(all.end(), attributes.begin(), attributes.end());
  element("rect", all);
  body_ += "/>\n";
}

void Svg::circle(double cx, double cy, double r, const SvgAttributes& attributes) {
  SvgAttributes all = {{"cx", svg_number(cx)}, {"cy", svg_number(cy)}, {"r", svg_number(r)}};
  all.insert(all.end(), attributes.begin(), attributes.end());
  element("circle", all);
  body_ += "/>\n";
}

void Svg::text(double x, double y, std::string_view text, const SvgAttributes& attributes) {
  SvgAttributes all = {{"x", svg_number(x)}, {"y", svg_number(y)}};
  all.insert(all.end(), attributes.begin(), attributes.end());
  element("text", all);
  body_ += ">" + xml_escape(text) + "</text>\n";
}

void Svg::title(std::string_view text) { body_ += "<title>" + xml_escape(text) + "</title>\n"; }

void Svg::open_group(const SvgAttributes& attributes) {
  element("g", attributes);
  body_ += ">\n";
  ++open_groups_;
}

void Svg::close_group() {
  if (open_groups_ == 0) return;
  body_ += "</g>\n";
  --open_groups_;
}

std::string Svg::str() const {
  std::string out = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + svg_number(width_) +
                    "\" height=\"" + svg_number(height_) + "\" viewBox=\"0 0 " +
                    svg_number(width_) + " " + svg_number(height_) +
                    "\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n";
  out += body_;
  for (int i = 0; i < open_groups_; ++i) out += "</g>\n";
  out += "</svg>\n";
  return out;
}

}  // namespace objmap::report
