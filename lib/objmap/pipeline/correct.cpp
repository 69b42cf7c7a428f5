#include "objmap/pipeline/correct.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "objmap/core/clock.h"
#include "objmap/core/error.h"
#include "objmap/core/parallel.h"
#include "objmap/core/version.h"
#include "objmap/geometry/bounds.h"
#include "objmap/io/atomic.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/ply.h"
#include "objmap/io/run_path.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/config.h"
#include "objmap/pipeline/run_folder.h"
#include "objmap/pipeline/run_json.h"
#include "objmap/pose/view_groups.h"

namespace objmap::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;

json read_json_file(const fs::path& file) { return run_json::read_file(file); }
using run_json::field;
using run_json::input_path;
using run_json::vec3;
Camera camera_from_run(const json& run, const fs::path& file) {
  return run_json::camera(run, file);
}

// Copies a run folder's files (not its sub-folders' sub-folders; a run has objects/ only).
void copy_run(const fs::path& from, const fs::path& to) {
  for (const auto& entry : fs::recursive_directory_iterator(from)) {
    const fs::path rel = fs::relative(entry.path(), from);
    if (entry.is_directory())
      fs::create_directories(to / rel);
    else
      fs::copy_file(entry.path(), to / rel, fs::copy_options::overwrite_existing);
  }
}

// A temporary folder beside `out`, removed with the object (or when the process is interrupted).
class ScratchDir {
 public:
  ScratchDir(const fs::path& out, const std::string& tag)
      : path_((out.has_parent_path() ? out.parent_path() : fs::path(".")) /
              (out.filename().string() + "." + tag + "-tmp-" + std::to_string(::getpid()))),
        unfinished_(path_) {
    std::error_code ec;
    fs::remove_all(path_, ec);
    fs::create_directories(path_, ec);
    require(!ec, path_.string(), "cannot create a temporary folder: " + ec.message());
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  io::UnfinishedOutput unfinished_;
};

// The fuse options of a run (its run.json "options"), with the run's inputs.
FuseOptions fuse_options_of(const fs::path& run_dir, const json& run, const fs::path& scratch) {
  const fs::path file = run_dir / "run.json";
  FuseOptions fo;
  const fs::path options_file = scratch / "fuse_options.json";
  io::write_file_atomic(options_file, field<json>(run, "options", file, "").dump(2));
  apply_config_file(options_file, fuse_config_fields(fo));
  fo.dataset = input_path(run, file, "dataset");
  fo.layout = run_json::input_layout(run, file);
  fo.segmentation = input_path(run, file, "segmentation");
  fo.seg_format = field<std::string>(
      field<json>(field<json>(run, "inputs", file, ""), "segmentation", file, "inputs"), "format",
      file, "inputs.segmentation");
  const fs::path camera_file = scratch / "camera.json";
  io::write_camera_json(camera_file, camera_from_run(run, file));
  fo.camera = camera_file.string();
  return fo;
}

}  // namespace

void CorrectOptions::check() const {
  require(!run.empty(), "CorrectOptions.run", "empty; expected a fuse run folder");
  require(!out.empty(), "CorrectOptions.out", "empty; expected an output folder");
  require(view_model == "visible" || view_model == "centroid" || view_model == "icp",
          "CorrectOptions.view_model",
          "'" + view_model + "' is not a view model; expected visible, centroid or icp");
  icp.check();
  require(icp_links >= 0 && icp_links <= 3, "CorrectOptions.icp_links",
          "must be in [0, 3] (the previous, the earliest and the middle view), got " +
              std::to_string(icp_links));
  const auto in = [](double v, double lo, double hi) {
    return std::isfinite(v) && v > lo && v <= hi;
  };
  require(in(icp_max_view_angle_deg, 0.0, 180.0), "CorrectOptions.icp_max_view_angle_deg",
          "must be in (0, 180]");
  require(in(icp_link_max_view_angle_deg, 0.0, 180.0), "CorrectOptions.icp_link_max_view_angle_deg",
          "must be in (0, 180]");
  require(in(icp_link_sigma_scale, 0.0, 1e6), "CorrectOptions.icp_link_sigma_scale", "must be > 0");
  require(in(icp_link_max_sigma_deg, 0.0, 1e6), "CorrectOptions.icp_link_max_sigma_deg",
          "must be > 0");
  require(std::isfinite(link_max_translation_per_m) && link_max_translation_per_m >= 0,
          "CorrectOptions.link_max_translation_per_m", "must be >= 0");
  require(std::isfinite(link_max_rotation_deg_per_m) && link_max_rotation_deg_per_m >= 0,
          "CorrectOptions.link_max_rotation_deg_per_m", "must be >= 0");
  require(threads >= 0 && threads <= 64, "CorrectOptions.threads",
          "must be in [0, 64] (0: all cores), got " + std::to_string(threads));
  visibility.check();
  correction.check();
}

