#include "objmap/report/summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "objmap/core/version.h"
#include "objmap/report/plots.h"
#include "objmap/report/svg.h"

namespace objmap::report {

namespace {

using io::RunSummary;
using nlohmann::json;

// The stages any recording ran, in the pipeline's order.
std::vector<std::string> stages_run(const std::vector<RunSummary>& runs) {
  std::vector<std::string> names;
  for (const io::RunStage& stage : io::run_stages())
    for (const RunSummary& r : runs)
      if (std::any_of(r.stages.begin(), r.stages.end(),
                      [&](const io::StageCost& c) { return c.stage == stage.name; })) {
        names.push_back(stage.name);
        break;
      }
  return names;
}

std::vector<std::string> classes_of(const std::vector<RunSummary>& runs) {
  std::set<std::string> classes;
  for (const RunSummary& r : runs)
    for (const auto& [cls, n] : r.objects_per_class) classes.insert(cls);
  return {classes.begin(), classes.end()};
}

const io::StageCost* cost_of(const RunSummary& r, const std::string& stage) {
  for (const io::StageCost& c : r.stages)
    if (c.stage == stage) return &c;
  return nullptr;
}

double total_seconds(const RunSummary& r) {
  double s = 0;
  for (const io::StageCost& c : r.stages) s += c.seconds;
  return s;
}

std::optional<double> peak_mb(const RunSummary& r) {
  std::optional<double> peak;
  for (const io::StageCost& c : r.stages)
    if (c.max_rss_mb) peak = std::max(peak.value_or(0.0), *c.max_rss_mb);
  return peak;
}

template <typename T>
json or_null(const std::optional<T>& v) {
  return v ? json(*v) : json(nullptr);
}

// One stage over all recordings that ran it.
struct StageTotals {
  std::string stage;
  int recordings = 0;
  double seconds_total = 0, seconds_max = 0;
  std::optional<double> max_rss_mb;
};

std::vector<StageTotals> stage_totals(const std::vector<RunSummary>& runs) {
  std::vector<StageTotals> totals;
  for (const std::string& stage : stages_run(runs)) {
    StageTotals t;
    t.stage = stage;
    for (const RunSummary& r : runs)
      if (const io::StageCost* c = cost_of(r, stage)) {
        ++t.recordings;
        t.seconds_total += c->seconds;
        t.seconds_max = std::max(t.seconds_max, c->seconds);
        if (c->max_rss_mb) t.max_rss_mb = std::max(t.max_rss_mb.value_or(0.0), *c->max_rss_mb);
      }
    totals.push_back(t);
  }
  return totals;
}

json recording_json(const RunSummary& r) {
  json stages = json::array();
  for (const io::StageCost& c : r.stages)
    stages.push_back(
        {{"stage", c.stage}, {"seconds", c.seconds}, {"max_rss_mb", or_null(c.max_rss_mb)}});
  return {
      {"name", r.name},
      {"path", r.path},
      {"status", r.status},
      {"failed_stage", r.failed_stage.empty() ? json(nullptr) : json(r.failed_stage)},
      {"error", r.error.empty() ? json(nullptr) : json(r.error)},
      {"map", r.map},
      {"keyframes", or_null(r.keyframes)},
      {"objects", or_null(r.objects)},
      {"objects_per_class", r.objects_per_class},
      {"duplicates", or_null(r.duplicates)},
      {"ate_rmse_m", or_null(r.ate_rmse_m)},
      {"rpe_translational_rmse_m", or_null(r.rpe_translational_rmse_m)},
      {"rpe_rotational_rmse_deg", or_null(r.rpe_rotational_rmse_deg)},
      {"ate_corrected_rmse_m", or_null(r.ate_corrected_rmse_m)},
      {"rpe_corrected_translational_rmse_m", or_null(r.rpe_corrected_translational_rmse_m)},
      {"gt_objects", or_null(r.gt_objects)},
      {"matched_objects", or_null(r.matched_objects)},
      {"count_error", or_null(r.count_error)},
      {"centroid_error_mean_m", or_null(r.centroid_error_mean_m)},
      {"centroid_error_rmse_m", or_null(r.centroid_error_rmse_m)},
      {"seconds", total_seconds(r)},
      {"max_rss_mb", or_null(peak_mb(r))},
      {"stages", stages},
  };
}

// Text of a number for Markdown: `decimals` digits, "-" when absent.
template <typename T>
std::string md(const std::optional<T>& v, int decimals) {
  if (!v) return "-";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, static_cast<double>(*v));
  return text;
}

// A Markdown cell: '|' and line breaks would break the table.
std::string cell(std::string text) {
  std::string out;
  for (char c : text) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n' || c == '\r')
      out += ' ';
    else
      out += c;
  }
  return out;
}

