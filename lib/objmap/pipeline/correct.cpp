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
#include "objmap/pipeline/run_json.h"

namespace objmap::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

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

// correction.json's options: those of the pose stage, and check_map.
ordered_json options_json(const CorrectOptions& options) {
  const pose::CorrectionOptions& o = options.correction;
  ordered_json out = {{"min_pairs", o.min_pairs},
                      {"min_spread_m", o.min_spread_m},
                      {"observation_sigma_m", o.observation_sigma_m},
                      {"robust_sigmas", o.robust_sigmas},
                      {"odometry_sigma_m", o.odometry_sigma_m},
                      {"odometry_sigma_fraction", o.odometry_sigma_fraction},
                      {"odometry_sigma_deg", o.odometry_sigma_deg},
                      {"odometry_sigma_deg_per_deg", o.odometry_sigma_deg_per_deg},
                      {"odometry_sigma_deg_per_m", o.odometry_sigma_deg_per_m},
                      {"max_translation_m", o.max_translation_m},
                      {"max_translation_fraction", o.max_translation_fraction},
                      {"max_rotation_deg", o.max_rotation_deg},
                      {"max_rotation_deg_per_m", o.max_rotation_deg_per_m},
                      {"link_sigma_m", o.link_sigma_m},
                      {"link_sigma_deg", o.link_sigma_deg},
                      {"min_held_out_link_improvement", o.min_held_out_link_improvement},
                      {"min_improvement", o.min_improvement},
                      {"min_translation_m", o.min_translation_m},
                      {"min_rotation_deg", o.min_rotation_deg},
                      {"min_held_out_improvement", o.min_held_out_improvement},
                      {"reweight_rounds", o.reweight_rounds},
                      {"paper_prior", o.paper_prior},
                      {"paper_prior_fraction", o.paper_prior_fraction},
                      {"max_iterations", o.max_iterations},
                      {"check_map", options.check_map}};
  return out;
}

// correction.json's consistency: observation, held-out, odometry and link RMS, and the map's
// object scatter before and after.
ordered_json consistency_json(const CorrectResult& result) {
  const pose::CorrectionResult& c = result.correction;
  ordered_json out = {
      {"observation_rms_before_m", c.residual_before_m},
      {"held_out_rms_before_m", c.held_out_before_m},
      {"held_out_rms_after_m", c.held_out_after_m},
      {"observation_rms_after_m", c.residual_after_m},
      {"odometry_rms_sigmas", c.odometry_rms_sigmas},
      {"link_rms_before_sigmas", result.with_links.link_rms_before_sigmas},
      {"link_rms_after_sigmas", result.with_links.link_rms_after_sigmas},
      {"held_out_link_rms_before_sigmas", result.with_links.held_out_link_before_sigmas},
      {"held_out_link_rms_after_sigmas", result.with_links.held_out_link_after_sigmas},
      {"map_scatter_before_m", result.map_rms_before_m},
      {"map_scatter_after_m", result.map_rms_after_m},
      {"map_objects_before", result.map_objects_before},
      {"map_objects_after", result.map_objects_after}};
  return out;
}

// Per keyframe: its objects, the verdict and the solver's proposed pose (also when refused).
ordered_json keyframes_json(const CorrectResult& result, const RunProblem& rp) {
  const pose::CorrectionResult& c = result.correction;
  ordered_json kfs = ordered_json::array();
  for (const auto& k : c.keyframes) {
    ordered_json e;
    e["index"] = k.index;
    e["timestamp"] = k.timestamp;
    e["objects"] = rp.keyframe_objects[k.index];
    e["matched"] = k.matched;
    e["spread_m"] = k.spread_m;
    e["corrected"] = result.accepted && k.corrected;
    e["reason"] = k.reason;
    e["residual_before_m"] = k.residual_before_m;
    e["residual_after_m"] = k.residual_after_m;
    e["translation_m"] = k.translation_m;
    e["rotation_deg"] = k.rotation_deg;
    const Pose& p = c.proposed[k.index];
    const Eigen::Quaterniond q = io::quaternion_of(p);
    e["proposed_world_from_cam"] = {
        p.translation().x(), p.translation().y(), p.translation().z(), q.x(), q.y(), q.z(), q.w()};
    kfs.push_back(e);
  }
  return kfs;
}

