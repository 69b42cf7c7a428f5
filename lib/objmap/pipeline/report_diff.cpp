#include "objmap/pipeline/report_diff.h"

#include <cctype>
#include <cmath>
#include <map>
#include <optional>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/fusion/palette.h"
#include "objmap/io/atomic.h"
#include "objmap/io/diff_json.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/ply.h"
#include "objmap/io/png_encode.h"
#include "objmap/io/run_path.h"
#include "objmap/io/scene_json.h"
#include "objmap/report/thumbnail.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

fs::path DiffReportOptions::diff_file() const {
  std::error_code ec;
  return fs::is_directory(diff, ec) ? diff / "diff.json" : diff;
}

fs::path DiffReportOptions::out_folder() const {
  return out.empty() ? diff_file().parent_path() / "report" : out;
}

void DiffReportOptions::check() const {
  require(thumbnail_px >= 32 && thumbnail_px <= 1024, "--thumbnail",
          std::to_string(thumbnail_px) + "; expected 32 to 1024 pixels");
  require(view_points >= 2000 && view_points <= 5000000, "--view-points",
          std::to_string(view_points) + "; expected 2000 to 5000000 points");
  std::error_code ec;
  require(!fs::equivalent(out_folder(), diff_file().parent_path(), ec), "--out",
          out_folder().string() + " is the diff folder itself; expected a folder of its own");
  io::require_replaceable(out_folder(), io::kReportFolder);
}

namespace {

// The tints of the two maps in the 3D view: half the point's colour, half the tint.
const Rgb kBeforeTint{40, 110, 230};  // A: blue
const Rgb kAfterTint{240, 140, 20};   // B: orange
const Rgb kArrow{220, 30, 30};

// One run as the page draws it, in the before run's gravity frame.
struct VisitView {
  char name = 'A';
  std::string why_not;  // not empty: the run could not be read (the reason)
  std::vector<io::MappedObject> objects;
  std::map<int, std::size_t> index;                           // id -> objects[]
  std::vector<PointCloud> clouds;                             // per object, gravity frame of A
  PointCloud map;                                             // tinted, gravity frame of A, thinned
  std::size_t map_points = 0;                                 // before thinning
  Eigen::Isometry3f to_view = Eigen::Isometry3f::Identity();  // run world -> A's gravity frame
  fs::path folder;
};

std::string png_bytes(const cv::Mat& image) {
  std::vector<std::uint8_t> png;
  io::encode_png(image, &png);
  return std::string(png.begin(), png.end());
}

// The map of a run: map_dense.ply (its colours), else map_semantic.ply.
PointCloud read_map(const fs::path& run) {
  for (const char* name : {"map_dense.ply", "map_semantic.ply"})
    if (fs::exists(run / name)) return io::read_ply(run / name);
  throw InputError(run.string(), "has neither map_dense.ply nor map_semantic.ply");
}

PointCloud tinted(const PointCloud& cloud, const Eigen::Isometry3f& to_view, Rgb tint) {
  PointCloud out;
  out.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Rgb c = cloud.has_colors() ? cloud.colors[i] : Rgb{128, 128, 128};
    const auto mix = [](std::uint8_t a, std::uint8_t b) {
      return static_cast<std::uint8_t>((int(a) + int(b)) / 2);
    };
    out.push_back(to_view * cloud.points[i],
                  Rgb{mix(c.r, tint.r), mix(c.g, tint.g), mix(c.b, tint.b)});
  }
  return out;
}

// Step 2: a run folder's objects, their points and its map; on bad input the reason is kept
// (the page says it) and the rest of the page is still made.
VisitView read_visit_view(char name, const fs::path& run, const Eigen::Isometry3f& to_view,
                          std::size_t max_map_points, Rgb tint) {
  VisitView v;
  v.name = name;
  v.folder = run;
  v.to_view = to_view;
  try {
    const fs::path objects_file = run / "objects.json";
    v.objects = io::read_objects_json(objects_file);
    for (std::size_t i = 0; i < v.objects.size(); ++i) {
      const io::MappedObject& o = v.objects[i];
      v.index[o.id] = i;
      const fs::path ply =
          io::path_in_run(run, o.ply.empty() ? "objects/" + std::to_string(o.id) + ".ply" : o.ply,
                          objects_file, "objects[" + std::to_string(i) + "].ply");
      PointCloud cloud = io::read_ply(ply);
      for (Vec3f& p : cloud.points) p = to_view * p;
      v.clouds.push_back(std::move(cloud));
    }
    const PointCloud map = read_map(run);
    v.map_points = map.size();
    v.map = tinted(report::thin_points(map, max_map_points), to_view, tint);
  } catch (const InputError& e) {
    v.why_not = e.what();
    v.objects.clear();
    v.index.clear();
    v.clouds.clear();
  }
  return v;
}

