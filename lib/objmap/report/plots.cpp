#include "objmap/report/plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "objmap/core/error.h"
#include "objmap/report/svg.h"

namespace objmap::report {

Rgb error_color(double t) {
  if (!std::isfinite(t)) return Rgb{150, 150, 150};
  t = std::clamp(t, 0.0, 1.0);
  struct Anchor {
    double t;
    double r, g, b;
  };
  static const Anchor anchors[] = {{0.0, 40, 60, 190},
                                   {0.3, 25, 160, 200},
                                   {0.5, 50, 170, 70},
                                   {0.72, 235, 170, 20},
                                   {1.0, 205, 25, 30}};
  for (std::size_t i = 1; i < std::size(anchors); ++i) {
    const Anchor& a = anchors[i - 1];
    const Anchor& b = anchors[i];
    if (t <= b.t) {
      const double s = (t - a.t) / (b.t - a.t);
      const auto mix = [s](double x, double y) {
        return static_cast<std::uint8_t>(std::lround(x + s * (y - x)));
      };
      return Rgb{mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)};
    }
  }
  return Rgb{205, 25, 30};
}

void PlotOptions::check() const {
  require(std::isfinite(width_px) && width_px >= 200 && width_px <= 4000, "PlotOptions.width_px",
          "must be in [200, 4000]");
  require(std::isfinite(height_px) && height_px >= 150 && height_px <= 4000,
          "PlotOptions.height_px", "must be in [150, 4000]");
  require(up_axis >= 0 && up_axis <= 2, "PlotOptions.up_axis", "must be 0, 1 or 2 (x, y, z)");
}

namespace {
std::vector<double> ticks_with_step(double lo, double hi, double step);
}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi <= lo || target < 1) return ticks;
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * mag;
    if (step >= raw) break;
  }
  return ticks_with_step(lo, hi, step);
}

namespace {

std::vector<double> ticks_with_step(double lo, double hi, double step) {
  std::vector<double> ticks;
  if (!(step > 0) || !std::isfinite(lo) || !std::isfinite(hi)) return ticks;
  for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * step; k += 1.0)
    ticks.push_back(std::abs(k * step) < 1e-12 * step ? 0.0 : k * step);
  return ticks;
}

const std::string kGrid = "#e4e4e4";
const std::string kFrame = "#8a8a8a";
const std::string kText = "#333333";

double step_of(const std::vector<double>& ticks) {
  return ticks.size() >= 2 ? ticks[1] - ticks[0] : 1.0;
}

// The decimals that a step (in the unit written) needs: relative to the step itself, so that a
// step of 2e-8 needs 8 and a step of 0.1 one.
int decimals_of(double step) {
  int decimals = 0;
  while (decimals < 15) {
    const double scaled = std::abs(step) * std::pow(10.0, decimals);
    if (std::abs(scaled - std::round(scaled)) <= 1e-6 * scaled) break;
    ++decimals;
  }
  return decimals;
}

// The unit for a power of ten (a multiple of 3): an SI prefix, or "×10^k unit" beyond them.
std::string scaled_unit(int exponent, const std::string& unit) {
  static const char* const kPrefixes[] = {"p", "n", "µ", "m", "", "k", "M", "G", "T"};
  const int k = exponent / 3 + 4;
  if (exponent % 3 == 0 && k >= 0 && k < 9) return kPrefixes[k] + unit;
  return "×10^" + std::to_string(exponent) + " " + unit;
}

}  // namespace