std::string row(const std::vector<std::string>& cells) {
  std::string line = "|";
  for (const std::string& c : cells) line += " " + c + " |";
  return line + "\n";
}

// The header and its rule: the first `text_columns` columns left-aligned, the numbers right.
std::string header(const std::vector<std::string>& cells, std::size_t text_columns = 1) {
  std::string rule = "|";
  for (std::size_t i = 0; i < cells.size(); ++i) rule += i < text_columns ? "---|" : "--:|";
  return row(cells) + rule + "\n";
}

int count_status(const std::vector<RunSummary>& runs, const std::string& status) {
  return static_cast<int>(std::count_if(runs.begin(), runs.end(),
                                        [&](const RunSummary& r) { return r.status == status; }));
}

std::string recordings_table(const std::vector<RunSummary>& runs) {
  std::string text =
      header({"recording", "status", "keyframes", "objects", "duplicates", "ATE RMSE (m)",
              "RPE RMSE (m)", "RPE RMSE (deg)", "ATE corrected (m)", "GT objects", "matched",
              "centroid error mean (m)", "time (s)", "peak memory (MB)"},
             2);
  for (const RunSummary& r : runs)
    text += row({cell(r.name), r.status == "failed" ? "failed (" + r.failed_stage + ")" : r.status,
                 md(r.keyframes, 0), md(r.objects, 0), md(r.duplicates, 0), md(r.ate_rmse_m, 4),
                 md(r.rpe_translational_rmse_m, 4), md(r.rpe_rotational_rmse_deg, 3),
                 md(r.ate_corrected_rmse_m, 4), md(r.gt_objects, 0), md(r.matched_objects, 0),
                 md(r.centroid_error_mean_m, 4), md(std::optional<double>(total_seconds(r)), 2),
                 md(peak_mb(r), 0)});
  return text;
}

std::string classes_table(const std::vector<RunSummary>& runs) {
  const std::vector<std::string> classes = classes_of(runs);
  std::vector<std::string> head = {"recording"};
  for (const std::string& c : classes) head.push_back(cell(c));
  std::string text = header(head);
  for (const RunSummary& r : runs) {
    std::vector<std::string> cells = {cell(r.name)};
    for (const std::string& c : classes) {
      const auto it = r.objects_per_class.find(c);
      cells.push_back(it == r.objects_per_class.end() ? "0" : std::to_string(it->second));
    }
    text += row(cells);
  }
  return text;
}

std::string stages_table(const std::vector<RunSummary>& runs) {
  std::string text = header({"stage", "recordings", "mean time (s)", "max time (s)",
                             "total time (s)", "max peak memory (MB)"});
  for (const StageTotals& t : stage_totals(runs))
    text += row({t.stage, std::to_string(t.recordings),
                 md(std::optional<double>(t.seconds_total / std::max(t.recordings, 1)), 2),
                 md(std::optional<double>(t.seconds_max), 2),
                 md(std::optional<double>(t.seconds_total), 2), md(t.max_rss_mb, 0)});
  return text;
}

// CSV field: quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csv_value(const json& v) {
  if (v.is_null()) return "";
  if (v.is_string()) return csv_field(v.get<std::string>());
  return v.dump();  // numbers: the shortest text that reads back the same value
}

}  // namespace