// Per observation: which object from which keyframe, its partial-view bias and residuals.
ordered_json observations_json(const pose::CorrectionResult& c, const RunProblem& rp) {
  std::vector<Vec3> mean(rp.problem.landmarks.size(), Vec3::Zero());
  std::vector<int> count(rp.problem.landmarks.size(), 0);
  for (const auto& ob : rp.problem.observations) {
    mean[ob.landmark] +=
        rp.problem.keyframes[ob.keyframe].world_from_cam * ob.centroid_in_cam - ob.bias_in_world;
    ++count[ob.landmark];
  }
  ordered_json obs = ordered_json::array();
  for (const auto& ob : rp.problem.observations) {
    const Vec3 m = mean[ob.landmark] / count[ob.landmark];
    const Vec3 before =
        rp.problem.keyframes[ob.keyframe].world_from_cam * ob.centroid_in_cam - ob.bias_in_world;
    const Vec3 after = c.proposed[ob.keyframe] * ob.centroid_in_cam - ob.bias_in_world;
    obs.push_back({{"object", rp.object_ids[ob.landmark]},
                   {"keyframe", ob.keyframe},
                   {"bias_m", ob.bias_in_world.norm()},
                   {"residual_before_m", (before - m).norm()},
                   {"residual_after_m", (after - c.landmarks_in_world[ob.landmark]).norm()}});
  }
  return obs;
}

// Per view link: the two keyframes, the object, how far the poses are from the measured relative
// pose, before and after.
ordered_json links_json(const pose::CorrectionResult& c, const RunProblem& rp) {
  ordered_json links = ordered_json::array();
  for (const auto& l : rp.problem.links) {
    const auto error = [&](const Pose& a, const Pose& b) {
      const Pose e = l.a_from_b.inverse() * (a.inverse() * b);
      return std::make_pair(e.translation().norm(),
                            Eigen::AngleAxisd(e.linear()).angle() * 180.0 / 3.14159265358979323846);
    };
    const auto [tb, rb] =
        error(rp.problem.keyframes[l.a].world_from_cam, rp.problem.keyframes[l.b].world_from_cam);
    const auto [ta, ra] = error(c.proposed[l.a], c.proposed[l.b]);
    links.push_back({{"object", rp.object_ids[l.landmark]},
                     {"keyframes", {l.a, l.b}},
                     {"sigma_m", l.sigma_m},
                     {"sigma_deg", l.sigma_deg},
                     {"error_before_m", tb},
                     {"error_before_deg", rb},
                     {"error_after_m", ta},
                     {"error_after_deg", ra}});
  }
  return links;
}

std::string correction_json(const CorrectOptions& options, const CorrectResult& result,
                            const RunProblem& rp, const std::string& input_trajectory) {
  const pose::CorrectionResult& c = result.correction;
  ordered_json doc;
  // The run, the method and the verdict.
  doc["schema_version"] = 1;
  doc["generator"] = std::string("objmap ") + objmap::version();
  doc["command"] = "correct";
  doc["run"] = options.run.string();
  doc["input_trajectory"] = input_trajectory;
  doc["output_trajectory"] = "trajectory_corrected.txt";
  doc["method"] = options.correction.method;
  doc["view_model"] = options.view_model;
  doc["accepted"] = result.accepted;
  doc["reason"] = result.reason;
  doc["view_links_used"] = result.links_used;
  doc["reason_with_view_links"] = result.reason_with_links;
  // The options.
  doc["options"] = options_json(options);
  // Counts, consistency, the largest correction and the time taken.
  doc["counts"] = {{"keyframes", c.keyframes.size()},
                   {"keyframes_corrected", result.accepted ? c.corrected_keyframes : 0},
                   {"landmarks", result.landmarks},
                   {"observations", result.observations},
                   {"observations_without_view", result.observations_without_view},
                   {"observations_aligned", result.observations_aligned},
                   {"view_links", result.links},
                   {"view_links_tried", result.links_tried}};
  doc["consistency"] = consistency_json(result);
  doc["max_correction"] = {{"translation_m", c.max_translation_m},
                           {"rotation_deg", c.max_rotation_deg}};
  doc["solver"] = {{"iterations", c.iterations}, {"seconds", c.seconds}};
  doc["seconds"] = {{"correct", result.seconds_correct}, {"total", result.seconds_total}};
  // Per keyframe, per observation, per view link.
  doc["keyframes"] = keyframes_json(result, rp);
  doc["observations"] = observations_json(c, rp);
  doc["links"] = links_json(c, rp);
  return doc.dump(2) + "\n";
}

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

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

