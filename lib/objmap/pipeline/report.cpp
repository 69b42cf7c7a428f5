#include "objmap/pipeline/report.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "objmap/core/error.h"
#include "objmap/eval/ate.h"
#include "objmap/eval/objects.h"
#include "objmap/fusion/palette.h"
#include "objmap/io/atomic.h"
#include "objmap/io/json_file.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/ply.h"
#include "objmap/io/png_encode.h"
#include "objmap/io/run_path.h"
#include "objmap/io/scene_json.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/report_view3d.h"
#include "objmap/report/page.h"
#include "objmap/report/plots.h"
#include "objmap/report/scene_graph.h"
#include "objmap/report/thumbnail.h"
#include "objmap/report/topview.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using nlohmann::json;

void ReportOptions::check() const {
  require(up == "auto" || up == "x" || up == "y" || up == "z", "--up",
          "'" + up + "'; expected auto, x, y or z");
  require(thumbnail_px >= 32 && thumbnail_px <= 1024, "--thumbnail",
          std::to_string(thumbnail_px) + "; expected 32 to 1024 pixels");
  require(std::isfinite(pixel_m) && pixel_m >= 0.0005 && pixel_m <= 1, "--pixel",
          std::to_string(pixel_m) + "; expected 0.0005 to 1 metres per pixel");
  require(view_points >= 1000 && view_points <= 5000000, "--view-points",
          std::to_string(view_points) + "; expected 1000 to 5000000 points");
  io::require_replaceable(out.empty() ? run / "report" : out, io::kReportFolder);
}

namespace {

// The series colours: the casing of a coloured trajectory and its line in the error plot.
const Rgb kGtColor{70, 70, 70};
const Rgb kEstColor{20, 20, 20};
const Rgb kCorrectedColor{150, 50, 175};

json read_json(const fs::path& file) { return io::read_json_file(file, "cannot open"); }

// The pictures are CV_8UC3; objmap's PNG encoder (also that of `objmap synth`) writes them.
std::string png_bytes(const cv::Mat& image) {
  std::vector<std::uint8_t> png;
  io::encode_png(image, &png);
  return std::string(png.begin(), png.end());
}

// A path from run.json "inputs.<key>.path", when there.
std::optional<fs::path> input_path(const json& run, const std::string& key) {
  if (!run.is_object() || !run.contains("inputs") || !run["inputs"].contains(key)) return {};
  const json& entry = run["inputs"][key];
  if (!entry.is_object() || !entry.contains("path") || !entry["path"].is_string()) return {};
  return fs::path(entry["path"].get<std::string>());
}

bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::equivalent(a, b, ec) && !ec;
}

// One trajectory against the ground truth: the ATE and the plot series (aligned poses, error per
// pose; poses without a partner NaN).
report::PlotSeries aligned_series(const std::string& name, const Rgb& color,
                                  const eval::AteResult& ate) {
  report::PlotSeries s;
  s.name = name;
  s.color = color;
  const std::size_t n = ate.aligned.size();
  s.errors_m.assign(n, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < ate.matches.size(); ++i)
    s.errors_m[ate.matches[i].est_index] = ate.errors_m[i];
  for (const StampedPose& p : ate.aligned.poses) {
    s.stamps_s.push_back(p.timestamp);
    s.positions_m.push_back(p.world_from_cam.translation());
  }
  return s;
}