AxisLabels axis_labels(const std::vector<double>& ticks, const std::string& unit) {
  AxisLabels labels;
  labels.unit = unit;
  double largest = 0;
  for (const double t : ticks) largest = std::max(largest, std::abs(t));
  const double step = std::abs(step_of(ticks));
  int exponent = 0;
  if (ticks.size() >= 2 && step > 0 && std::isfinite(step) &&
      (decimals_of(step) > 3 || largest >= 1e5)) {
    exponent = 3 * static_cast<int>(std::floor(std::log10(std::max(largest, step)) / 3.0));
    labels.unit = scaled_unit(exponent, unit);
  }
  const double scale = std::pow(10.0, -exponent);
  const int decimals = ticks.size() >= 2 ? decimals_of(step * scale) : 0;
  for (const double t : ticks) {
    char s[64];
    std::snprintf(s, sizeof s, "%.*f", decimals, t * scale);
    labels.ticks.push_back(std::string(s) == "-0" ? "0" : s);
  }
  return labels;
}

namespace {

bool has_errors(const PlotSeries& s) {
  return !s.errors_m.empty() && s.errors_m.size() == s.positions_m.size();
}

// Legend entries left to right along the top edge.
void legend(Svg& svg, const std::vector<PlotSeries>& series, double x, double y,
            const std::vector<std::string>& labels) {
  for (std::size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& s = series[i];
    SvgAttributes a = {{"stroke", hex_color(s.color)}, {"stroke-width", "2.5"}};
    if (s.dashed) a.push_back({"stroke-dasharray", "6 4"});
    svg.line(x, y - 4, x + 22, y - 4, a);
    svg.text(x + 27, y, labels[i], {{"fill", kText}});
    x += 27 + 6.6 * labels[i].size() + 16;
  }
}

// The colour bar: `steps` boxes from 0 (bottom) to max_error (top), ticks in metres.
void color_bar(Svg& svg, double x, double top, double bottom, double max_error) {
  const int steps = 48;
  const double h = (bottom - top) / steps;
  svg.open_group({{"stroke", "none"}});
  for (int i = 0; i < steps; ++i) {
    const double t = (i + 0.5) / steps;
    svg.rect(x, bottom - (i + 1) * h, 12, h + 0.3, {{"fill", hex_color(error_color(t))}});
  }
  svg.close_group();
  svg.rect(x, top, 12, bottom - top, {{"fill", "none"}, {"stroke", kFrame}});
  const auto ticks = nice_ticks(0.0, max_error, 4);
  const AxisLabels labels = axis_labels(ticks, "m");
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    const double y = bottom - ticks[i] / max_error * (bottom - top);
    svg.line(x + 12, y, x + 16, y, {{"stroke", kFrame}});
    svg.text(x + 18, y + 4, labels.ticks[i], {{"fill", kText}, {"font-size", "11"}});
  }
  svg.text(x - 6, top - 8, "error [" + labels.unit + "]", {{"fill", kText}, {"font-size", "11"}});
}

std::string axis_name(int axis, const std::string& unit) {
  return std::string(1, static_cast<char>('x' + axis)) + " [" + unit + "]";
}

// What a trajectory plot shows: the data's extent on the two horizontal axes and, when a series
// carries errors, the top of the colour scale.
struct PlanData {
  double a0 = 0, a1 = 0, b0 = 0, b1 = 0;
  double max_error = 0;
  bool colored = false;
};

// The extent of every series on the axes ax and bx (0..1 when there is none), and the largest
// error rounded up to a tick, so that the colour bar's top is labelled.
PlanData plan_data(const std::vector<PlotSeries>& series, int ax, int bx) {
  PlanData d;
  double a0 = std::numeric_limits<double>::infinity(), a1 = -a0, b0 = a0, b1 = -a0;
  for (const PlotSeries& s : series) {
    for (const Vec3& p : s.positions_m) {
      a0 = std::min(a0, p[ax]), a1 = std::max(a1, p[ax]);
      b0 = std::min(b0, p[bx]), b1 = std::max(b1, p[bx]);
    }
    if (has_errors(s)) {
      d.colored = true;
      for (const double e : s.errors_m)
        if (std::isfinite(e)) d.max_error = std::max(d.max_error, e);
    }
  }
  if (!std::isfinite(a0)) a0 = b0 = 0, a1 = b1 = 1;
  if (d.max_error <= 0) d.max_error = 1e-3;
  const auto t = nice_ticks(0.0, d.max_error, 4);
  const double step = step_of(t);
  d.max_error = std::ceil(d.max_error / step - 1e-9) * step;
  d.a0 = a0, d.a1 = a1, d.b0 = b0, d.b1 = b1;
  return d;
}