// The direction from the keyframe's camera to observation i's centroid, world frame.
Vec3 view_direction(const pose::Problem& problem, std::size_t i) {
  const Pose& pose = problem.keyframes[problem.observations[i].keyframe].world_from_cam;
  return (pose * problem.observations[i].centroid_in_cam - pose.translation()).normalized();
}

// View links: each observation aligned to a few earlier views of its object that look at the
// same side (the previous one, the earliest, the one between); an alignment measures the relative
// pose of the two keyframes. `source[i]` holds observation i's points (world frame, input poses),
// `of_landmark[j]` object j's observations in keyframe order; `tried` counts the alignments.
std::vector<pose::ViewLink> view_links(const pose::Problem& problem,
                                       const std::vector<const fusion::Observation*>& source,
                                       const std::vector<std::vector<std::size_t>>& of_landmark,
                                       const CorrectOptions& options, std::size_t& tried_total) {
  std::vector<pose::ViewLink> links;
  const double cos_link = std::cos(options.icp_link_max_view_angle_deg * kRadPerDeg);
  pose::IcpOptions link_icp = options.icp;
  link_icp.max_points = options.icp_link_max_points;
  link_icp.max_model_points = options.icp_link_max_model_points;
  for (std::size_t j = 0; j < of_landmark.size(); ++j) {
    const std::vector<std::size_t>& mine = of_landmark[j];
    if (mine.size() < 2) continue;
    std::vector<Vec3> view(mine.size());
    std::vector<std::unique_ptr<pose::ModelAligner>> aligners(mine.size());
    parallel_for(mine.size(), options.threads, [&](std::size_t p) {
      view[p] = view_direction(problem, mine[p]);
      aligners[p] =
          std::make_unique<pose::ModelAligner>(source[mine[p]]->points_in_world, link_icp);
    });
    std::vector<std::vector<pose::ViewLink>> found(mine.size());
    std::vector<std::size_t> tried(mine.size(), 0);
    parallel_for(mine.size(), options.threads, [&](std::size_t p) {
      const std::size_t kb = problem.observations[mine[p]].keyframe;
      std::vector<std::size_t> candidates;
      for (std::size_t q = 0; q < p; ++q)
        if (problem.observations[mine[q]].keyframe != kb && view[q].dot(view[p]) >= cos_link)
          candidates.push_back(q);
      if (candidates.empty()) return;
      std::vector<std::size_t> targets = {candidates.back(), candidates.front(),
                                          candidates[candidates.size() / 2]};
      targets.resize(std::min<std::size_t>(targets.size(), options.icp_links));
      std::sort(targets.begin(), targets.end());
      targets.erase(std::unique(targets.begin(), targets.end()), targets.end());
      const Pose& pose_b = problem.keyframes[kb].world_from_cam;
      for (std::size_t q : targets) {
        ++tried[p];
        const pose::IcpResult r = aligners[q]->align(source[mine[p]]->points_in_world);
        if (!r.aligned || !std::isfinite(r.rotation_sigma_deg)) continue;
        const std::size_t ka = problem.observations[mine[q]].keyframe;
        const Pose& pose_a = problem.keyframes[ka].world_from_cam;
        // A rotation error about the object's centre moves the camera by that angle times its
        // distance.
        const double distance = (r.centre - pose_b.translation()).norm();
        const double scale = options.icp_link_sigma_scale;
        pose::ViewLink link{ka, kb, j, pose_a.inverse() * r.correction * pose_b};
        link.sigma_deg = scale * r.rotation_sigma_deg;
        link.sigma_m =
            scale * (r.translation_sigma_m + r.rotation_sigma_deg * M_PI / 180.0 * distance);
        if (link.sigma_deg > options.icp_link_max_sigma_deg) continue;
        found[p].push_back(link);
      }
    });
    for (std::size_t p = 0; p < mine.size(); ++p) {
      links.insert(links.end(), found[p].begin(), found[p].end());
      tried_total += tried[p];
    }
  }
  return links;
}

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