// run.json "duplicates" (fuse's suspected duplicates); nullopt when the run.json has none.
std::optional<std::vector<report::PageDuplicate>> read_duplicates(const json& run,
                                                                  const fs::path& run_file) {
  if (!run.is_object() || !run.contains("duplicates")) return std::nullopt;
  const json& section = run["duplicates"];
  if (!section.is_object() || !section.contains("pairs") || !section["pairs"].is_array())
    throw InputError(run_file.string(), "\"duplicates\" has no \"pairs\" array");
  std::vector<report::PageDuplicate> pairs;
  try {
    for (const json& p : section["pairs"]) {
      report::PageDuplicate d;
      d.a = p.at("a").get<int>();
      d.b = p.at("b").get<int>();
      d.class_name = p.at("class").get<std::string>();
      d.obb_overlap = p.at("obb_overlap").get<double>();
      d.surface_distance_m = p.at("surface_distance_m").get<double>();
      d.touching_share = p.at("touching_share").get<double>();
      d.merge_refused = p.at("merge_refused").get<std::string>();
      d.merge_reason = p.value("merge_reason", d.merge_refused);
      pairs.push_back(std::move(d));
    }
  } catch (const json::exception& e) {
    throw InputError(run_file.string(), std::string("\"duplicates\": ") + e.what());
  }
  return pairs;
}

// The objects of the top view, each labelled "id class"; a suspected duplicate's label names its
// partners: "7 chair (dup 3)".
std::vector<report::TopViewObject> top_view_objects(
    const std::vector<io::MappedObject>& objects,
    const std::optional<std::vector<report::PageDuplicate>>& duplicates) {
  std::map<int, std::string> partners;
  if (duplicates)
    for (const report::PageDuplicate& d : *duplicates) {
      partners[d.a] += (partners[d.a].empty() ? "" : ",") + std::to_string(d.b);
      partners[d.b] += (partners[d.b].empty() ? "" : ",") + std::to_string(d.a);
    }
  std::vector<report::TopViewObject> drawn;
  for (const auto& o : objects) {
    std::string label = std::to_string(o.id) + " " + o.class_name;
    if (partners.count(o.id)) label += " (dup " + partners[o.id] + ")";
    drawn.push_back({o.id, label, o.obb, fusion::class_color(o.class_name)});
  }
  return drawn;
}

// "objmap report: <the run folder's name>" (its parent's name when the path ends in a slash).
std::string page_title(const fs::path& run) {
  std::string title = "objmap report: " + fs::absolute(run).lexically_normal().filename().string();
  if (title == "objmap report: ")
    title += fs::absolute(run).lexically_normal().parent_path().filename().string();
  return title;
}

// What the report reads of the run folder itself.
struct RunFiles {
  fs::path objects_file;
  std::vector<io::MappedObject> objects;
  json objects_doc;
  json run;  // run.json, null when there is none
};

// Step 1: the objects (required) and run.json (counts, inputs, Table 6, duplicates).
RunFiles read_run(const ReportOptions& options, report::PageContent& page) {
  RunFiles files;
  files.objects_file = options.run / "objects.json";
  files.objects = io::read_objects_json(files.objects_file);
  files.objects_doc = read_json(files.objects_file);
  page.sightings = io::read_sightings(files.objects_file);
  const fs::path run_file = options.run / "run.json";
  if (fs::exists(run_file)) {
    files.run = read_json(run_file);
    const json& run = files.run;
    if (run.contains("counts") && run["counts"].is_object()) {
      const json& c = run["counts"];
      report::RunCounts counts;
      counts.frames = c.value("frames", 0LL);
      counts.keyframes = c.value("keyframes", 0LL);
      counts.instances = c.value("instances", 0LL);
      counts.objects_confirmed = c.value("objects_confirmed", 0LL);
      counts.objects_before_confirmation = c.value("objects_before_confirmation", 0LL);
      page.counts = counts;
    }
    if (run.contains("points")) page.points = eval::read_point_counts(run_file);
    page.duplicates = read_duplicates(run, run_file);
  } else {
    page.notes.push_back(run_file.string() + " not found: no counts, no trajectory, no Table 6");
  }
  page.inputs.push_back("run: " +
                        (options.shown_run.empty() ? options.run : options.shown_run).string());
  return files;
}

// The trajectories of the report: the run's estimate, the ground truth, the corrected one.
struct Trajectories {
  std::optional<Trajectory> est, gt, corrected;
  fs::path gt_path;
};