// The plot area in SVG units and the visible metres of an equal-axis fit.
struct PlanArea {
  double left = 0, top = 0, right = 0, bottom = 0, pw = 0, ph = 0;
  double scale = 0, va0 = 0, va1 = 0, vb0 = 0, vb1 = 0;
  double X(double a) const { return left + (a - va0) * scale; }
  double Y(double b) const { return bottom - (b - vb0) * scale; }
};

// Step 1: the plot area (room for the colour bar when coloured) and an equal-axis fit of the data
// (5% padding, at least 10 cm).
PlanArea fit_plan_area(const PlanData& d, const PlotOptions& options) {
  PlanArea v;
  v.left = 58, v.top = 34, v.right = options.width_px - (d.colored ? 78 : 16),
  v.bottom = options.height_px - 42;
  v.pw = v.right - v.left, v.ph = v.bottom - v.top;
  const double ra = std::max(0.1, (d.a1 - d.a0) * 1.1), rb = std::max(0.1, (d.b1 - d.b0) * 1.1);
  v.scale = std::min(v.pw / ra, v.ph / rb);
  const double ca = 0.5 * (d.a0 + d.a1), cb = 0.5 * (d.b0 + d.b1);
  v.va0 = ca - v.pw / (2 * v.scale), v.va1 = ca + v.pw / (2 * v.scale);
  v.vb0 = cb - v.ph / (2 * v.scale), v.vb1 = cb + v.ph / (2 * v.scale);
  return v;
}

// Step 2: the metre grid (one step on both axes), its labels, the frame and the axis names.
void plan_grid(Svg& svg, const PlanArea& v, int ax, int bx) {
  const int target = std::max(3, static_cast<int>(std::min(v.pw, v.ph) / 70));
  const auto ta = nice_ticks(v.va0, v.va1, target), tb = nice_ticks(v.vb0, v.vb1, target);
  const double step = std::min(step_of(ta), step_of(tb));
  const auto ga = ticks_with_step(v.va0, v.va1, step), gb = ticks_with_step(v.vb0, v.vb1, step);
  svg.open_group({{"stroke", kGrid}, {"stroke-width", "1"}});
  for (const double x : ga) svg.line(v.X(x), v.top, v.X(x), v.bottom, {});
  for (const double y : gb) svg.line(v.left, v.Y(y), v.right, v.Y(y), {});
  svg.close_group();
  // Both axes in one unit (equal axes): the labels of both sets of ticks made together.
  std::vector<double> both = ga;
  both.insert(both.end(), gb.begin(), gb.end());
  std::sort(both.begin(), both.end());
  both.erase(std::unique(both.begin(), both.end()), both.end());
  if (both.size() < 2) both.push_back(both.empty() ? step : both.back() + step);
  const AxisLabels labels = axis_labels(both, "m");
  const auto label = [&](double t) {
    const auto at = std::lower_bound(both.begin(), both.end(), t);
    return labels.ticks[static_cast<std::size_t>(at - both.begin())];
  };
  svg.open_group({{"fill", kText}, {"font-size", "11"}});
  for (const double x : ga) svg.text(v.X(x), v.bottom + 15, label(x), {{"text-anchor", "middle"}});
  for (const double y : gb) svg.text(v.left - 5, v.Y(y) + 4, label(y), {{"text-anchor", "end"}});
  svg.close_group();
  svg.rect(v.left, v.top, v.pw, v.ph, {{"fill", "none"}, {"stroke", kFrame}});
  svg.text(0.5 * (v.left + v.right), v.bottom + 33, axis_name(ax, labels.unit),
           {{"fill", kText}, {"text-anchor", "middle"}});
  const std::string ylabel_y = svg_number(0.5 * (v.top + v.bottom));
  svg.text(16, 0.5 * (v.top + v.bottom), axis_name(bx, labels.unit),
           {{"fill", kText},
            {"text-anchor", "middle"},
            {"transform", "rotate(-90 16 " + ylabel_y + ")"}});
}

