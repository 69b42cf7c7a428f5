// correction.json, the record `objmap correct` writes into its run folder (run_folder.h).
#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "objmap/core/version.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/run_folder.h"

namespace objmap::pipeline {

using ordered_json = nlohmann::ordered_json;

namespace {

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

}  // namespace

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

}  // namespace objmap::pipeline