// The trajectory the run was fused with, from run.json; for a run made by `objmap correct` (or fuse
// --correct-poses), fused with its corrected trajectory, the input of the correction
// (correction.json).
std::optional<fs::path> run_trajectory_path(const ReportOptions& options, const json& run) {
  std::optional<fs::path> run_trajectory = input_path(run, "trajectory");
  if (std::ifstream cin(options.run / "correction.json"); cin) {
    const json correction = json::parse(cin, nullptr, false);
    if (correction.is_object() && correction.contains("input_trajectory") &&
        correction["input_trajectory"].is_string()) {
      const fs::path input = correction["input_trajectory"].get<std::string>();
      if (fs::exists(input)) run_trajectory = input;
    }
  }
  return run_trajectory;
}

// --gt, or the dataset's groundtruth.txt unless the run was fused with that very file.
fs::path ground_truth_path(const ReportOptions& options, const json& run,
                           const std::optional<fs::path>& est_path, report::PageContent& page) {
  fs::path gt_path = options.gt;
  if (gt_path.empty()) {
    if (const auto dataset = input_path(run, "dataset")) {
      const fs::path candidate = *dataset / "groundtruth.txt";
      if (fs::exists(candidate) && !(est_path && same_file(candidate, *est_path)))
        gt_path = candidate;
      else if (fs::exists(candidate))
        page.notes.push_back(
            "the run was fused with the dataset's groundtruth.txt itself: no "
            "trajectory error to show (give --gt F to compare with another)");
    }
  }
  return gt_path;
}

// Step 2: the trajectories that are there, each named in the page's inputs.
Trajectories read_trajectories(const ReportOptions& options, const json& run,
                               report::PageContent& page) {
  Trajectories t;
  const std::optional<fs::path> est_path = run_trajectory_path(options, run);
  if (est_path) {
    const fs::path poses = options.trajectory.empty() ? *est_path : options.trajectory;
    if (fs::exists(poses)) {
      t.est = io::read_trajectory(poses);
      t.est->source = est_path->string();
      page.inputs.push_back("estimated trajectory: " + est_path->string());
    } else {
      page.notes.push_back("the run's trajectory " + est_path->string() +
                           " is not there: no trajectory plots");
    }
  }
  t.gt_path = ground_truth_path(options, run, est_path, page);
  if (!t.gt_path.empty()) {
    t.gt = io::read_trajectory(t.gt_path);
    page.inputs.push_back("ground-truth trajectory: " + t.gt_path.string());
  }
  fs::path corrected_path = options.corrected;
  if (corrected_path.empty() && fs::exists(options.run / "trajectory_corrected.txt"))
    corrected_path = options.run / "trajectory_corrected.txt";
  if (!corrected_path.empty()) {
    t.corrected = io::read_trajectory(corrected_path);
    page.inputs.push_back("corrected trajectory: " + corrected_path.string());
  }
  return t;
}

// An estimate to plot: the run's or the corrected trajectory.
struct Estimate {
  std::string name;
  const std::optional<Trajectory>* trajectory;
  Rgb color;
};

// With a ground truth: the ground truth over the compared span (dashed) and each estimate aligned
// to it and coloured by its error; the ATE of each goes to the page.
std::vector<report::PlotSeries> aligned_plot_series(const Trajectories& t,
                                                    const Estimate (&estimates)[2],
                                                    report::PageContent& page) {
  report::PlotSeries g;
  g.name = "ground truth";
  g.color = kGtColor;
  g.dashed = true;
  std::vector<report::PlotSeries> coloured;
  double t0 = std::numeric_limits<double>::infinity(), t1 = -t0;
  for (const Estimate& e : estimates) {
    const auto& [name, traj, color] = e;
    if (!*traj) continue;
    const eval::AteResult ate = eval::evaluate_ate(*t.gt, **traj, eval::AteOptions{});
    page.ate.push_back({name, t.gt_path.string(), (*traj)->source, ate.stats});
    coloured.push_back(aligned_series(name, color, ate));
    for (const eval::StampMatch& m : ate.matches) {
      t0 = std::min(t0, t.gt->poses[m.gt_index].timestamp);
      t1 = std::max(t1, t.gt->poses[m.gt_index].timestamp);
    }
  }
  for (const StampedPose& p : t.gt->poses)  // the ground truth over the compared span
    if (p.timestamp >= t0 && p.timestamp <= t1) {
      g.stamps_s.push_back(p.timestamp);
      g.positions_m.push_back(p.world_from_cam.translation());
    }
  std::vector<report::PlotSeries> series;
  series.push_back(g);
  series.insert(series.end(), coloured.begin(), coloured.end());
  return series;
}