namespace {

// The remade observations of a run's keyframes, and for each problem observation the remade one
// with the same keyframe and centroid (null when there is none).
struct RemadeViews {
  std::vector<fusion::Observation> remade;
  std::vector<const fusion::Observation*> source;  // per problem observation
};

// Each observation's points, made again from the run's inputs (the same masks and back-projection
// as fuse), in a temporary run folder in `scratch`.
RemadeViews remade_views(const fs::path& run, const json& run_doc, const CorrectOptions& options,
                         const std::map<int, double>& keyframe_time, const pose::Problem& problem,
                         const fs::path& scratch) {
  const fs::path run_file = run / "run.json";
  FuseOptions fo = fuse_options_of(run, run_doc, scratch);
  fo.trajectory = input_path(run_doc, run_file, "trajectory");
  fo.out = scratch / "run";
  fo.threads = options.threads;
  // Problem keyframe slot -> run keyframe index (the problem's keyframes are keyframe_time's).
  std::vector<int> run_keyframe;
  for (const auto& [kf, t] : keyframe_time) run_keyframe.push_back(kf);
  RemadeViews views;
  views.remade = remake_observations(fo, run_keyframe);
  std::map<int, std::vector<const fusion::Observation*>> of_keyframe;
  for (const auto& o : views.remade)
    if (o.keyframe_index && o.centroid_in_cam) of_keyframe[*o.keyframe_index].push_back(&o);
  const std::size_t n_obs = problem.observations.size();
  // The remade observation of each problem observation: same keyframe, same centroid.
  views.source.assign(n_obs, nullptr);
  for (std::size_t i = 0; i < n_obs; ++i) {
    const pose::Observation& o = problem.observations[i];
    double best = 1e-6;
    for (const fusion::Observation* r : of_keyframe[run_keyframe[o.keyframe]]) {
      const double d = (*r->centroid_in_cam - o.centroid_in_cam).norm();
      if (d < best) best = d, views.source[i] = r;
    }
  }
  return views;
}

// The view-grouping options of pose/view_groups.h from correct's.
pose::ViewGroupOptions view_group_options(const CorrectOptions& options) {
  pose::ViewGroupOptions o;
  o.icp = options.icp;
  o.icp_max_view_angle_deg = options.icp_max_view_angle_deg;
  o.icp_links = options.icp_links;
  o.icp_link_max_view_angle_deg = options.icp_link_max_view_angle_deg;
  o.icp_link_max_points = options.icp_link_max_points;
  o.icp_link_max_model_points = options.icp_link_max_model_points;
  o.icp_link_sigma_scale = options.icp_link_sigma_scale;
  o.icp_link_max_sigma_deg = options.icp_link_max_sigma_deg;
  o.threads = options.threads;
  return o;
}

struct RawObservation {
  int keyframe;
  std::size_t landmark;
  Vec3 centroid_in_cam;
};

// What objects.json gives besides the landmarks: the object models, the keyframes' timestamps
// (by run keyframe index) and the observations with their run keyframe index.
struct ObjectsRead {
  std::vector<PointCloud> models;
  std::map<int, double> keyframe_time;
  std::vector<RawObservation> raw;
};

// The landmarks: objects observed by >= 1 keyframe, at their models' centroids (objects.json's
// centroid for an empty model); into rp.problem.landmarks and rp.object_ids.
ObjectsRead read_objects(const fs::path& run, const json& objects, const fs::path& objects_file,
                         RunProblem& rp) {
  ObjectsRead read;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const json& o = objects[i];
    const std::string where = "objects[" + std::to_string(i) + "]";
    const int id = field<int>(o, "id", objects_file, where);
    const std::string ply = field<std::string>(o, "ply", objects_file, where);
    PointCloud model = io::read_ply(io::path_in_run(run, ply, objects_file, where + ".ply"));
    pose::Landmark landmark;
    landmark.id = id;
    if (model.empty()) {
      landmark.position_in_world = vec3(o.at("centroid"), objects_file, where + ".centroid");
    } else {
      landmark.position_in_world = geometry::centroid(model);
    }
    const json obs = field<json>(o, "observations", objects_file, where);
    require(obs.is_array(), objects_file.string() + ": " + where + ".observations",
            "expected an array");
    std::size_t used = 0;
    for (std::size_t k = 0; k < obs.size(); ++k) {
      const std::string w = where + ".observations[" + std::to_string(k) + "]";
      const json& e = obs[k];
      if (!e.contains("keyframe") || e["keyframe"].is_null() || !e.contains("centroid_in_cam") ||
          e["centroid_in_cam"].is_null())
        continue;
      const int kf = field<int>(e, "keyframe", objects_file, w);
      const double t = field<double>(e, "timestamp", objects_file, w);
      read.keyframe_time.emplace(kf, t);
      read.raw.push_back({kf, rp.problem.landmarks.size(),
                          vec3(e["centroid_in_cam"], objects_file, w + ".centroid_in_cam")});
      ++used;
    }
    if (used == 0) continue;
    rp.problem.landmarks.push_back(landmark);
    rp.object_ids.push_back(id);
    read.models.push_back(std::move(model));
  }
  return read;
}

