#include "objmap/report/page.h"
#include "objmap/core/format.h"

#include <cmath>
#include <cstdio>
#include <map>

#include "objmap/fusion/palette.h"
#include "objmap/report/html.h"
#include "objmap/report/svg.h"

namespace objmap::report {

namespace {

std::string count_text(double value) {  // 1234567 -> "1 234 567" (thin groups read at a glance)
  std::string digits = fixed_text(value, 0);
  std::string out;
  const std::size_t start = digits[0] == '-' ? 1 : 0;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > start && (digits.size() - i) % 3 == 0) out += ' ';
    out += digits[i];
  }
  return out;
}

// Metres with 4 decimals; below 0.1 mm (an almost perfect trajectory) 3 significant digits, so
// that the figure does not read 0.0000.
std::string metres_text(double value) {
  if (value == 0 || std::abs(value) >= 1e-4) return fixed_text(value, 4);
  char s[32];
  std::snprintf(s, sizeof s, "%.3g", value);
  return s;
}

std::string percent(double ratio) { return fixed_text(100.0 * ratio, 1) + "%"; }

std::map<std::string, int> per_class(const PageContent& c) {
  std::map<std::string, int> n;
  for (const PageObject& o : c.objects) ++n[o.object.class_name];
  return n;
}

std::optional<double> gt_distance(const PageContent& c, int map_id) {
  if (!c.object_eval) return std::nullopt;
  for (const eval::ObjectMatch& m : c.object_eval->result.matches)
    if (m.map_id == map_id) return m.distance_m;
  return std::nullopt;
}

Table ate_table(const PageContent& c) {
  Table t;
  t.caption = "Absolute trajectory error (aligned to the ground truth, metres)";
  t.header = {"trajectory", "pairs", "RMSE", "mean", "median", "std", "min", "max"};
  t.numeric = {false, true, true, true, true, true, true, true};
  for (const PageAte& a : c.ate)
    t.rows.push_back({a.name, std::to_string(a.stats.count), metres_text(a.stats.rmse),
                      metres_text(a.stats.mean), metres_text(a.stats.median),
                      metres_text(a.stats.stddev), metres_text(a.stats.min),
                      metres_text(a.stats.max)});
  return t;
}

Table objects_table(const PageContent& c) {
  Table t;
  t.caption =
      "Objects (objects.json): centroid in the world frame [m], points before and after "
      "the filters";
  t.header = {"id",   "class",        "x",    "y", "z", "points raw", "voxel-filtered",
              "kept", "observations", "score"};
  t.numeric = {true, false, true, true, true, true, true, true, true, true};
  if (c.object_eval) {
    t.header.push_back("error vs GT [m]");
    t.numeric.push_back(true);
  }
  for (const PageObject& p : c.objects) {
    const io::MappedObject& o = p.object;
    std::vector<std::string> row = {
        std::to_string(o.id),
        o.class_name,
        fixed_text(o.centroid.x(), 3),
        fixed_text(o.centroid.y(), 3),
        fixed_text(o.centroid.z(), 3),
        p.points_raw ? count_text(static_cast<double>(*p.points_raw)) : "-",
        p.points_voxel ? count_text(static_cast<double>(*p.points_voxel)) : "-",
        count_text(static_cast<double>(o.points)),
        std::to_string(o.observations),
        fixed_text(o.score, 2)};
    if (c.object_eval) {
      const auto d = gt_distance(c, o.id);
      row.push_back(d ? fixed_text(*d, 3) : "unmatched");
    }
    t.rows.push_back(row);
    t.swatches.push_back(hex_color(fusion::class_color(o.class_name)));
  }
  return t;
}

Table class_table(const PageContent& c) {
  Table t;
  t.total_row = "overall";
  if (c.object_eval) {
    t.caption = "Table 3: number of objects per class, against the ground truth";
    t.header = {"class", "ground truth", "mapped", "error"};
    t.numeric = {false, true, true, true};
    for (const eval::CountRow& r : c.object_eval->result.counts) {
      t.rows.push_back({r.class_name, std::to_string(r.reference), std::to_string(r.mapped),
                        r.error ? percent(*r.error) : "-"});
      t.swatches.push_back(
          r.class_name == "overall" ? "" : hex_color(fusion::class_color(r.class_name)));
    }
    return t;
  }
  t.caption = "Objects per class (no ground-truth objects given)";
  t.header = {"class", "objects"};
  t.numeric = {false, true};
  for (const auto& [name, n] : per_class(c)) {
    t.rows.push_back({name, std::to_string(n)});
    t.swatches.push_back(hex_color(fusion::class_color(name)));
  }
  t.rows.push_back({"overall", std::to_string(c.objects.size())});
  return t;
}