// Without a ground truth: each estimate as it is.
std::vector<report::PlotSeries> plain_plot_series(const Estimate (&estimates)[2]) {
  std::vector<report::PlotSeries> series;
  for (const Estimate& e : estimates) {
    const auto& [name, traj, color] = e;
    if (!*traj) continue;
    report::PlotSeries s;
    s.name = name;
    s.color = color;
    for (const StampedPose& p : (*traj)->poses) {
      s.stamps_s.push_back(p.timestamp);
      s.positions_m.push_back(p.world_from_cam.translation());
    }
    series.push_back(s);
  }
  return series;
}

// The run's gravity_from_world (objects.json), absent in a run of an objmap before it.
std::optional<Eigen::Matrix3d> gravity_of(const json& objects_doc) {
  if (!objects_doc.contains("gravity_from_world")) return std::nullopt;
  const json& g = objects_doc["gravity_from_world"];
  if (!g.is_array() || g.size() != 9) return std::nullopt;
  Eigen::Matrix3d r;
  for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = g[i].get<double>();
  return r;
}

std::string up_text(const ReportOptions& options, const std::optional<Eigen::Matrix3d>& gravity) {
  if (options.up != "auto") return options.up;
  return gravity ? "the run's up direction" : "z";
}

// Step 5b: the scene graph (surfaces, objects, `on` edges), for a run with a scene.
void add_scene_graph(const ReportOptions& options, report::PageContent& page) {
  io::SceneDescription map;
  try {
    map = io::read_map_scene(options.run / "objects.json");
  } catch (const InputError&) {
    page.notes.push_back(
        "no scene graph: objects.json has no surfaces and relations (a run of an "
        "objmap before them)");
    return;
  }
  page.scene_graph.file = "scene_graph.svg";
  page.scene_graph.bytes = report::scene_graph_svg(map);
  page.scene_graph_list = report::scene_graph_markdown(map);
  page.scene_graph.caption =
      std::string(
          "Scene graph: each support surface (floor first, then by height) with the "
          "objects that stand on it, an object on another indented under it "
          "(objects.json relations.on); ") +
      (report::floor_height_m(map) ? "heights above the floor (its largest piece)."
                                   : "no floor found, so no heights.");
}

// Step 3: the ATE per pose and the plots (the trajectories from above, the error over time).
void add_trajectory_plots(const ReportOptions& options, const Trajectories& t, int up_axis,
                          const std::optional<Eigen::Matrix3d>& gravity,
                          report::PageContent& page) {
  // Without a ground truth the plot is in the run's frame: turned to look down its up direction
  // (with one, the estimates are aligned to the ground truth's frame, z up).
  Trajectories turned = t;
  if (gravity && !t.gt)
    for (std::optional<Trajectory>* tr : {&turned.est, &turned.corrected})
      if (*tr)
        for (StampedPose& p : (*tr)->poses) p.world_from_cam.prerotate(*gravity);
  const Estimate estimates[] = {{"estimated", &turned.est, kEstColor},
                                {"corrected", &turned.corrected, kCorrectedColor}};
  const std::vector<report::PlotSeries> series = t.gt && (t.est || t.corrected)
                                                     ? aligned_plot_series(t, estimates, page)
                                                     : plain_plot_series(estimates);
  report::PlotOptions plot_options;
  plot_options.up_axis = up_axis;
  if (!series.empty()) {
    page.trajectory_plot.file = "trajectory.svg";
    page.trajectory_plot.bytes = report::trajectory_svg(series, plot_options);
    page.trajectory_plot.caption =
        page.ate.empty()
            ? "Camera trajectory seen from above (" + up_text(options, gravity) + " up)."
            : "Trajectories seen from above (" + up_text(options, gravity) +
                  " up), each estimate aligned to the ground truth (Horn) and coloured by its "
                  "absolute error; the ring marks the start.";
  }
  if (!page.ate.empty()) {
    page.ate_plot.file = "ate.svg";
    page.ate_plot.bytes = report::error_over_time_svg(series, plot_options);
    page.ate_plot.caption = "Absolute trajectory error over time.";
  }
}