std::string point_text(const Vec3& p) {
  return "(" + fixed_text(p.x(), 3) + ", " + fixed_text(p.y(), 3) + ", " + fixed_text(p.z(), 3) +
         ")";
}

std::string side_text(const std::optional<io::DiffSide>& s) {
  return s ? std::to_string(s->id) + " " + s->class_name : "-";
}

// Letters, digits, '-' and '_' kept, the rest '_': a name for report.md's links.
std::string file_safe(std::string name) {
  for (char& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-') ch = '_';
  return name;
}

// Why a visit has no picture of an object: the other visit's evidence about its place.
std::string missing_side_why(const io::DiffObject& o, char visit) {
  const std::optional<io::DiffEvidence>& e = visit == 'B' ? o.after_visit : o.before_visit;
  std::string why = std::string("not in ") + visit + ": ";
  if (o.status == "removed" || o.status == "added")
    why += std::string(1, visit) + " saw its place empty";
  else if (o.status == "not_seen_again" || o.status == "not_seen_before")
    why += std::string(1, visit) + " did not see its place clearly";
  else
    why += "not detected there";
  if (e)
    why += " (" + std::to_string(e->seen_through) + " of " + std::to_string(e->sightlines) +
           " lines of sight through it, " + std::to_string(e->surface) + " on a surface, " +
           std::to_string(e->views) + " views)";
  return why;
}

// One side's thumbnail: the object's points (in A's gravity frame, so both sides are seen from
// the same view), or a blank picture labelled with why there is none.
report::PagePicture side_thumbnail(const io::DiffObject& o, const std::optional<io::DiffSide>& s,
                                   const VisitView& v, std::size_t row,
                                   const report::ThumbnailOptions& options) {
  report::PagePicture p;
  PointCloud cloud;
  std::string label = std::string(1, v.name) + " " + side_text(s);
  if (!s) {
    p.caption = missing_side_why(o, v.name);
    label = std::string("not in ") + v.name;
  } else if (!v.why_not.empty()) {
    p.caption = "no picture: " + v.why_not;
  } else if (const auto it = v.index.find(s->id); it == v.index.end()) {
    p.caption = "no picture: no object " + std::to_string(s->id) + " in " +
                (v.folder / "objects.json").string();
  } else {
    cloud = v.clouds[it->second];
    p.caption = std::to_string(cloud.size()) + " points";
  }
  const cv::Mat image = report::render_thumbnail(cloud, label, options);
  p.file = "thumbnails/" + std::to_string(row) + "_" + v.name +
           (s ? "_" + file_safe(std::to_string(s->id) + "_" + s->class_name) : "") + ".png";
  p.bytes = png_bytes(image);
  p.width_px = image.cols;
  p.height_px = image.rows;
  return p;
}

// Step 3: the registration as a table.
report::Table registration_table(const io::DiffRegistration& r) {
  report::Table t;
  t.caption = "before_from_after: the after run's world registered into the before run's";
  t.header = {"", "value"};
  const Eigen::Matrix4d m = r.before_from_after.matrix();
  std::string rows;
  for (int i = 0; i < 3; ++i)
    rows += (i ? " / " : "") + fixed_text(m(i, 0), 4) + " " + fixed_text(m(i, 1), 4) + " " +
            fixed_text(m(i, 2), 4) + " " + fixed_text(m(i, 3), 4);
  const auto sigma = [](const std::optional<double>& s, double scale, const char* unit,
                        int digits) {
    return s ? fixed_text(*s * scale, digits) + unit : std::string("not constrained");
  };
  t.rows = {{"source", r.source},
            {"transform (rows 1-3)", rows},
            {"yaw about up", fixed_text(r.yaw_deg, 3) + "°"},
            {"tilt corrected", fixed_text(r.tilt_deg, 3) + "°"},
            {"translation", point_text(r.translation_m) + " m"},
            {"common objects", std::to_string(r.common_objects)},
            {"coarse RMS", fixed_text(r.coarse_rms_m * 100, 2) + " cm"},
            {"fitness (larger / smaller share)",
             fixed_text(r.fitness, 3) + " / " + fixed_text(r.fitness_both, 3)},
            {"ICP RMS",
             fixed_text(r.rms_m * 1000, 2) + " mm, " + std::to_string(r.icp_points) + " points"},
            {"σ translation (lower bound)", sigma(r.sigma_translation_m, 1000, " mm", 2)},
            {"σ yaw (lower bound)", sigma(r.sigma_yaw_deg, 1, "°", 3)}};
  return t;
}

// Step 4: a row per change, both thumbnails; the unchanged listed.
void add_changes(const io::DiffFile& diff, const VisitView& a, const VisitView& b, int thumbnail_px,
                 report::DiffPageContent& page) {
  report::ThumbnailOptions options;
  options.size_px = thumbnail_px;
  options.up_axis = 2;  // both in A's gravity frame
  for (const io::DiffObject& o : diff.objects) {
    if (o.status == "unchanged") {
      page.unchanged.push_back(o.before ? side_text(o.before) : "B " + side_text(o.after));
      continue;
    }
    report::DiffPageChange r;
    r.status = o.status;
    r.before = side_text(o.before);
    r.after = side_text(o.after);
    r.position = point_text(o.position_in_before());
    if (o.displacement_m)
      r.change = "moved " + fixed_text(o.displacement_m->norm(), 3) + " m " +
                 point_text(*o.displacement_m);
    else if (o.distance_m)
      r.change = fixed_text(*o.distance_m, 3) + " m apart";
    r.why = o.why;
    const std::size_t row = page.changes.size() + 1;
    r.before_thumbnail = side_thumbnail(o, o.before, a, row, options);
    r.after_thumbnail = side_thumbnail(o, o.after, b, row, options);
    page.changes.push_back(std::move(r));
  }
}

// A view object of one side of a diff object: its points, its box (both in A's gravity frame).
report::View3dObject view_object(const io::DiffObject& o, const io::DiffSide& s,
                                 const VisitView& v) {
  report::View3dObject x;
  x.class_name = s.class_name;
  x.color = fusion::class_color(s.class_name);
  x.id = v.name == 'A' ? s.id : -1 - s.id;  // unique in the view: B's below 0
  x.label = std::string(1, v.name) + " " + std::to_string(s.id) + " " + s.class_name +
            (o.status == "unchanged" ? "" : ": " + o.status);
  x.relations = {o.why};
  if (const auto it = v.index.find(s.id); it != v.index.end()) {
    const io::MappedObject& m = v.objects[it->second];
    const Eigen::Isometry3d t = v.to_view.cast<double>();
    x.obb = m.obb;
    x.obb.center = t * m.obb.center;
    x.obb.rotation = t.linear() * m.obb.rotation;
    x.observations = m.observations;
    x.score = m.score;
    x.points = v.clouds[it->second].points;
  } else {
    x.obb.center = v.to_view.cast<double>() * s.position;
    x.obb.rotation = Eigen::Matrix3d::Identity();
    x.obb.half_extent = Vec3::Constant(0.05);
  }
  return x;
}

// Step 5: the 3D view: both maps, every before object, the after objects that are not the same
// object at the same place, an arrow per moved object.
report::View3dContent diff_view(const io::DiffFile& diff, const VisitView& a, const VisitView& b,
                                const Eigen::Isometry3f& a_view) {
  report::View3dContent c;
  c.map = a.map;
  c.map_points_total = a.map_points;
  c.second_map = b.map;
  c.second_map_points_total = b.map_points;
  for (const io::DiffObject& o : diff.objects) {
    if (o.before) c.objects.push_back(view_object(o, *o.before, a));
    if (o.after && (!o.before || o.status != "unchanged"))
      c.objects.push_back(view_object(o, *o.after, b));
    if (o.status == "moved") {
      report::View3dArrow arrow;
      arrow.from = (a_view.cast<double>() * o.before->position);
      arrow.to = (a_view.cast<double>() * o.after->position_in_before);
      arrow.color = kArrow;
      arrow.label =
          side_text(o.before) + " moved " + fixed_text(o.displacement_m->norm(), 3) + " m";
      c.arrows.push_back(arrow);
    }
  }
  for (const report::View3dObject& o : c.objects) c.queries[o.class_name].push_back(o.id);
  c.known_classes = {};
  for (const auto& [cls, ids] : c.queries) c.known_classes.push_back(cls);
  c.caption =
      "Both runs in the before run's gravity frame (z up): the before map (A) tinted blue, the "
      "after map (B, registered with before_from_after) tinted orange, each object's points and "
      "box labelled \"A id class: status\" or \"B id class: status\" (B's unchanged objects are "
      "drawn as A's), and a red arrow from each moved object's old place to its new one.";
  return c;
}

std::string counts_line(const io::DiffFile& diff) {
  std::string s;
  for (const char* status : io::kDiffStatuses) {
    const auto it = diff.counts.find(status);
    const int n = it == diff.counts.end() ? 0 : it->second;
    s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + status;
  }
  return s;
}

fs::path write_diff_report(const fs::path& out, const report::DiffPageContent& page) {
  io::StagingDir staging(out, io::kReportFolder);
  fs::create_directories(staging.path() / "thumbnails");
  for (const report::DiffPageChange& r : page.changes)
    for (const report::PagePicture* p : {&r.before_thumbnail, &r.after_thumbnail})
      io::write_file_atomic(staging.path() / p->file, p->bytes);
  io::write_file_atomic(staging.path() / "report.md", report::diff_page_markdown(page));
  io::write_file_atomic(staging.path() / "report.html", report::diff_page_html(page));
  staging.commit();
  return out;
}

}  // namespace