// Keyframes in the run's order, their poses from `trajectory` as fuse looked them up; returns the
// problem slot of each run keyframe.
std::map<int, std::size_t> add_keyframes(const Trajectory& trajectory,
                                         const std::map<int, double>& keyframe_time,
                                         double max_diff_s, const fs::path& objects_file,
                                         RunProblem& rp) {
  io::PoseLookupOptions lookup;
  lookup.max_diff_s = max_diff_s;
  lookup.interpolate = true;
  std::map<int, std::size_t> keyframe_slot;
  for (const auto& [kf, t] : keyframe_time) {
    const auto pose = io::lookup_pose(trajectory, t, lookup);
    require(pose.has_value(), trajectory.source,
            "no pose within " + std::to_string(max_diff_s) + " s of keyframe " +
                std::to_string(kf) + " (t = " + std::to_string(t) + ") of " +
                objects_file.string() + "; expected the trajectory the run was fused with");
    keyframe_slot[kf] = rp.problem.keyframes.size();
    rp.problem.keyframes.push_back({t, *pose});
  }
  return keyframe_slot;
}

// The partial-view bias of each observation: render every model from the keyframe's pose.
void visible_part_bias(const std::vector<PointCloud>& models, const Camera& camera,
                       const CorrectOptions& options, RunProblem& rp) {
  std::vector<const PointCloud*> model_ptrs;
  for (const auto& m : models) model_ptrs.push_back(&m);
  std::vector<std::vector<std::size_t>> of_keyframe(rp.problem.keyframes.size());
  for (std::size_t i = 0; i < rp.problem.observations.size(); ++i)
    of_keyframe[rp.problem.observations[i].keyframe].push_back(i);
  for (std::size_t k = 0; k < rp.problem.keyframes.size(); ++k) {
    if (of_keyframe[k].empty()) continue;
    const auto visible = pose::visible_centroids(model_ptrs, rp.problem.keyframes[k].world_from_cam,
                                                 camera, options.visibility);
    for (std::size_t i : of_keyframe[k]) {
      pose::Observation& o = rp.problem.observations[i];
      if (visible[o.landmark])
        o.bias_in_world = *visible[o.landmark] - rp.problem.landmarks[o.landmark].position_in_world;
      else
        ++rp.observations_without_view;
    }
  }
}

// The options as run: the view model's thresholds (unless given), view links for the graph with
// the icp view model only.
CorrectOptions options_as_run(const CorrectOptions& given) {
  CorrectOptions options = given;
  if (options.view_model_thresholds) {
    const bool icp = options.view_model == "icp";
    options.correction.min_improvement = icp ? 0.15 : 0.10;
    options.correction.min_held_out_improvement = icp ? 0.0 : 0.20;
  }
  // View links serve the pose graph only.
  if (options.view_model != "icp" || options.correction.method != "graph") options.icp_links = 0;
  return options;
}