// Step 4: Tables 3-5 against ground-truth objects (--gt-objects, --reference, or the dataset's
// objects_gt.json), when there are any.
void add_object_tables(const ReportOptions& options, const RunFiles& files,
                       report::PageContent& page) {
  fs::path gt_objects = options.gt_objects;
  if (gt_objects.empty() && options.reference.empty())
    if (const auto dataset = input_path(files.run, "dataset"))
      if (fs::exists(*dataset / "objects_gt.json")) gt_objects = *dataset / "objects_gt.json";
  if (gt_objects.empty() && options.reference.empty()) return;
  eval::ObjectEvalReport e;
  e.map_source = files.objects_file.string();
  std::vector<eval::ReferenceObject> reference;
  if (!options.reference.empty()) {
    e.mode = "reference";
    e.reference_source = options.reference.string();
    reference = eval::to_reference(io::read_objects_json(options.reference));
    page.inputs.push_back("reference map: " + options.reference.string());
  } else {
    e.mode = "ground_truth";
    e.reference_source = gt_objects.string();
    reference = eval::read_objects_gt(gt_objects, options.gt_class);
    page.inputs.push_back("ground-truth objects: " + gt_objects.string());
  }
  e.result = eval::evaluate_objects(files.objects, reference, e.options);
  page.object_eval = e;
}

// run.json "options.<section>.voxel_m", when there.
std::optional<double> run_voxel_m(const json& run, const char* section) {
  if (run.is_object() && run.contains("options") && run["options"].contains(section) &&
      run["options"][section].contains("voxel_m") && run["options"][section]["voxel_m"].is_number())
    return run["options"][section]["voxel_m"].get<double>();
  return std::nullopt;
}

// The camera positions of the trajectory the map was fused with (world frame): the run's
// estimate, or the corrected trajectory for a corrected run.
std::vector<Vec3> camera_path(const ReportOptions& options, const Trajectories& t) {
  const std::optional<Trajectory>& map_trajectory =
      fs::exists(options.run / "correction.json") && t.corrected ? t.corrected : t.est;
  std::vector<Vec3> out;
  if (map_trajectory)
    for (const StampedPose& p : map_trajectory->poses)
      out.push_back(p.world_from_cam.translation());
  return out;
}

// The map the page shows (map_semantic.ply, else map_objects.ply): read a block at a time, its
// points turned into the gravity frame when there is one.
struct PageMap {
  std::string name;
  std::size_t points = 0;
  report::PointBlocks blocks;
  PointCloud thin;  // thinned for the 3D view
};

PageMap page_map(const ReportOptions& options, const std::optional<Eigen::Matrix3d>& gravity) {
  const bool has_semantic = fs::exists(options.run / "map_semantic.ply");
  PageMap map;
  map.name = has_semantic ? "map_semantic.ply" : "map_objects.ply";
  const fs::path file = options.run / map.name;
  require(fs::exists(file), (options.run / "map_semantic.ply").string(),
          "missing, and so is map_objects.ply; expected the maps objmap fuse writes (the "
          "semantic map, or the objects-only map of a run fused with --dense-map false)");
  map.points = io::ply_vertex_count(file);
  const std::optional<Eigen::Matrix3f> r =
      gravity ? std::optional<Eigen::Matrix3f>(gravity->cast<float>()) : std::nullopt;
  map.blocks = [file, r](const std::function<void(const PointCloud&)>& take) {
    if (!r) return io::read_ply_blocks(file, take);
    io::read_ply_blocks(file, [&](const PointCloud& block) {
      PointCloud turned = block;
      for (Vec3f& p : turned.points) p = *r * p;
      take(turned);
    });
  };
  return map;
}