DiffReportResult run_diff_report(const DiffReportOptions& options) {
  options.check();
  // 1. diff.json (every field checked); A's gravity frame is the view's (the identity for a run
  //    without the scene fields).
  const io::DiffFile diff = io::read_diff_json(options.diff_file());
  report::DiffPageContent page;
  page.title =
      "objmap diff report: " +
      fs::absolute(options.diff_file()).lexically_normal().parent_path().filename().string();
  page.summary = counts_line(diff);
  Eigen::Isometry3f a_view = Eigen::Isometry3f::Identity();
  try {
    a_view.linear() =
        io::read_map_scene(fs::path(diff.before) / "objects.json").gravity_from_world.cast<float>();
  } catch (const InputError&) {
    page.notes.push_back(
        "the before run's up is unknown (objects.json has no gravity_from_world):"
        " its world's z is drawn up");
  }
  const Eigen::Isometry3f b_view = a_view * diff.registration.before_from_after.cast<float>();
  // 2. Both runs: objects, their points, the maps (each thinned to half the view's points).
  const VisitView a =
      read_visit_view('A', diff.before, a_view, options.view_points / 2, kBeforeTint);
  const VisitView b = read_visit_view('B', diff.after, b_view, options.view_points / 2, kAfterTint);
  for (const VisitView* v : {&a, &b})
    if (!v->why_not.empty())
      page.notes.push_back(std::string(v->name == 'A' ? "before" : "after") + " run " +
                           v->folder.string() + " not read (" + v->why_not +
                           "): no pictures nor map of it");
  // 3. The registration, 4. a row per change, 5. the 3D view.
  page.registration = registration_table(diff.registration);
  add_changes(diff, a, b, options.thumbnail_px, page);
  page.view3d = diff_view(diff, a, b, a_view);
  page.view3d_options.max_map_points = options.view_points / 2;
  page.inputs = {"diff: " + diff.source, "before run (A): " + diff.before,
                 "after run (B): " + diff.after};
  // 6. The files.
  const fs::path out = write_diff_report(options.out_folder(), page);
  return {std::move(page), out};
}

}  // namespace objmap::pipeline