// Step 3: the series: one polyline each (a casing under the error colours for coloured series;
// each further coloured series narrower, so that one drawn over another leaves it visible).
void plan_series(Svg& svg, const std::vector<PlotSeries>& series, const PlanArea& v, int ax, int bx,
                 double max_error) {
  int coloured_index = 0;
  for (const PlotSeries& s : series) {
    std::vector<std::pair<double, double>> pts;
    pts.reserve(s.positions_m.size());
    for (const Vec3& p : s.positions_m) pts.emplace_back(v.X(p[ax]), v.Y(p[bx]));
    const bool c = has_errors(s);
    const double casing = std::max(3.0, 6.5 - 2.5 * coloured_index);
    if (c) ++coloured_index;
    SvgAttributes a = {{"stroke", hex_color(s.color)},
                       {"stroke-width", c ? svg_number(casing) : "1.6"},
                       {"stroke-linejoin", "round"},
                       {"stroke-linecap", "round"}};
    if (s.dashed) a.push_back({"stroke-dasharray", "6 4"});
    svg.polyline(pts, a);
    if (!c) continue;
    svg.open_group({{"stroke-width", svg_number(casing - 2.2)}, {"stroke-linecap", "round"}});
    for (std::size_t i = 1; i < pts.size(); ++i) {
      const double e0 = s.errors_m[i - 1], e1 = s.errors_m[i];
      if (!std::isfinite(e0) || !std::isfinite(e1)) continue;
      svg.line(pts[i - 1].first, pts[i - 1].second, pts[i].first, pts[i].second,
               {{"stroke", hex_color(error_color(0.5 * (e0 + e1) / max_error))}});
    }
    svg.close_group();
    if (!pts.empty())  // the start
      svg.circle(pts.front().first, pts.front().second, 4,
                 {{"fill", "#ffffff"}, {"stroke", hex_color(s.color)}, {"stroke-width", "1.5"}});
  }
}

}  // namespace

std::string trajectory_svg(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  options.check();
  const int ax = (options.up_axis + 1) % 3, bx = (options.up_axis + 2) % 3;
  const PlanData data = plan_data(series, ax, bx);

  // 1. Plot area and an equal-axis fit of the data (5% padding, at least 10 cm).
  const PlanArea area = fit_plan_area(data, options);
  Svg svg(options.width_px, options.height_px);
  svg.rect(0, 0, options.width_px, options.height_px, {{"fill", "#ffffff"}});
  // 2. Metre grid and axes.
  plan_grid(svg, area, ax, bx);
  // 3. The series: one polyline each, coloured by the error where there is one.
  plan_series(svg, series, area, ax, bx, data.max_error);
  // 4. Legend and colour bar.
  std::vector<std::string> labels;
  for (const PlotSeries& s : series) labels.push_back(s.name);
  legend(svg, series, area.left, 20, labels);
  if (data.colored) color_bar(svg, area.right + 16, area.top + 14, area.bottom, data.max_error);
  return svg.str();
}