// Step 5: the top view with the objects and the camera path, in the map's frame: the run's
// estimate, or the corrected trajectory for a corrected run (fused with it). A run fused with
// --dense-map false has no semantic map: the objects-only map is drawn. The map is read as it is
// drawn, never whole; returned with its sample for the 3D view (in the gravity frame).
PageMap add_top_view(const ReportOptions& options, const RunFiles& files, const Trajectories& t,
                     int up_axis, const std::optional<Eigen::Matrix3d>& gravity,
                     report::PageContent& page) {
  PageMap map = page_map(options, gravity);
  report::TopViewOptions view_options;
  view_options.up_axis = up_axis;
  view_options.pixel_m = options.pixel_m;
  view_options.fade = 0.2;
  if (const auto voxel_m = run_voxel_m(files.run, "map")) view_options.point_size_m = *voxel_m;
  std::vector<report::TopViewObject> drawn = top_view_objects(files.objects, page.duplicates);
  if (gravity)
    for (auto& d : drawn) {
      d.obb.center = *gravity * d.obb.center;
      d.obb.rotation = *gravity * d.obb.rotation;
    }
  std::vector<report::TopViewPath> paths;
  if (const std::vector<Vec3> cameras = camera_path(options, t); !cameras.empty()) {
    report::TopViewPath path;
    path.color = Rgb{230, 0, 120};
    for (const Vec3& p : cameras) path.points_in_world.push_back(gravity ? Vec3(*gravity * p) : p);
    paths.push_back(path);
  }
  const report::TopView view =
      report::render_top_view(map.blocks, map.points, drawn, view_options, paths);
  page.topview.file = "topview.png";
  page.topview.bytes = png_bytes(view.image);
  page.topview.width_px = view.image.cols;
  page.topview.height_px = view.image.rows;
  char caption[512];
  std::snprintf(caption, sizeof caption,
                "%s seen from above (%s up, %.1f mm per pixel, %zu points): each "
                "object's oriented box outlined in its class colour and labelled \"id class\" "
                "(\"(dup N)\": a suspected duplicate of object N; where objects crowd, the id "
                "alone or nothing, and the label in the list on the right)%s; the bar is 1 m.",
                map.name.c_str(), up_text(options, gravity).c_str(), view.pixel_m * 1000,
                map.points, t.est ? ", the camera path in magenta (ring: start)" : "");
  page.topview.caption = caption;
  map.thin = report::thin_points(map.blocks, map.points, options.view_points);
  return map;
}