Table error_table(const eval::ObjectEvalReport& e) {
  Table t;
  t.caption = "Tables 4-5: centroid error of the matched objects [m] (one-to-one by class, gate " +
              fixed_text(e.options.gate_m, 2) + " m) and oriented-box IoU";
  t.header = {"class", "matched", "mean", "median", "max", "|dx|", "|dy|", "|dz|", "IoU"};
  t.numeric = {false, true, true, true, true, true, true, true, true};
  t.total_row = "overall";
  for (const eval::ErrorRow& r : e.result.errors) {
    const std::string matched = std::to_string(r.matched) + "/" + std::to_string(r.reference);
    if (r.matched == 0) {
      t.rows.push_back({r.class_name, matched, "-", "-", "-", "-", "-", "-", "-"});
    } else {
      t.rows.push_back({r.class_name, matched, fixed_text(r.distance_m.mean, 4),
                        fixed_text(r.distance_m.median, 4), fixed_text(r.distance_m.max, 4),
                        fixed_text(r.mean_abs_xyz_m.x(), 4), fixed_text(r.mean_abs_xyz_m.y(), 4),
                        fixed_text(r.mean_abs_xyz_m.z(), 4), fixed_text(r.iou.mean, 3)});
    }
    t.swatches.push_back(r.class_name == "overall" ? ""
                                                   : hex_color(fusion::class_color(r.class_name)));
  }
  return t;
}

Table precision_table(const eval::ObjectEvalReport& e) {
  Table t;
  t.caption = "Precision and recall (objects matched one-to-one by class within the distance)";
  t.header = {"within", "matched", "precision", "recall"};
  t.numeric = {true, true, true, true};
  for (const eval::PrecisionRecall& p : e.result.precision_recall)
    t.rows.push_back({fixed_text(p.threshold_m, 2) + " m", std::to_string(p.matched),
                      fixed_text(p.precision, 3), fixed_text(p.recall, 3)});
  return t;
}

Table points_table(const eval::PointCounts& p) {
  Table t;
  t.caption = "Table 6: map points (run.json)";
  t.header = {"map", "points"};
  t.numeric = {false, true};
  t.rows = {{"dense map", count_text(p.dense_map)},
            {"objects-only map", count_text(p.objects_map)},
            {"reduction", percent(p.reduction())},
            {"dense points back-projected", count_text(p.dense_back_projected)},
            {"object points raw", count_text(p.objects_raw)},
            {"object points voxel-filtered", count_text(p.objects_voxel_filtered)},
            {"object points outlier-filtered", count_text(p.objects_outlier_filtered)}};
  return t;
}

Table duplicates_table(const std::vector<PageDuplicate>& pairs) {
  Table t;
  t.caption =
      "Suspected duplicates (run.json): objects of one class whose oriented boxes overlap or whose "
      "surfaces touch, and why the merge pass kept them apart";
  t.header = {"ids", "class", "box overlap", "surface distance [m]", "touching", "why not merged"};
  t.numeric = {false, false, true, true, true, false};
  for (const PageDuplicate& d : pairs) {
    t.rows.push_back({std::to_string(d.a) + " + " + std::to_string(d.b), d.class_name,
                      percent(d.obb_overlap), fixed_text(d.surface_distance_m, 3),
                      percent(d.touching_share), d.merge_reason});
    t.swatches.push_back(hex_color(fusion::class_color(d.class_name)));
  }
  return t;
}

Table sightings_table(const std::vector<io::Sighting>& sightings) {
  Table t;
  t.caption =
      "Seen moving things (objects.json sightings): classes that move by themselves, not part of "
      "the map; where their points were over the keyframes they were seen in";
  t.header = {"id", "class", "position [m]", "first seen [s]", "last seen [s]", "keyframes"};
  t.numeric = {true, false, false, true, true, true};
  for (const io::Sighting& s : sightings) {
    t.rows.push_back({std::to_string(s.id), s.class_name,
                      fixed_text(s.position.x(), 2) + ", " + fixed_text(s.position.y(), 2) + ", " +
                          fixed_text(s.position.z(), 2),
                      fixed_text(s.first_seen, 3), fixed_text(s.last_seen, 3),
                      std::to_string(s.frames)});
    t.swatches.push_back(hex_color(fusion::class_color(s.class_name)));
  }
  return t;
}

// The duplicates section of a run without any.
const char* kNoDuplicates =
    "No suspected duplicates: no two objects of one class overlap or touch.";