std::string error_over_time_svg(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  options.check();
  std::vector<PlotSeries> plotted;
  double t0 = std::numeric_limits<double>::infinity(), t1 = -t0, e1 = 0.0;
  for (const PlotSeries& s : series) {
    if (!has_errors(s) || s.stamps_s.size() != s.errors_m.size()) continue;
    plotted.push_back(s);
    for (std::size_t i = 0; i < s.errors_m.size(); ++i) {
      if (!std::isfinite(s.errors_m[i])) continue;
      t0 = std::min(t0, s.stamps_s[i]), t1 = std::max(t1, s.stamps_s[i]);
      e1 = std::max(e1, s.errors_m[i]);
    }
  }
  if (!std::isfinite(t0)) t0 = 0, t1 = 1;
  if (t1 - t0 <= 0) t1 = t0 + 1;
  if (e1 <= 0) e1 = 1e-3;

  const double left = 58, top = 34, right = options.width_px - 16, bottom = options.height_px - 42;
  const auto tt = nice_ticks(0.0, t1 - t0, 6);
  const auto te = nice_ticks(0.0, e1 * 1.05, 5);
  const double x_max = std::max(t1 - t0, tt.empty() ? 0.0 : tt.back());
  const double y_max = std::max(e1 * 1.05, te.empty() ? 0.0 : te.back());
  const auto X = [&](double t) { return left + (t - t0) / x_max * (right - left); };
  const auto Y = [&](double e) { return bottom - e / y_max * (bottom - top); };

  Svg svg(options.width_px, options.height_px);
  svg.rect(0, 0, options.width_px, options.height_px, {{"fill", "#ffffff"}});
  svg.open_group({{"stroke", kGrid}, {"stroke-width", "1"}});
  for (const double v : tt) svg.line(X(t0 + v), top, X(t0 + v), bottom, {});
  for (const double v : te) svg.line(left, Y(v), right, Y(v), {});
  svg.close_group();
  const AxisLabels time_labels = axis_labels(tt, "s"), error_labels = axis_labels(te, "m");
  svg.open_group({{"fill", kText}, {"font-size", "11"}});
  for (std::size_t i = 0; i < tt.size(); ++i)
    svg.text(X(t0 + tt[i]), bottom + 15, time_labels.ticks[i], {{"text-anchor", "middle"}});
  for (std::size_t i = 0; i < te.size(); ++i)
    svg.text(left - 5, Y(te[i]) + 4, error_labels.ticks[i], {{"text-anchor", "end"}});
  svg.close_group();
  svg.rect(left, top, right - left, bottom - top, {{"fill", "none"}, {"stroke", kFrame}});
  svg.text(0.5 * (left + right), bottom + 33,
           "time since the first pose [" + time_labels.unit + "]",
           {{"fill", kText}, {"text-anchor", "middle"}});
  const std::string mid = svg_number(0.5 * (top + bottom));
  svg.text(
      16, 0.5 * (top + bottom), "absolute error [" + error_labels.unit + "]",
      {{"fill", kText}, {"text-anchor", "middle"}, {"transform", "rotate(-90 16 " + mid + ")"}});

  std::vector<std::string> labels;
  for (const PlotSeries& s : plotted) {
    std::vector<std::pair<double, double>> pts;
    double sum2 = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < s.errors_m.size(); ++i) {
      if (!std::isfinite(s.errors_m[i])) continue;
      pts.emplace_back(X(s.stamps_s[i]), Y(s.errors_m[i]));
      sum2 += s.errors_m[i] * s.errors_m[i];
      ++n;
    }
    SvgAttributes a = {
        {"stroke", hex_color(s.color)}, {"stroke-width", "1.6"}, {"stroke-linejoin", "round"}};
    if (s.dashed) a.push_back({"stroke-dasharray", "6 4"});
    svg.polyline(pts, a);
    char rmse[64];
    const double r = n ? std::sqrt(sum2 / n) : 0.0;  // 4 decimals, or 3 digits below 1 mm
    std::snprintf(rmse, sizeof rmse, r >= 1e-3 || r == 0 ? " (RMSE %.4f m)" : " (RMSE %.3g m)", r);
    labels.push_back(s.name + rmse);
  }
  legend(svg, plotted, left, 20, labels);
  return svg.str();
}

}  // namespace objmap::report