// One object of the page: its thumbnail (its shaded mesh where fuse wrote one, else its points)
// and the point counts before the filters (objects.json).
report::PageObject page_object(const ReportOptions& options, std::size_t index,
                               const io::MappedObject& o, const json& record,
                               const report::ThumbnailOptions& thumb_options,
                               const TriangleMesh& mesh, PointCloud* cloud_out) {
  report::PageObject p;
  p.object = o;
  if (record.contains("points") && record["points"].is_object()) {
    const json& pts = record["points"];
    if (pts.contains("raw") && pts["raw"].is_number_unsigned())
      p.points_raw = pts["raw"].get<std::size_t>();
    if (pts.contains("voxel_filtered") && pts["voxel_filtered"].is_number_unsigned())
      p.points_voxel = pts["voxel_filtered"].get<std::size_t>();
  }
  const fs::path ply = io::path_in_run(
      options.run, o.ply.empty() ? "objects/" + std::to_string(o.id) + ".ply" : o.ply,
      options.run / "objects.json", "objects[" + std::to_string(index) + "].ply");
  const PointCloud cloud = io::read_ply(ply);
  const std::string label = std::to_string(o.id) + " " + o.class_name;
  const cv::Mat thumb = mesh.empty()
                            ? report::render_thumbnail(cloud, label, thumb_options)
                            : report::render_mesh_thumbnail(mesh, fusion::class_color(o.class_name),
                                                            label, thumb_options);
  // Named as its PLY (fuse's "<id>_<class>"), every character but letters, digits, '-' and '_'
  // made '_': the name goes into report.md's links as it is.
  std::string name = ply.stem().string();
  for (char& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-') ch = '_';
  p.thumbnail.file = "thumbnails/" + (name.empty() ? std::to_string(o.id) : name) + ".png";
  p.thumbnail.bytes = png_bytes(thumb);
  p.thumbnail.width_px = thumb.cols;
  p.thumbnail.height_px = thumb.rows;
  const Vec3 size_cm = 200.0 * o.obb.half_extent;
  char text[256];
  std::snprintf(text, sizeof text, "%s: %zu points%s, %d observations, %.0f×%.0f×%.0f cm",
                label.c_str(), cloud.size(),
                mesh.empty()
                    ? ""
                    : (" (mesh: " + std::to_string(mesh.triangles.size()) + " triangles)").c_str(),
                o.observations, size_cm.x(), size_cm.y(), size_cm.z());
  p.thumbnail.caption = text;
  *cloud_out = cloud;
  return p;
}

// Step 6: a thumbnail per object; returns each object's points (world frame).
std::vector<PointCloud> add_thumbnails(const ReportOptions& options, const RunFiles& files,
                                       const std::vector<TriangleMesh>& meshes, int up_axis,
                                       report::PageContent& page) {
  report::ThumbnailOptions thumb_options;
  thumb_options.size_px = options.thumbnail_px;
  thumb_options.up_axis = up_axis;
  if (const auto voxel_m = run_voxel_m(files.run, "objects")) thumb_options.point_size_m = *voxel_m;
  std::vector<PointCloud> clouds(files.objects.size());
  for (std::size_t i = 0; i < files.objects.size(); ++i)
    page.objects.push_back(page_object(options, i, files.objects[i],
                                       files.objects_doc["objects"][i], thumb_options, meshes[i],
                                       &clouds[i]));
  return clouds;
}

// The objects' meshes (objects.json "mesh.file", written by fuse --mesh objects|all) for the
// thumbnails and the 3D view, inside the run folder; at most kViewMeshTriangles in all, so that the
// page stays light (the points are drawn for the others, and the page says so).
constexpr std::size_t kViewMeshTriangles = 300000;
std::vector<TriangleMesh> object_meshes(const ReportOptions& options, const RunFiles& files,
                                        report::PageContent& page) {
  std::vector<TriangleMesh> meshes(files.objects.size());
  std::size_t triangles = 0, left_out = 0;
  for (std::size_t i = 0; i < files.objects.size(); ++i) {
    const json& record = files.objects_doc["objects"][i];
    if (!record.contains("mesh") || !record["mesh"].is_object() ||
        !record["mesh"].contains("file") || !record["mesh"]["file"].is_string())
      continue;
    const std::string where = "objects[" + std::to_string(i) + "].mesh.file";
    TriangleMesh mesh =
        io::read_mesh_ply(io::path_in_run(options.run, record["mesh"]["file"].get<std::string>(),
                                          options.run / "objects.json", where));
    if (triangles + mesh.triangles.size() > kViewMeshTriangles) {
      ++left_out;
      continue;
    }
    triangles += mesh.triangles.size();
    meshes[i] = std::move(mesh);
  }
  if (left_out > 0)
    page.notes.push_back(
        "3D view: " + std::to_string(left_out) +
        " object(s) drawn as points in the 3D view and thumbnails: their meshes would pass " +
        std::to_string(kViewMeshTriangles) + " triangles in all");
  return meshes;
}

// Step 7: the 3D view: the map, the objects' points and boxes, the surfaces, the camera path and
// the answers of `objmap query` to every phrase of the map's classes.
void add_view3d(const ReportOptions& options, const RunFiles& files, const Trajectories& t,
                const std::optional<Eigen::Matrix3d>& gravity, const PageMap& map,
                std::vector<PointCloud> clouds, const std::vector<TriangleMesh>& meshes,
                report::PageContent& page) {
  View3dInputs in;
  in.objects = &files.objects;
  for (const json& record : files.objects_doc["objects"])
    in.views.push_back(record.contains("view_count") && record["view_count"].is_number_integer()
                           ? record["view_count"].get<int>()
                           : 0);
  in.clouds = std::move(clouds);
  in.meshes = meshes;
  in.map = map.thin;
  in.map_points_total = map.points;
  if (const auto voxel_m = run_voxel_m(files.run, "map")) in.map_point_size_m = *voxel_m;
  in.camera_path = camera_path(options, t);
  try {
    in.scene = io::read_map_scene(options.run / "objects.json");
  } catch (const InputError&) {
    page.notes.push_back("3D view: no surfaces, relations nor search (objects.json has no scene)");
  }
  in.gravity_from_world = gravity;
  page.view3d = view3d_content(std::move(in));
  page.view3d_options.max_map_points = options.view_points;
}

// Step 8: the page, the summary and every picture beside them, staged and renamed into OUT.
fs::path write_report(const ReportOptions& options, const report::PageContent& page) {
  const fs::path out = options.out.empty() ? options.run / "report" : options.out;
  io::StagingDir staging(out, io::kReportFolder);
  io::write_file_atomic(staging.path() / page.topview.file, page.topview.bytes);
  for (const report::PagePicture* p : {&page.trajectory_plot, &page.ate_plot, &page.scene_graph})
    if (!p->bytes.empty()) io::write_file_atomic(staging.path() / p->file, p->bytes);
  for (const report::PageObject& o : page.objects)
    io::write_file_atomic(staging.path() / o.thumbnail.file, o.thumbnail.bytes);
  io::write_file_atomic(staging.path() / "report.md", report::page_markdown(page));
  io::write_file_atomic(staging.path() / "report.html", report::page_html(page));
  staging.commit();
  return out;
}

}  // namespace

