#pragma once
#include <string>
#include <vector>

#include "objmap/core/types.h"

// The report's plots as SVG documents: trajectories seen from above, coloured by their absolute
// trajectory error, and the error over time.
namespace objmap::report {

// A colour for a value in [0, 1] (clamped; NaN gives grey): blue → cyan → green → amber → red,
// every colour dark enough to read on white.
Rgb error_color(double t);

// One trajectory of a plot.
struct PlotSeries {
  std::string name;               // legend: "ground truth", "estimated", "corrected"
  Rgb color{60, 60, 60};          // the line (a plain series) or the casing of a coloured one
  bool dashed = false;            // a dashed line (the ground truth)
  std::vector<double> stamps_s;   // per pose, seconds
  std::vector<Vec3> positions_m;  // per pose, world (the ground truth's frame when aligned)
  std::vector<double> errors_m;   // per pose absolute error, NaN for a pose without one; empty:
                                  // the series is not coloured (the ground truth)
};

struct PlotOptions {
  double width_px = 560;   // the whole SVG
  double height_px = 440;  // the whole SVG
  int up_axis = 2;         // trajectory plot: the world axis that points up (drawn from above)
  void check() const;      // throws InputError naming the bad field
};

// Top view of the trajectories on equal axes with a metre grid: each series is ONE <polyline> (the
// ground truth dashed); a series with errors is also drawn as short segments coloured by error on a
// scale shared by all series, with a colour bar in metres. The legend names each series.
std::string trajectory_svg(const std::vector<PlotSeries>& series, const PlotOptions& options);

// The absolute error of each series that has errors against time since the first stamp: ONE
// <polyline> per such series (NaN errors skipped), axes in seconds and metres, legend with RMSE.
std::string error_over_time_svg(const std::vector<PlotSeries>& series, const PlotOptions& options);

// The tick labels of an axis and the unit they are in: as many decimals as the step needs (at any
// scale); when the ticks would need more than 3 decimals or reach 100000, they are written in
// the unit with an SI prefix (0.00000005 m → "50" nm; 1.5e5 s → "150" ks), or with "×10^k" beyond
// the prefixes. Every two different ticks get different labels.
struct AxisLabels {
  std::vector<std::string> ticks;  // one per tick
  std::string unit;                // e.g. "m", "mm", "nm", "×10^-21 m"
};
AxisLabels axis_labels(const std::vector<double>& ticks, const std::string& unit);

// "Nice" tick positions (1, 2, 5 × 10^k steps) covering [lo, hi], about `target` of them.
std::vector<double> nice_ticks(double lo, double hi, int target);

}  // namespace objmap::report