const char* kStyle = R"(
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       color: #222; max-width: 1240px; margin: 20px auto; padding: 0 16px; line-height: 1.4; }
h1 { font-size: 24px; margin: 0 0 4px; }
h2 { font-size: 18px; margin: 28px 0 8px; border-bottom: 1px solid #ddd; padding-bottom: 3px; }
p.summary { font-size: 16px; margin: 4px 0 12px; }
ul.notes { color: #8a4b00; font-size: 13px; }
figure { margin: 8px 0; }
figcaption { font-size: 13px; color: #555; }
figure.map img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figure.scene-graph svg { max-width: 100%; height: auto; }
div.plots { display: flex; flex-wrap: wrap; gap: 16px; }
div.plots figure { flex: 1 1 480px; margin: 0; }
div.plots svg { max-width: 100%; height: auto; border: 1px solid #eee; }
div.thumbs { display: grid; grid-template-columns: repeat(auto-fill, minmax(172px, 1fr)); gap: 10px; }
div.thumbs figure { margin: 0; text-align: center; }
div.thumbs img { width: 160px; height: 160px; }
div.tables { display: flex; flex-wrap: wrap; gap: 0 32px; align-items: flex-start; }
table { border-collapse: collapse; margin: 6px 0 18px; font-size: 13px; }
caption { text-align: left; font-weight: 600; padding: 2px 0 6px; }
th, td { padding: 3px 9px; border-bottom: 1px solid #e4e4e4; }
th { background: #f4f4f4; text-align: left; }
.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.total td { font-weight: 600; border-top: 1px solid #999; }
span.swatch { display: inline-block; width: 10px; height: 10px; border-radius: 2px;
              margin-right: 6px; border: 1px solid #0003; }
footer { margin-top: 28px; font-size: 12px; color: #666; }
)";

}  // namespace

std::string page_style() { return kStyle; }

std::string image_tag(const PagePicture& p, const std::string& css_class, const std::string& alt) {
  std::string tag = "<img";
  if (!css_class.empty()) tag += " class=\"" + css_class + "\"";
  tag += " src=\"" + png_data_uri(p.bytes) + "\" alt=\"" + xml_escape(alt) + "\"";
  if (p.width_px > 0)
    tag += " width=\"" + std::to_string(p.width_px) + "\" height=\"" + std::to_string(p.height_px) +
           "\"";
  return tag + "/>";
}

std::string summary_line(const PageContent& c) {
  std::string s;
  if (c.counts)
    s += std::to_string(c.counts->keyframes) + " keyframes of " + std::to_string(c.counts->frames) +
         " frames, " + std::to_string(c.counts->instances) + " instances; ";
  s += std::to_string(c.objects.size()) + (c.objects.size() == 1 ? " object" : " objects");
  const auto classes = per_class(c);
  if (!classes.empty()) {
    s += " (";
    bool first = true;
    for (const auto& [name, n] : classes) {
      s += (first ? "" : ", ") + std::to_string(n) + " " + name;
      first = false;
    }
    s += ")";
  }
  if (c.ate.empty()) {
    s += "; ATE not computed (no ground-truth trajectory)";
  } else {
    for (std::size_t i = 0; i < c.ate.size(); ++i)
      s += (i == 0 ? "; ATE RMSE " : ", ") + c.ate[i].name + " " +
           metres_text(c.ate[i].stats.rmse) + " m";
    s += " (" + std::to_string(c.ate[0].stats.count) + " pose pairs)";
  }
  if (c.object_eval) {
    for (const eval::ErrorRow& r : c.object_eval->result.errors)
      if (r.class_name == "overall" && r.matched > 0)
        s += "; " + std::to_string(r.matched) + "/" + std::to_string(r.reference) +
             " ground-truth objects matched, mean centroid error " +
             fixed_text(r.distance_m.mean, 3) + " m";
  }
  return s + ".";
}

std::string page_html(const PageContent& c) {
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n";
  h += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n";
  h += "<title>" + xml_escape(c.title) + "</title>\n<style>" + kStyle +
       "</style>\n</head>\n<body>\n";
  h += "<h1>" + xml_escape(c.title) + "</h1>\n";
  h += "<p class=\"summary\">" + xml_escape(summary_line(c)) + "</p>\n";
  if (!c.notes.empty()) {
    h += "<ul class=\"notes\">\n";
    for (const std::string& n : c.notes) h += "<li>" + xml_escape(n) + "</li>\n";
    h += "</ul>\n";
  }

  // 1. The map in 3D, then from above, big.
  if (c.view3d) h += "<h2>The map in 3D</h2>\n" + view3d_html(*c.view3d, c.view3d_options);
  if (!c.topview.bytes.empty()) {
    h += "<h2>Semantic map seen from above</h2>\n<figure class=\"map\">" +
         image_tag(c.topview, "topview", "top view of the semantic map") + "<figcaption>" +
         xml_escape(c.topview.caption) + "</figcaption></figure>\n";
  }
  if (!c.scene_graph.bytes.empty())
    h += "<h2>Scene graph</h2>\n<figure class=\"scene-graph\">\n" + c.scene_graph.bytes +
         "<figcaption>" + xml_escape(c.scene_graph.caption) + "</figcaption></figure>\n";
  // 2. Plots.
  if (!c.trajectory_plot.bytes.empty() || !c.ate_plot.bytes.empty()) {
    h += "<h2>Trajectory</h2>\n<div class=\"plots\">\n";
    for (const PagePicture* p : {&c.trajectory_plot, &c.ate_plot}) {
      if (p->bytes.empty()) continue;
      h += "<figure>\n" + p->bytes + "<figcaption>" + xml_escape(p->caption) +
           "</figcaption></figure>\n";
    }
    h += "</div>\n";
    if (!c.ate.empty()) h += html_table(ate_table(c));
  }
  // 3. Thumbnails, one per object.
  h += "<h2>Objects</h2>\n<div class=\"thumbs\">\n";
  for (const PageObject& o : c.objects) {
    const std::string label = std::to_string(o.object.id) + " " + o.object.class_name;
    h += "<figure class=\"object\" data-object-id=\"" + std::to_string(o.object.id) + "\">" +
         image_tag(o.thumbnail, "thumb", label) + "<figcaption>" + xml_escape(o.thumbnail.caption) +
         "</figcaption></figure>\n";
  }
  h += "</div>\n";
  // 4. Tables.
  h += html_table(objects_table(c));
  h += "<div class=\"tables\">\n<div>" + html_table(class_table(c)) + "</div>\n";
  if (c.points) h += "<div>" + html_table(points_table(*c.points)) + "</div>\n";
  h += "</div>\n";
  if (!c.sightings.empty()) {
    h += "<h2>Seen moving things</h2>\n";
    h += html_table(sightings_table(c.sightings));
  }
  if (c.duplicates) {
    h += "<h2>Suspected duplicates</h2>\n";
    if (c.duplicates->empty())
      h += std::string("<p>") + kNoDuplicates + "</p>\n";
    else
      h += html_table(duplicates_table(*c.duplicates));
  }
  if (c.object_eval) {
    h += html_table(error_table(*c.object_eval));
    h += html_table(precision_table(*c.object_eval));
  }
  h += "<footer>\n";
  for (const std::string& line : c.inputs) h += xml_escape(line) + "<br/>\n";
  h += "Written by objmap report.\n</footer>\n</body>\n</html>\n";
  return h;
}

std::string page_markdown(const PageContent& c) {
  // Every text of the run (names, paths, notes) as Markdown text: no HTML gets through.
  std::string m = "# " + markdown_text(c.title) + "\n\n" + markdown_text(summary_line(c)) + "\n\n";
  for (const std::string& n : c.notes) m += "- " + markdown_text(n) + "\n";
  if (!c.notes.empty()) m += "\n";
  if (!c.topview.bytes.empty())
    m += "![top view of the semantic map](" + c.topview.file + ")\n\n" +
         markdown_text(c.topview.caption) + "\n\n";
  if (!c.scene_graph.bytes.empty())
    m += "![scene graph](" + c.scene_graph.file + ")\n\n" + markdown_text(c.scene_graph.caption) +
         "\n\n" + c.scene_graph_list;
  for (const PagePicture* p : {&c.trajectory_plot, &c.ate_plot})
    if (!p->bytes.empty()) m += "![" + markdown_text(p->caption) + "](" + p->file + ")\n\n";
  if (!c.ate.empty()) m += markdown_table(ate_table(c));
  m += "## Objects\n\n";
  for (const PageObject& o : c.objects)
    m += "![" + markdown_text(std::to_string(o.object.id) + " " + o.object.class_name) + "](" +
         o.thumbnail.file + ") ";
  if (!c.objects.empty()) m += "\n\n";
  m += markdown_table(objects_table(c));
  m += markdown_table(class_table(c));
  if (c.object_eval) {
    m += markdown_table(error_table(*c.object_eval));
    m += markdown_table(precision_table(*c.object_eval));
  }
  if (c.points) m += markdown_table(points_table(*c.points));
  if (!c.sightings.empty()) {
    m += "## Seen moving things\n\n";
    m += markdown_table(sightings_table(c.sightings));
  }
  if (c.duplicates) {
    m += "## Suspected duplicates\n\n";
    m += c.duplicates->empty() ? std::string(kNoDuplicates) + "\n\n"
                               : markdown_table(duplicates_table(*c.duplicates));
  }
  for (const std::string& line : c.inputs) m += markdown_text(line) + "  \n";
  return m;
}

}  // namespace objmap::report