ReportResult run_report(const ReportOptions& options) {
  options.check();
  report::PageContent page;
  const fs::path& shown = options.shown_run.empty() ? options.run : options.shown_run;
  page.title = page_title(shown);
  page.run_path = shown.string();

  // 1. The run: objects (required), run.json (counts, inputs, Table 6). Every small input is read
  //    before the big ones (the maps), so that a bad one fails fast. With --up auto the pictures
  //    look down the run's up direction (objects.json gravity_from_world), else down an axis.
  const RunFiles files = read_run(options, page);
  const std::optional<Eigen::Matrix3d> gravity =
      options.up == "auto" ? gravity_of(files.objects_doc) : std::nullopt;
  const int up_axis = options.up == "auto" ? 2 : options.up[0] - 'x';
  // 2. Trajectories: the run's estimate, the ground truth, the corrected one.
  const Trajectories trajectories = read_trajectories(options, files.run, page);
  // 3. ATE per pose and the plots.
  add_trajectory_plots(options, trajectories, up_axis, gravity, page);
  // 4. Tables 3-5 against ground-truth objects.
  add_object_tables(options, files, page);
  // 5. The top view with the objects and the camera path.
  const PageMap map = add_top_view(options, files, trajectories, up_axis, gravity, page);
  add_scene_graph(options, page);
  // 6. A thumbnail per object.
  const std::vector<TriangleMesh> meshes = object_meshes(options, files, page);
  std::vector<PointCloud> clouds = add_thumbnails(options, files, meshes, up_axis, page);
  // 7. The 3D view (the map and the objects in the gravity frame).
  add_view3d(options, files, trajectories, gravity, map, std::move(clouds), meshes, page);
  // 8. The files: the page, the summary and every picture beside them.
  const fs::path out = write_report(options, page);
  return {std::move(page), out};
}

}  // namespace objmap::pipeline
