#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "objmap/eval/objects.h"
#include "objmap/eval/stats.h"
#include "objmap/io/objects_json.h"
#include "objmap/report/view3d.h"

// The report page of a run: everything it shows, gathered by the caller (apps/objmap/report.cpp
// reads the files), and the two renderings: one self-contained HTML file (pictures embedded as
// data URIs, plots as inline SVG) and a Markdown summary that references the files beside it.
namespace objmap::report {

// A picture of the page: its file name beside the page and its encoded bytes.
struct PagePicture {
  std::string file;   // relative to the report folder, e.g. "topview.png"
  std::string bytes;  // PNG bytes (embedded in the HTML) or SVG text (inlined)
  int width_px = 0, height_px = 0;
  std::string caption;  // plain text
};

struct PageObject {
  io::MappedObject object;
  std::optional<std::size_t> points_raw;    // objects.json points.raw (before any filter)
  std::optional<std::size_t> points_voxel;  // points.voxel_filtered (before the outlier filter)
  PagePicture thumbnail;                    // PNG
};

// The "counts" block of run.json.
struct RunCounts {
  long long frames = 0, keyframes = 0, instances = 0, objects_confirmed = 0,
            objects_before_confirmation = 0;
};

// One pair of run.json "duplicates": same-class objects whose boxes overlap or whose surfaces
// touch.
struct PageDuplicate {
  int a = -1, b = -1;  // object ids
  std::string class_name;
  double obb_overlap = 0.0;         // share of the smaller box inside the larger
  double surface_distance_m = 0.0;  // shortest distance between the two clouds
  double touching_share = 0.0;      // of the smaller cloud's points touching the larger
  std::string merge_refused;        // the merge pass's rule: "shared_frames", "overlap", ...
  std::string merge_reason;         // that rule in words, with its figures
};

struct PageAte {
  std::string name;  // "estimated", "corrected"
  std::string gt_source, est_source;
  eval::ErrorStats stats;  // metres
};

struct PageContent {
  std::string title;  // e.g. "objmap report: rpy"
  std::string run_path;
  std::optional<RunCounts> counts;
  PagePicture topview;                                // PNG; empty bytes: none
  PagePicture trajectory_plot;                        // SVG; empty bytes: none
  PagePicture ate_plot;                               // SVG; empty bytes: none
  PagePicture scene_graph;                            // SVG; empty bytes: none
  std::string scene_graph_list;                       // the same as a nested Markdown list
  std::vector<PageAte> ate;                           // one per trajectory with a ground truth
  std::vector<PageObject> objects;                    // in objects.json order
  std::optional<eval::ObjectEvalReport> object_eval;  // Tables 3–5 against ground truth
  std::optional<eval::PointCounts> points;            // Table 6
  // run.json "duplicates" (absent: a run.json without that section, e.g. of an older objmap).
  std::optional<std::vector<PageDuplicate>> duplicates;
  // objects.json `sightings`: things that move by themselves, seen during the run (a table of
  // their own, "Seen moving things"; none: no such table).
  std::vector<io::Sighting> sightings;
  std::optional<View3dContent> view3d;  // the interactive 3D view; none: the page has none
  View3dOptions view3d_options;
  std::vector<std::string> notes;   // what could not be shown and why
  std::vector<std::string> inputs;  // "label: path" lines for the footer
};

// The pages' style sheet (the run report's and the diff report's).
std::string page_style();

// <img> of a PNG picture as a data URI, with its size when known; `alt` escaped.
std::string image_tag(const PagePicture& picture, const std::string& css_class,
                      const std::string& alt);

// One line: keyframes, objects (per class), ATE when known.
std::string summary_line(const PageContent& content);

// The whole page, UTF-8, self-contained (no external reference); well-formed XML apart from the
// doctype (void elements are self-closed), every text escaped.
std::string page_html(const PageContent& content);

// The Markdown summary; pictures referenced by their `file` names.
std::string page_markdown(const PageContent& content);

}  // namespace objmap::report