// The median object scatter of a run problem at its own keyframe poses.
double median_scatter_m(const RunProblem& rp) {
  std::vector<Pose> poses;
  for (const auto& k : rp.problem.keyframes) poses.push_back(k.world_from_cam);
  return pose::median_scatter_m(rp.problem, poses);
}

// Correct the keyframe poses (graph or paper), with the guardrails of the pose stage. With view
// links first (bounds that grow with the path, as the links confirm large corrections); when the
// links do not confirm it, the same problem without them, with the fixed bounds.
void correct_keyframes(const RunProblem& rp, const CorrectOptions& options, CorrectResult& result) {
  if (!rp.problem.links.empty()) {
    pose::CorrectionOptions with_links = options.correction;
    if (options.link_bounds) {
      with_links.max_translation_fraction = options.link_max_translation_per_m;
      with_links.max_rotation_deg_per_m = options.link_max_rotation_deg_per_m;
    }
    result.correction = pose::correct_poses(rp.problem, with_links);
    result.with_links = result.correction;
    result.links_used = result.correction.accepted;
  }
  if (!result.links_used) {
    pose::Problem without = rp.problem;
    without.links.clear();
    result.correction = pose::correct_poses(without, options.correction);
    if (!rp.problem.links.empty()) result.reason_with_links = result.with_links.reason;
  }
  result.accepted = result.correction.accepted;
  result.reason = result.correction.reason;
  if (!result.reason_with_links.empty())
    result.reason += " (with view links: " + result.reason_with_links + ")";
}

// Fuse the run again with the corrected trajectory (written to `scratch`) into OUT.
void fuse_again(const CorrectOptions& options, const json& run_doc, const Trajectory& corrected,
                const std::string& trajectory_path, const fs::path& scratch,
                const FuseProgress& progress, CorrectResult& result) {
  const fs::path corrected_tmp = scratch / "trajectory_corrected.txt";
  io::write_trajectory(
      corrected_tmp, corrected,
      "corrected by objmap correct (" + options.correction.method + ") from " + trajectory_path);
  FuseOptions fo = fuse_options_of(options.run, run_doc, scratch);
  fo.trajectory = corrected_tmp;
  fo.out = options.out;
  fo.threads = options.threads;
  result.fuse = run_fuse(fo, progress);
  result.refused_map = true;
}

// OUT/trajectory_corrected.txt and OUT/correction.json; an accepted correction's run.json names the
// corrected trajectory.
void write_outputs(const CorrectOptions& options, const Trajectory& corrected,
                   const std::string& trajectory_path, const RunProblem& rp,
                   Clock::time_point t_start, CorrectResult& result) {
  const fs::path trajectory_out = options.out / "trajectory_corrected.txt";
  io::write_trajectory(trajectory_out, corrected,
                       std::string(result.accepted ? "corrected" : "not corrected (refused)") +
                           " by objmap correct (" + options.correction.method + ") from " +
                           trajectory_path);
  if (result.accepted) {
    const fs::path out_run = options.out / "run.json";
    ordered_json doc = ordered_json::parse(read_json_file(out_run).dump());
    doc["inputs"]["trajectory"]["path"] = trajectory_out.string();
    io::write_file_atomic(out_run, doc.dump(2) + "\n");
  }
  result.seconds_total = seconds_since(t_start);
  io::write_file_atomic(options.out / "correction.json",
                        correction_json(options, result, rp, trajectory_path));
}

}  // namespace