// Per object, its observations with points in keyframe order (the problem keeps them by object).
std::vector<std::vector<std::size_t>> in_keyframe_order(
    const pose::Problem& problem, const std::vector<const fusion::Observation*>& source) {
  std::vector<std::vector<std::size_t>> of_landmark(problem.landmarks.size());
  for (std::size_t i = 0; i < problem.observations.size(); ++i)
    if (source[i]) of_landmark[problem.observations[i].landmark].push_back(i);
  for (auto& v : of_landmark)
    std::stable_sort(v.begin(), v.end(), [&](std::size_t a, std::size_t b) {
      return problem.observations[a].keyframe < problem.observations[b].keyframe;
    });
  return of_landmark;
}

struct Member {
  std::size_t observation;
  Pose correction;
};

// An anchor view of an object and the views aligned to it.
struct Group {
  std::size_t landmark;
  Vec3 anchor_centroid, view;  // world frame; view: unit vector camera -> anchor centroid
  std::unique_ptr<pose::ModelAligner> aligner;
  std::vector<Member> members;
};

Group make_group(const pose::Problem& problem,
                 const std::vector<const fusion::Observation*>& source,
                 const CorrectOptions& options, std::size_t j, std::size_t i) {
  Group group;
  group.landmark = j;
  group.anchor_centroid = geometry::centroid(source[i]->points_in_world);
  group.view = view_direction(problem, i);
  group.aligner = std::make_unique<pose::ModelAligner>(source[i]->points_in_world, options.icp);
  group.members.push_back({i, Pose::Identity()});
  return group;
}

// One anchor per object (its first view); every other view aligns to it on its own, so all
// alignments run in parallel.
void align_to_first_views(const pose::Problem& problem,
                          const std::vector<const fusion::Observation*>& source,
                          const std::vector<std::vector<std::size_t>>& of_landmark,
                          const CorrectOptions& options, std::vector<std::vector<Group>>& groups) {
  const double cos_max = std::cos(options.icp_max_view_angle_deg * kRadPerDeg);
  parallel_for(problem.landmarks.size(), options.threads, [&](std::size_t j) {
    if (!of_landmark[j].empty())
      groups[j].push_back(make_group(problem, source, options, j, of_landmark[j].front()));
  });
  std::vector<std::pair<std::size_t, std::size_t>> jobs;  // (landmark, observation)
  for (std::size_t j = 0; j < of_landmark.size(); ++j)
    for (std::size_t k = 1; k < of_landmark[j].size(); ++k) jobs.emplace_back(j, of_landmark[j][k]);
  std::vector<std::optional<Pose>> aligned(jobs.size());
  parallel_for(jobs.size(), options.threads, [&](std::size_t n) {
    const auto [j, i] = jobs[n];
    const Group& g = groups[j].front();
    if (g.view.dot(view_direction(problem, i)) < cos_max) return;
    const pose::IcpResult r = g.aligner->align(source[i]->points_in_world);
    if (r.aligned) aligned[n] = r.correction;
  });
  for (std::size_t n = 0; n < jobs.size(); ++n)
    if (aligned[n]) groups[jobs[n].first].front().members.push_back({jobs[n].second, *aligned[n]});
}

// Groups: an observation joins the first anchor (closest direction first) that aligns it, or
// anchors a group of its own; the order matters, so each object runs in keyframe order.
void align_in_groups(const pose::Problem& problem,
                     const std::vector<const fusion::Observation*>& source,
                     const std::vector<std::vector<std::size_t>>& of_landmark,
                     const CorrectOptions& options, std::vector<std::vector<Group>>& groups) {
  const double cos_max = std::cos(options.icp_max_view_angle_deg * kRadPerDeg);
  parallel_for(problem.landmarks.size(), options.threads, [&](std::size_t j) {
    auto& mine = groups[j];
    for (std::size_t i : of_landmark[j]) {
      const Vec3 view = view_direction(problem, i);
      std::vector<std::pair<double, std::size_t>> candidates;
      for (std::size_t g = 0; g < mine.size(); ++g) {
        const double c = mine[g].view.dot(view);
        if (c >= cos_max) candidates.emplace_back(-c, g);
      }
      std::sort(candidates.begin(), candidates.end());
      bool joined = false;
      for (const auto& [c, g] : candidates) {
        const pose::IcpResult r = mine[g].aligner->align(source[i]->points_in_world);
        if (!r.aligned) continue;
        mine[g].members.push_back({i, r.correction});
        joined = true;
        break;
      }
      if (!joined) mine.push_back(make_group(problem, source, options, j, i));
    }
  });
}

