#include "objmap/report/plots.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/report/svg.h"
#include "xml_check.h"

namespace objmap::report {
namespace {

using test::count_of;
using test::xml_problem;

// A circle of n poses in the z = 0 plane, radius r, one pose per 0.1 s.
PlotSeries circle(const std::string& name, int n, double r, bool with_errors) {
  PlotSeries s;
  s.name = name;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    s.stamps_s.push_back(100.0 + 0.1 * i);
    s.positions_m.push_back(Vec3(r * std::cos(a), r * std::sin(a), 0.0));
    if (with_errors) s.errors_m.push_back(0.01 * (i % 5));
  }
  return s;
}

TEST(Plots, ErrorColoursGoFromBlueToRed) {
  const Rgb low = error_color(0.0), high = error_color(1.0);
  EXPECT_GT(low.b, low.r);
  EXPECT_GT(high.r, high.b);
  EXPECT_EQ(error_color(-3.0), low);  // clamped
  EXPECT_EQ(error_color(7.0), high);
  EXPECT_EQ(error_color(std::numeric_limits<double>::quiet_NaN()), (Rgb{150, 150, 150}));
}

TEST(Plots, NiceTicks) {
  const auto t = nice_ticks(0.0, 1.0, 5);
  ASSERT_EQ(t.size(), 6u);
  EXPECT_DOUBLE_EQ(t[1], 0.2);
  EXPECT_DOUBLE_EQ(t.back(), 1.0);
  const auto u = nice_ticks(-0.23, 0.41, 4);  // step 0.2: -0.2, 0, 0.2, 0.4
  ASSERT_EQ(u.size(), 4u);
  EXPECT_DOUBLE_EQ(u[1], 0.0);
  EXPECT_TRUE(nice_ticks(1.0, 1.0, 4).empty());
}

TEST(Plots, TrajectoryPlotHasOnePolylinePerSeries) {
  PlotSeries gt = circle("ground truth", 40, 1.0, false);
  gt.dashed = true;
  const PlotSeries est = circle("estimated <run>", 40, 1.02, true);
  std::string doc = trajectory_svg({gt, est}, PlotOptions{});
  EXPECT_EQ(xml_problem(doc), "") << doc;
  EXPECT_EQ(count_of(doc, "<polyline"), 2u);
  EXPECT_EQ(count_of(doc, "stroke-dasharray"), 2u);  // the dashed line and its legend entry
  EXPECT_NE(doc.find("estimated &lt;run&gt;"), std::string::npos);
  EXPECT_NE(doc.find("error [m]"), std::string::npos);  // the colour bar is there
  // The estimate's 40 poses make 39 segments coloured by their mean error on a 0..0.04 m scale:
  // the 8 segments from 0.03 to 0.04 m in the colour of 0.875.
  const auto group = doc.find("<g stroke-width=");
  ASSERT_NE(group, std::string::npos);
  const std::string segments = doc.substr(group, doc.find("</g>", group) - group);
  EXPECT_EQ(count_of(segments, "<line"), 39u);
  EXPECT_EQ(count_of(segments, "stroke=\"" + hex_color(error_color(0.875)) + "\""), 8u);

  doc = trajectory_svg({gt, est, circle("corrected", 40, 0.99, true)}, PlotOptions{});
  EXPECT_EQ(xml_problem(doc), "") << doc;
  EXPECT_EQ(count_of(doc, "<polyline"), 3u);
  // A plain trajectory alone: one polyline, no colour bar.
  doc = trajectory_svg({circle("estimated", 10, 1.0, false)}, PlotOptions{});
  EXPECT_EQ(count_of(doc, "<polyline"), 1u);
  EXPECT_EQ(doc.find("error [m]"), std::string::npos);
}

TEST(Plots, ErrorOverTimeShowsEachSeriesWithItsRmse) {
  PlotSeries a = circle("estimated", 4, 1.0, false);
  a.errors_m = {0.3, 0.4, std::numeric_limits<double>::quiet_NaN(), 0.0};  // NaN skipped
  const PlotSeries gt = circle("ground truth", 4, 1.0, false);             // no errors: not drawn
  const std::string doc = error_over_time_svg({gt, a}, PlotOptions{});
  EXPECT_EQ(xml_problem(doc), "") << doc;
  EXPECT_EQ(count_of(doc, "<polyline"), 1u);
  // RMSE of 0.3, 0.4, 0 = sqrt(0.25 / 3) = 0.2887
  EXPECT_NE(doc.find("estimated (RMSE 0.2887 m)"), std::string::npos) << doc;
  const auto start = doc.find("<polyline points=\"");
  const std::string points = doc.substr(start, doc.find('"', start + 18) - start);
  EXPECT_EQ(count_of(points, ","), 3u) << points;
}

TEST(Plots, AxisLabelsSayTheTicksAtAnyScale) {
  // Metres with the decimals the step needs.
  AxisLabels l = axis_labels({0.0, 0.05, 0.1, 0.15}, "m");
  EXPECT_EQ(l.ticks, (std::vector<std::string>{"0.00", "0.05", "0.10", "0.15"}));
  EXPECT_EQ(l.unit, "m");
  // An almost perfect trajectory's errors: nanometres, not "0, 0, 0, 0".
  l = axis_labels(nice_ticks(0.0, 6.3e-8, 4), "m");
  EXPECT_EQ(l.ticks, (std::vector<std::string>{"0", "20", "40", "60"}));
  EXPECT_EQ(l.unit, "nm");
  l = axis_labels({0.0, 2e-4, 4e-4, 6e-4}, "m");
  EXPECT_EQ(l.ticks, (std::vector<std::string>{"0", "200", "400", "600"}));
  EXPECT_EQ(l.unit, "µm");
  l = axis_labels({0.0, 5e-4, 1e-3, 1.5e-3}, "m");
  EXPECT_EQ(l.ticks, (std::vector<std::string>{"0.0", "0.5", "1.0", "1.5"}));
  EXPECT_EQ(l.unit, "mm");
  l = axis_labels({0.0, 1e5, 2e5}, "s");  // large: a prefix too
  EXPECT_EQ(l.ticks, (std::vector<std::string>{"0", "100", "200"}));
  EXPECT_EQ(l.unit, "ks");
  l = axis_labels({0.0, 1e-21, 2e-21}, "m");  // beyond the prefixes: a power of ten
  EXPECT_EQ(l.ticks, (std::vector<std::string>{"0", "1", "2"}));
  EXPECT_EQ(l.unit, "×10^-21 m");
  // Every scale from 1e-12 to 1e9: as many labels as ticks, all different.
  for (int e = -12; e <= 9; ++e)
    for (const double span : {1.0, 3.7, 6.3}) {
      const double hi = span * std::pow(10.0, e);
      const auto ticks = nice_ticks(0.0, hi, 5);
      const AxisLabels a = axis_labels(ticks, "m");
      ASSERT_EQ(a.ticks.size(), ticks.size());
      std::set<std::string> distinct(a.ticks.begin(), a.ticks.end());
      EXPECT_EQ(distinct.size(), ticks.size()) << "0.." << hi << " " << a.unit;
      for (const std::string& t : a.ticks) EXPECT_LE(t.size(), 7u) << t << " of 0.." << hi;
    }
}

TEST(Plots, ErrorOverTimeOfANearlyPerfectTrajectoryIsInNanometres) {
  PlotSeries a = circle("estimated", 4, 1.0, false);
  a.errors_m = {1e-8, 3e-8, 5e-8, 2e-8};
  const std::string doc = error_over_time_svg({a}, PlotOptions{});
  EXPECT_EQ(xml_problem(doc), "") << doc;
  EXPECT_NE(doc.find("absolute error [nm]"), std::string::npos) << doc;
  EXPECT_NE(doc.find(">40</text>"), std::string::npos) << doc;  // a tick at 40 nm
  EXPECT_NE(doc.find("(RMSE 3.12e-08 m)"), std::string::npos) << doc;
  const std::string bar = trajectory_svg({a}, PlotOptions{});
  EXPECT_NE(bar.find("error [nm]"), std::string::npos) << bar;  // the colour bar's unit
}

TEST(Plots, BadOptionsAreNamed) {
  PlotOptions options;
  options.width_px = 10;
  try {
    trajectory_svg({}, options);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("PlotOptions.width_px"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace objmap::report