// view_model icp: every object's observations grouped by view. In keyframe order, an observation
// is aligned (point-to-plane ICP) to the anchor observations of its object that look at it from
// within max_view_angle_deg; the first that aligns takes it into its group, else it anchors a new
// group. Each group with >= 2 members becomes a landmark at its anchor's centroid, and each member
// observes that point where its alignment puts it (centroid_in_cam = (ΔT·world_from_cam)⁻¹·anchor
// centroid). Two views of the same side of an object are compared point by point, at the
// resolution of the depth image, not through the 1 cm model (which the drift itself blurs).
void icp_landmarks(const fs::path& run, const json& run_doc, const CorrectOptions& options,
                   const std::map<int, double>& keyframe_time, RunProblem& rp) {
  ScratchDir scratch(options.out, "icp");
  const pose::Problem& problem = rp.problem;
  const pose::ViewGroupOptions group_options = view_group_options(options);
  // 1. Each observation's points, made again from the run's inputs.
  const RemadeViews views =
      remade_views(run, run_doc, options, keyframe_time, problem, scratch.path());
  pose::ViewClouds source(views.source.size(), nullptr);
  for (std::size_t i = 0; i < source.size(); ++i)
    if (views.source[i]) source[i] = &views.source[i]->points_in_world;
  // 2. Per object, its observations in keyframe order.
  const std::vector<std::vector<std::size_t>> of_landmark =
      pose::in_keyframe_order(problem, source);
  // 3. Each view aligned to an anchor view of its object: its first view, or groups.
  std::vector<std::vector<pose::ViewGroup>> groups(problem.landmarks.size());
  if (options.icp_groups)
    pose::align_in_groups(problem, source, of_landmark, group_options, groups);
  else
    pose::align_to_first_views(problem, source, of_landmark, group_options, groups);
  // 4. View links between the views of each object.
  std::vector<pose::ViewLink> links;
  if (options.icp_links > 0)
    links = pose::view_links(problem, source, of_landmark, group_options, rp.links_tried);
  // 5. The aligned views observe their anchor's centroid: in place with one anchor per object, a
  //    new problem with a landmark per group.
  if (!options.icp_groups) {
    rp.problem.links = links;
    rp.observations_aligned += pose::observe_first_views(groups, rp.problem);
    return;
  }
  pose::GroupedProblem grouped =
      pose::problem_of_groups(groups, links, source, problem, rp.object_ids);
  RunProblem out;
  out.problem = std::move(grouped.problem);
  out.object_ids = std::move(grouped.object_ids);
  out.keyframe_objects = rp.keyframe_objects;
  out.observations_without_view = grouped.observations_without_view;
  out.observations_aligned = grouped.observations_aligned;
  out.links_tried = rp.links_tried;
  rp = std::move(out);
}

RunProblem problem_from_run(const fs::path& run, const Trajectory& trajectory,
                            const CorrectOptions& options) {
  const std::string& view_model = options.view_model;
  const fs::path run_file = run / "run.json";
  const fs::path objects_file = run / "objects.json";
  const json run_doc = read_json_file(run_file);
  const Camera camera = camera_from_run(run_doc, run_file);
  double max_diff_s = 0.02;
  if (run_doc.contains("options") && run_doc["options"].contains("max_diff_s"))
    max_diff_s = field<double>(run_doc["options"], "max_diff_s", run_file, "options");
  const json doc = read_json_file(objects_file);
  const json objects = field<json>(doc, "objects", objects_file, "");
  require(objects.is_array(), objects_file.string() + ": objects", "expected an array");

  RunProblem rp;
  // 1. Landmarks: the objects with observations, at their models' centroids.
  const ObjectsRead read = read_objects(run, objects, objects_file, rp);
  // 2. Keyframes in the run's order, their poses from `trajectory`.
  const std::map<int, std::size_t> keyframe_slot =
      add_keyframes(trajectory, read.keyframe_time, max_diff_s, objects_file, rp);
  // 3. Observations: each object's centroid_in_cam in its keyframe.
  rp.keyframe_objects.resize(rp.problem.keyframes.size());
  for (const RawObservation& r : read.raw) {
    pose::Observation o;
    o.keyframe = keyframe_slot.at(r.keyframe);
    o.landmark = r.landmark;
    o.centroid_in_cam = r.centroid_in_cam;
    rp.problem.observations.push_back(o);
    rp.keyframe_objects[o.keyframe].push_back(rp.object_ids[r.landmark]);
  }
  // 4. The partial-view bias of each observation: render every model from the keyframe's pose.
  if (view_model == "visible" || view_model == "icp")
    visible_part_bias(read.models, camera, options, rp);
  // 5. ICP: each observation's points, made again from the run's inputs, aligned to an earlier
  //    view of the same object (its anchor).
  if (view_model == "icp") icp_landmarks(run, run_doc, options, read.keyframe_time, rp);
  return rp;
}