std::string summary_markdown(const std::vector<RunSummary>& runs) {
  std::string text = "# objmap summary\n\n" + std::to_string(runs.size()) +
                     " recordings: " + std::to_string(count_status(runs, "ok")) + " ok, " +
                     std::to_string(count_status(runs, "failed")) + " failed, " +
                     std::to_string(count_status(runs, "incomplete")) + " incomplete.\n\n";
  text += recordings_table(runs);
  if (count_status(runs, "failed") > 0) {
    text += "\n## Failed\n\n";
    for (const RunSummary& r : runs)
      if (r.status == "failed")
        text += "- " + r.name + ": stage " + r.failed_stage + ": `" + r.error + "` (" + r.path +
                "/logs/" + r.failed_stage + ".log)\n";
  }
  text += "\n## Objects per class\n\n" + classes_table(runs);
  text += "\n## Time and memory per stage\n\n" + stages_table(runs);
  text += "\n![objects per recording](objects.svg)\n\n![errors per recording](errors.svg)\n";
  return text;
}

std::string summary_csv(const std::vector<RunSummary>& runs) {
  static const std::vector<std::string> fixed = {"name",
                                                 "status",
                                                 "failed_stage",
                                                 "error",
                                                 "map",
                                                 "keyframes",
                                                 "objects",
                                                 "duplicates",
                                                 "ate_rmse_m",
                                                 "rpe_translational_rmse_m",
                                                 "rpe_rotational_rmse_deg",
                                                 "ate_corrected_rmse_m",
                                                 "rpe_corrected_translational_rmse_m",
                                                 "gt_objects",
                                                 "matched_objects",
                                                 "count_error",
                                                 "centroid_error_mean_m",
                                                 "centroid_error_rmse_m",
                                                 "seconds",
                                                 "max_rss_mb"};
  const std::vector<std::string> stages = stages_run(runs);
  const std::vector<std::string> classes = classes_of(runs);
  std::vector<std::string> head = fixed;
  for (const std::string& s : stages) {
    head.push_back("seconds_" + s);
    head.push_back("max_rss_mb_" + s);
  }
  for (const std::string& c : classes) head.push_back("objects_" + c);
  std::string text;
  for (std::size_t i = 0; i < head.size(); ++i) text += (i ? "," : "") + csv_field(head[i]);
  text += "\n";
  for (const RunSummary& r : runs) {
    const json j = recording_json(r);
    std::vector<std::string> cells;
    for (const std::string& f : fixed) cells.push_back(csv_value(j.at(f)));
    for (const std::string& s : stages) {
      const io::StageCost* c = cost_of(r, s);
      cells.push_back(c ? csv_value(c->seconds) : "");
      cells.push_back(c ? csv_value(or_null(c->max_rss_mb)) : "");
    }
    for (const std::string& c : classes) {
      const auto it = r.objects_per_class.find(c);
      cells.push_back(std::to_string(it == r.objects_per_class.end() ? 0 : it->second));
    }
    for (std::size_t i = 0; i < cells.size(); ++i) text += (i ? "," : "") + cells[i];
    text += "\n";
  }
  return text;
}

std::string summary_json(const std::vector<RunSummary>& runs) {
  json recordings = json::array();
  long long objects = 0;
  double seconds = 0;
  for (const RunSummary& r : runs) {
    recordings.push_back(recording_json(r));
    objects += r.objects.value_or(0);
    seconds += total_seconds(r);
  }
  json stages = json::array();
  for (const StageTotals& t : stage_totals(runs))
    stages.push_back({{"stage", t.stage},
                      {"recordings", t.recordings},
                      {"seconds_total", t.seconds_total},
                      {"seconds_mean", t.seconds_total / std::max(t.recordings, 1)},
                      {"seconds_max", t.seconds_max},
                      {"max_rss_mb", or_null(t.max_rss_mb)}});
  const json doc = {{"schema_version", 1},
                    {"generator", std::string("objmap ") + objmap::version()},
                    {"totals",
                     {{"recordings", runs.size()},
                      {"ok", count_status(runs, "ok")},
                      {"failed", count_status(runs, "failed")},
                      {"incomplete", count_status(runs, "incomplete")},
                      {"objects", objects},
                      {"seconds", seconds}}},
                    {"recordings", recordings},
                    {"stages", stages}};
  return doc.dump(2) + "\n";
}