// One anchor per object: each aligned view observes the anchor's centroid where its alignment
// puts it; the observations it does not align keep the visible-part model.
void observe_first_views(const std::vector<std::vector<Group>>& groups, RunProblem& rp) {
  const pose::Problem& problem = rp.problem;
  for (std::size_t j = 0; j < groups.size(); ++j) {
    if (groups[j].empty() || groups[j][0].members.size() < 2) continue;
    const Group& g = groups[j][0];
    for (const Member& m : g.members) {
      pose::Observation& o = rp.problem.observations[m.observation];
      o.centroid_in_cam = (m.correction * problem.keyframes[o.keyframe].world_from_cam).inverse() *
                          g.anchor_centroid;
      o.bias_in_world = g.anchor_centroid - problem.landmarks[j].position_in_world;
      ++rp.observations_aligned;
    }
  }
}

// The problem of the groups: one landmark per group of >= 2 members at its anchor's centroid;
// links keep their keyframes, their landmark becomes the object's first group.
RunProblem problem_of_groups(const std::vector<std::vector<Group>>& groups,
                             const std::vector<pose::ViewLink>& links,
                             const std::vector<const fusion::Observation*>& source,
                             const RunProblem& rp) {
  const pose::Problem& problem = rp.problem;
  RunProblem out;
  out.problem.keyframes = problem.keyframes;
  out.keyframe_objects = rp.keyframe_objects;
  out.observations_without_view = 0;
  for (std::size_t j = 0; j < groups.size(); ++j) {
    for (const Group& g : groups[j]) {
      if (g.members.size() < 2) {
        ++out.observations_without_view;
        continue;
      }
      pose::Landmark landmark = problem.landmarks[j];
      landmark.position_in_world = g.anchor_centroid;
      for (const Member& m : g.members) {
        pose::Observation o = problem.observations[m.observation];
        o.landmark = out.problem.landmarks.size();
        o.centroid_in_cam =
            (m.correction * problem.keyframes[o.keyframe].world_from_cam).inverse() *
            g.anchor_centroid;
        o.bias_in_world = Vec3::Zero();
        out.problem.observations.push_back(o);
        ++out.observations_aligned;
      }
      out.problem.landmarks.push_back(landmark);
      out.object_ids.push_back(rp.object_ids[j]);
    }
  }
  for (std::size_t i = 0; i < problem.observations.size(); ++i)
    if (!source[i]) ++out.observations_without_view;
  std::map<int, std::size_t> first_landmark;
  for (std::size_t k = out.object_ids.size(); k-- > 0;) first_landmark[out.object_ids[k]] = k;
  for (pose::ViewLink l : links) {
    const auto it = first_landmark.find(rp.object_ids[l.landmark]);
    if (it == first_landmark.end()) continue;
    l.landmark = it->second;
    out.problem.links.push_back(l);
  }
  out.links_tried = rp.links_tried;
  return out;
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
  // 1. Each observation's points, made again from the run's inputs.
  const RemadeViews views =
      remade_views(run, run_doc, options, keyframe_time, problem, scratch.path());
  const std::vector<const fusion::Observation*>& source = views.source;
  // 2. Per object, its observations in keyframe order.
  const std::vector<std::vector<std::size_t>> of_landmark = in_keyframe_order(problem, source);
  // 3. Each view aligned to an anchor view of its object: its first view, or groups.
  std::vector<std::vector<Group>> groups(problem.landmarks.size());
  if (options.icp_groups)
    align_in_groups(problem, source, of_landmark, options, groups);
  else
    align_to_first_views(problem, source, of_landmark, options, groups);
  // 4. View links between the views of each object.
  std::vector<pose::ViewLink> links;
  if (options.icp_links > 0)
    links = view_links(problem, source, of_landmark, options, rp.links_tried);
  // 5. The aligned views observe their anchor's centroid: in place with one anchor per object, a
  //    new problem with a landmark per group.
  if (!options.icp_groups) {
    rp.problem.links = links;
    observe_first_views(groups, rp);
    return;
  }
  rp = problem_of_groups(groups, links, source, rp);
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
