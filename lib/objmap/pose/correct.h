#pragma once
#include <string>
#include <vector>

#include "objmap/core/trajectory.h"
#include "objmap/core/types.h"

// Pose correction with object constraints (paper §3.4, eqs 19-20). Objects of the map are
// landmarks; each keyframe's observations of them (the centroid of the observation's points in the
// camera frame) constrain that keyframe's pose.
//  - "paper": per keyframe, the SE(3) that best maps the observed centroids onto the matched
//    landmarks (eq 20): closed form (Horn/Umeyama), then refined with Ceres (Huber loss, pose on
//    SO(3)×R³), applied to that keyframe alone.
//  - "graph" (default): one Ceres problem over every keyframe pose and every landmark position:
//    relative-pose factors between consecutive keyframes from the input trajectory (the SLAM run's
//    own odometry), observation factors (landmark vs observed centroid, Huber loss), the first
//    keyframe fixed (gauge).
// Guardrails: a keyframe is corrected only with enough evidence; the whole result is refused when
// it moves a pose beyond the bounds or does not make the observations more consistent.
namespace objmap::pose {

// An object of the map.
struct Landmark {
  int id = -1;                            // object id in objects.json
  Vec3 position_in_world = Vec3::Zero();  // initial estimate (the fused object's centroid)
};

// One observation of a landmark by a keyframe.
struct Observation {
  std::size_t keyframe = 0;             // index into Problem::keyframes
  std::size_t landmark = 0;             // index into Problem::landmarks
  Vec3 centroid_in_cam = Vec3::Zero();  // centroid of the observation's points, camera frame
  // Partial-view bias: where the observed centroid lies relative to the landmark when seen from
  // this keyframe (visible-part centroid − model centroid), world frame. The model predicts
  // world_from_cam · centroid_in_cam = landmark + bias_in_world.
  Vec3 bias_in_world = Vec3::Zero();
  double weight = 1.0;  // > 0; scales the information of the factor
};

// Two keyframes' views of the same object aligned to each other (ICP of the object's points): the
// relative pose they measure, a_from_b ≈ world_from_cam[a]⁻¹ · world_from_cam[b]. An object seen
// from overlapping views pins down all six degrees of freedom between them, not only where its
// centroid lies.
struct ViewLink {
  std::size_t a = 0, b = 0;  // indices into Problem::keyframes, a != b
  std::size_t landmark = 0;  // the object whose views were aligned
  Pose a_from_b = Pose::Identity();
  // Its std (translation, rotation); the options' link_sigma_m / link_sigma_deg when larger.
  double sigma_m = 0.0, sigma_deg = 0.0;
};

struct Problem {
  std::vector<StampedPose> keyframes;  // input poses world_from_cam, increasing time
  std::vector<Landmark> landmarks;
  std::vector<Observation> observations;
  std::vector<ViewLink> links;  // graph only; may be empty
};

struct CorrectionOptions {
  std::string method = "graph";  // graph | paper
  // Evidence per keyframe.
  int min_pairs = 3;           // matched objects needed to correct a keyframe (paper: 3)
  double min_spread_m = 0.05;  // their second principal std (not collinear), metres
  // Noise model (graph and paper).
  double observation_sigma_m = 0.005;  // floor of an object's centroid noise, metres, per axis
                                       // (each object's own noise is estimated, IRLS)
  double ray_sigma_factor = 1.0;       // graph: std along the viewing ray = this × the lateral
  double robust_sigmas = 2.0;          // Huber threshold in sigmas (both methods)
  // Odometry factors (graph): relative pose of consecutive keyframes from the input trajectory,
  // std = base + fraction of the step (drift grows with the motion).
  double odometry_sigma_m = 0.001;           // translation std per step, base, metres
  double odometry_sigma_fraction = 0.02;     // ... plus this share of the step length
  double odometry_sigma_deg = 0.05;          // rotation std per step, base, degrees
  double odometry_sigma_deg_per_deg = 0.02;  // ... plus this share of the step rotation
  double odometry_sigma_deg_per_m = 1.0;     // ... plus this many degrees per metre travelled
  // View links (graph): std of an ICP-measured relative pose.
  double link_sigma_m = 0.01;
  double link_sigma_deg = 1.0;
  // Bounds and acceptance. A keyframe may move at most max_translation_m plus
  // max_translation_fraction of the path travelled up to it (drift grows with the path), and turn
  // at most max_rotation_deg plus max_rotation_deg_per_m per metre travelled.
  double max_translation_m = 0.10;  // a larger correction of any keyframe refuses the result
  double max_translation_fraction = 0.0;
  double max_rotation_deg = 5.0;  // idem, rotation
  double max_rotation_deg_per_m = 0.0;
  double min_improvement = 0.10;  // observation RMS must drop by this share (else refused)
  // A correction whose largest keyframe change is below both is refused: it is below what depth
  // images and object alignments can resolve (ycbv: 0.3 mm moves that made a 0.02 mm ATE 0.1 mm).
  double min_translation_m = 0.001;
  double min_rotation_deg = 0.1;
  int max_iterations = 100;  // Ceres iterations
  // paper: false (default): eq 20 alone, as the paper states it; true: eq 20 plus a prior on the
  // input pose whose std is the drift the run may have accumulated (odometry sigmas × path length
  // so far; beyond the paper, docs/pose.md).
  bool paper_prior = false;
  double paper_prior_fraction = 0.005;  // prior std: odometry_sigma_m + this × path so far
  int reweight_rounds = 1;              // re-estimate each object's noise and solve again
  // Held-out check: the observations split in two folds (by object, or by keyframe with fewer
  // than 4 objects); a correction fitted to one fold must lower the other fold's residual RMS by
  // this share (fitting noise does not, correcting drift does).
  bool held_out_check = true;
  double min_held_out_improvement = 0.20;
  // With view links: the held-out links' RMS (in sigmas) must drop by this share too.
  double min_held_out_link_improvement = 0.25;
  void check() const;  // throws InputError naming the bad field
};

// What happened to one keyframe.
struct KeyframeCorrection {
  std::size_t index = 0;
  double timestamp = 0.0;
  int matched = 0;                 // observations (matched objects) of this keyframe
  double spread_m = 0.0;           // spread of the matched landmarks
  bool corrected = false;          // its pose changed
  std::string reason;              // why (or why not)
  double residual_before_m = 0.0;  // RMS of its observations' residuals, input pose (0: none)
  double residual_after_m = 0.0;   // ... with the corrected pose
  double translation_m = 0.0;      // ‖t_after − t_before‖
  double rotation_deg = 0.0;       // angle of R_after R_beforeᵀ
};

struct CorrectionResult {
  std::string method;
  bool accepted = false;                 // false: world_from_cam are the input poses
  std::string reason;                    // why accepted or refused (one line)
  std::vector<Pose> world_from_cam;      // one per keyframe (the input poses when refused)
  std::vector<Pose> proposed;            // the solver's poses, even when refused
  std::vector<Vec3> landmarks_in_world;  // graph: optimised landmarks; paper: the input ones
  std::vector<KeyframeCorrection> keyframes;
  std::size_t corrected_keyframes = 0;
  // Consistency: observation_rms_m (weighted by the landmarks' noise of the input poses), before
  // and after.
  double residual_before_m = 0.0;
  double residual_after_m = 0.0;
  double held_out_before_m = 0.0;            // the held-out folds' residual RMS, input poses
  double held_out_after_m = 0.0;             // ... with the poses fitted to the other fold
  double odometry_rms_sigmas = 0.0;          // graph: RMS of the odometry factors after, in sigmas
  double link_rms_before_sigmas = 0.0;       // graph: RMS of the view links, input poses, in sigmas
  double link_rms_after_sigmas = 0.0;        // ... with the proposed poses
  double held_out_link_before_sigmas = 0.0;  // the held-out folds' link RMS, input poses
  double held_out_link_after_sigmas = 0.0;   // ... with the poses fitted to the other fold
  double max_translation_m = 0.0;            // largest keyframe correction
  double max_rotation_deg = 0.0;
  int iterations = 0;
  double seconds = 0.0;
};

// Throws InputError for an observation naming a missing keyframe or landmark, a non-positive
// weight or bad options.
CorrectionResult correct_poses(const Problem& problem, const CorrectionOptions& options);

// RMS of ‖world_from_cam[k]·c − L − bias‖ over the observations, with each landmark L the mean of
// its observations' (world_from_cam·c − bias) (landmarks seen once do not count): the consistency
// measure of a set of keyframe poses. Weighted by 1/sigma² of each landmark when
// `landmark_sigma_m` is given (one per landmark); only the observations flagged in
// `use_observation` when it is given (the landmark means then over those only).
double observation_rms_m(const Problem& problem, const std::vector<Pose>& world_from_cam,
                         const std::vector<double>& landmark_sigma_m = {},
                         const std::vector<bool>& use_observation = {});

// The median over the landmarks seen at least twice of their scatter (landmark_sigmas_m with no
// floor): a map consistency measure that the large, partially seen objects do not dominate.
double median_scatter_m(const Problem& problem, const std::vector<Pose>& world_from_cam);

// Each landmark's noise: the per-axis standard deviation of its observations
// (world_from_cam·c − bias) about their mean, at least `floor_m` (floor_m for landmarks seen once).
std::vector<double> landmark_sigmas_m(const Problem& problem,
                                      const std::vector<Pose>& world_from_cam, double floor_m);

// Spreads keyframe corrections to every pose of `input`: the world-side correction
// C_k = after_k · before_k⁻¹ of the keyframes is interpolated in time (linear translation, slerp
// rotation) between the two keyframes around each pose and held constant before the first and
// after the last; corrected = C(t) · input(t). Every input pose is kept, with its timestamp.
Trajectory apply_corrections(const Trajectory& input, const std::vector<StampedPose>& before,
                             const std::vector<Pose>& after);

}  // namespace objmap::pose