namespace {

// The re-fused map's own consistency must not get worse (the median object scatter of OUT against
// the input run's); refuses the result when it does.
void check_map_consistency(const CorrectOptions& options, const Trajectory& corrected,
                           const RunProblem& rp, CorrectResult& result) {
  CorrectOptions no_links = options;
  no_links.icp_links = 0;  // the scatter needs no links
  const RunProblem again = problem_from_run(options.out, corrected, no_links);
  result.map_rms_after_m = median_scatter_m(again);
  // Scatters compare like with like only when the objects are the same; fewer objects (one that
  // the drift had split, joined again) spread their observations around the whole object.
  result.map_objects_before = rp.problem.landmarks.size();
  result.map_objects_after = again.problem.landmarks.size();
  const bool fewer = result.links_used && result.map_objects_after < result.map_objects_before;
  if (result.map_rms_after_m > result.map_rms_before_m && !fewer) {
    result.accepted = false;
    char buffer[200];
    std::snprintf(buffer, sizeof buffer,
                  "refused: the re-fused map is less consistent (median object scatter %.4f -> "
                  "%.4f m)",
                  result.map_rms_before_m, result.map_rms_after_m);
    result.reason = buffer;
  }
}

}  // namespace

CorrectResult run_correct(const CorrectOptions& given, const FuseProgress& progress) {
  given.check();
  io::require_not_an_input({"--out", given.out}, {{"--run", given.run}});
  io::require_replaceable(given.out, io::kRunFolder);  // before the work, not after it
  const CorrectOptions options = options_as_run(given);
  const auto t_start = Clock::now();
  CorrectResult result;
  const fs::path run_file = options.run / "run.json";
  const json run_doc = read_json_file(run_file);
  const std::string trajectory_path = input_path(run_doc, run_file, "trajectory");
  const Trajectory trajectory = io::read_trajectory(trajectory_path);

  // 1. The problem: keyframes, object landmarks, observations (with their partial-view bias).
  const RunProblem rp = problem_from_run(options.run, trajectory, options);
  result.landmarks = rp.problem.landmarks.size();
  result.observations = rp.problem.observations.size();
  result.observations_without_view = rp.observations_without_view;
  result.observations_aligned = rp.observations_aligned;
  result.links = rp.problem.links.size();
  result.links_tried = rp.links_tried;

  // 2. Correct the keyframe poses (graph or paper), with the guardrails of the pose stage: with
  //    view links first, without them when the links do not confirm it.
  correct_keyframes(rp, options, result);
  result.map_rms_before_m = median_scatter_m(rp);
  result.seconds_correct = seconds_since(t_start);

  ScratchDir scratch(options.out, "correct");
  Trajectory corrected = trajectory;
  if (result.accepted) {
    // 3. Every pose of the trajectory, corrections interpolated between keyframes.
    corrected =
        pose::apply_corrections(trajectory, rp.problem.keyframes, result.correction.world_from_cam);
    // 4. Fuse again with the corrected trajectory.
    fuse_again(options, run_doc, corrected, trajectory_path, scratch.path(), progress, result);
    // 5. The re-fused map's own consistency must not get worse.
    if (options.check_map) check_map_consistency(options, corrected, rp, result);
  }
  if (!result.accepted) {
    // Refused: OUT is the input run, the trajectory unchanged.
    corrected = trajectory;
    io::StagingDir staging(options.out, io::kRunFolder);
    copy_run(options.run, staging.path());
    staging.commit();
  }
  // 6. OUT/trajectory_corrected.txt, OUT/correction.json; run.json names the trajectory used.
  write_outputs(options, corrected, trajectory_path, rp, t_start, result);
  return result;
}

CorrectResult run_fuse_and_correct(const FuseOptions& fuse, const CorrectOptions& correct,
                                   const FuseProgress& progress) {
  fuse.check();
  io::require_not_an_input({"--out", fuse.out}, {{"--dataset", fuse.dataset},
                                                 {"--trajectory", fuse.trajectory},
                                                 {"--segmentation", fuse.segmentation}});
  io::require_replaceable(fuse.out, io::kRunFolder);  // before the two fuses, not after them
  ScratchDir first(fuse.out, "first-fuse");
  FuseOptions fo = fuse;
  fo.out = first.path() / "run";
  run_fuse(fo, progress);
  CorrectOptions co = correct;
  co.run = fo.out;
  co.out = fuse.out;
  return run_correct(co, progress);
}

}  // namespace objmap::pipeline