namespace {

// One series of a bar chart: a value (or none) per recording.
struct Bars {
  std::string name;
  Rgb color;
  std::vector<std::optional<double>> values;
};

// Horizontal bars, one group per recording (its name on the left), a value axis at the bottom
// with "nice" ticks in `unit`, a legend on top; each bar is labelled with its value.
std::string bar_chart_svg(const std::string& title, const std::string& unit,
                          const std::vector<std::string>& labels, const std::vector<Bars>& series) {
  const double left = 170, right = 70, top = 56, bar = 14, gap = 10, width = 640;
  const double group = bar * series.size() + gap;
  const double height = top + group * labels.size() + 46;
  Svg svg(width, height);
  svg.text(10, 20, title, {{"font-size", "15"}, {"font-weight", "bold"}});
  double max_value = 0;
  for (const Bars& b : series)
    for (const auto& v : b.values)
      if (v) max_value = std::max(max_value, *v);
  if (max_value <= 0) max_value = 1;
  const std::vector<double> ticks = nice_ticks(0.0, max_value, 5);
  const double axis_max = std::max(ticks.back(), max_value);
  const double plot_w = width - left - right;
  auto x_of = [&](double v) { return left + v / axis_max * plot_w; };
  const double bottom = top + group * labels.size();
  const AxisLabels tick_labels = axis_labels(ticks, unit);
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    svg.line(x_of(ticks[i]), top - 4, x_of(ticks[i]), bottom, {{"stroke", "#dddddd"}});
    svg.text(x_of(ticks[i]), bottom + 16, tick_labels.ticks[i],
             {{"font-size", "11"}, {"text-anchor", "middle"}});
  }
  svg.text(left + plot_w / 2, bottom + 34,
           tick_labels.unit.empty() ? "" : "[" + tick_labels.unit + "]",
           {{"font-size", "11"}, {"text-anchor", "middle"}});
  double lx = left;
  for (const Bars& b : series) {
    svg.rect(lx, 32, 12, 10, {{"fill", hex_color(b.color)}});
    svg.text(lx + 16, 41, b.name, {{"font-size", "12"}});
    lx += 24 + 7 * b.name.size();
  }
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const double y0 = top + group * i;
    svg.text(left - 8, y0 + group / 2, labels[i], {{"font-size", "12"}, {"text-anchor", "end"}});
    for (std::size_t k = 0; k < series.size(); ++k) {
      const auto& v = series[k].values[i];
      const double y = y0 + bar * k;
      if (!v) {
        svg.text(left + 4, y + bar - 3, "-", {{"font-size", "11"}});
        continue;
      }
      svg.rect(left, y, x_of(*v) - left, bar - 2, {{"fill", hex_color(series[k].color)}});
      svg.text(x_of(*v) + 4, y + bar - 3, svg_number(*v, 4), {{"font-size", "11"}});
    }
  }
  return svg.str();
}

}  // namespace

std::string objects_per_recording_svg(const std::vector<RunSummary>& runs) {
  std::vector<std::string> labels;
  Bars objects{"objects", Rgb{70, 110, 180}, {}};
  Bars duplicates{"suspected duplicate pairs", Rgb{150, 150, 150}, {}};
  for (const RunSummary& r : runs) {
    labels.push_back(r.status == "failed" ? r.name + " (failed)" : r.name);
    objects.values.push_back(r.objects ? std::optional<double>(*r.objects) : std::nullopt);
    duplicates.values.push_back(r.duplicates ? std::optional<double>(*r.duplicates) : std::nullopt);
  }
  return bar_chart_svg("Objects per recording", "", labels, {objects, duplicates});
}

std::string errors_per_recording_svg(const std::vector<RunSummary>& runs) {
  std::vector<std::string> labels;
  Bars ate{"ATE RMSE", Rgb{200, 90, 40}, {}};
  Bars centroid{"object centroid error (mean)", Rgb{60, 140, 90}, {}};
  bool any = false;
  for (const RunSummary& r : runs) {
    labels.push_back(r.name);
    ate.values.push_back(r.ate_rmse_m);
    centroid.values.push_back(r.centroid_error_mean_m);
    any = any || r.ate_rmse_m || r.centroid_error_mean_m;
  }
  return bar_chart_svg(any ? "Errors per recording" : "Errors per recording: no ground truth", "m",
                       labels, {ate, centroid});
}

}  // namespace objmap::report
