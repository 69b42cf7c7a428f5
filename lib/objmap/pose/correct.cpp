#include "objmap/pose/correct.h"

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

#include "objmap/core/clock.h"
#include "objmap/core/error.h"
#include "objmap/pose/align.h"

namespace objmap::pose {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

std::string fmt(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, format, a, b, c);
  return buffer;
}

double angle_deg(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle() * kDegPerRad; }

// A keyframe pose as Ceres parameter blocks: unit quaternion (x, y, z, w; Eigen's memory order,
// EigenQuaternionManifold) and translation — the pose lives on SO(3) × R³.
struct PoseBlock {
  double q[4];
  double t[3];
  explicit PoseBlock(const Pose& pose) {
    const Eigen::Quaterniond quat(pose.linear());
    q[0] = quat.x(), q[1] = quat.y(), q[2] = quat.z(), q[3] = quat.w();
    t[0] = pose.translation().x(), t[1] = pose.translation().y(), t[2] = pose.translation().z();
  }
  Pose pose() const {
    Pose out = Pose::Identity();
    out.linear() = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
    out.translation() = Vec3(t[0], t[1], t[2]);
    return out;
  }
};

// Eq 20 for one pair: world_from_cam · c − target, in sigmas.
struct PointFactor {
  Vec3 centroid_in_cam, target_in_world;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* q, const T* t, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> translation(t);
    const Eigen::Matrix<T, 3, 1> predicted = rotation * centroid_in_cam.cast<T>() + translation;
    for (int i = 0; i < 3; ++i) residual[i] = (predicted[i] - T(target_in_world[i])) * T(inv_sigma);
    return true;
  }
};

// A landmark seen from a keyframe: world_from_cam · c − (landmark + bias), in sigmas.
// The error is taken in the camera frame with its component along the viewing ray (the
// direction of the centroid) divided by ray_sigma_factor: depth-direction errors of a centroid
// (mask bleeding onto the background, depth noise) are larger than lateral ones.
struct LandmarkFactor {
  Vec3 centroid_in_cam, bias_in_world;
  double inv_sigma;
  double ray_scale;  // 1 / ray_sigma_factor
  template <typename T>
  bool operator()(const T* q, const T* t, const T* landmark, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> translation(t);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> point(landmark);
    const Eigen::Matrix<T, 3, 1> error_in_world =
        rotation * centroid_in_cam.cast<T>() + translation - point - bias_in_world.cast<T>();
    const Eigen::Matrix<T, 3, 1> error = rotation.conjugate() * error_in_world;
    const Eigen::Matrix<T, 3, 1> ray = centroid_in_cam.normalized().cast<T>();
    const Eigen::Matrix<T, 3, 1> scaled = error + (T(ray_scale) - T(1.0)) * ray.dot(error) * ray;
    for (int i = 0; i < 3; ++i) residual[i] = scaled[i] * T(inv_sigma);
    return true;
  }
};

// Relative pose i → j as the input trajectory has it (the SLAM run's odometry): translation
// error in the frame of i and the rotation error (2·vec of the error quaternion ≈ angle axis),
// each in sigmas.
struct OdometryFactor {
  Eigen::Quaterniond i_from_j_rotation;
  Vec3 i_from_j_translation;
  double inv_sigma_m, inv_sigma_rad;
  template <typename T>
  bool operator()(const T* qi, const T* ti, const T* qj, const T* tj, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rot_i(qi), rot_j(qj);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> pos_i(ti), pos_j(tj);
    const Eigen::Quaternion<T> i_inverse = rot_i.conjugate();
    const Eigen::Matrix<T, 3, 1> translation = i_inverse * (pos_j - pos_i);
    const Eigen::Quaternion<T> error =
        i_from_j_rotation.conjugate().cast<T>() * (i_inverse * rot_j);
    for (int k = 0; k < 3; ++k) {
      residual[k] = (translation[k] - T(i_from_j_translation[k])) * T(inv_sigma_m);
      residual[3 + k] = T(2.0) * error.vec()[k] * T(inv_sigma_rad);
    }
    return true;
  }
};

// A pose stays near the input pose: the drift the SLAM run can have accumulated so far bounds
// how far eq 20 may move it (translation in the world frame and rotation, in sigmas).
struct PriorFactor {
  Eigen::Quaterniond rotation;
  Vec3 translation;
  double inv_sigma_m, inv_sigma_rad;
  template <typename T>
  bool operator()(const T* q, const T* t, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rot(q);
    const Eigen::Quaternion<T> error = rotation.conjugate().cast<T>() * rot;
    for (int k = 0; k < 3; ++k) {
      residual[k] = (t[k] - T(translation[k])) * T(inv_sigma_m);
      residual[3 + k] = T(2.0) * error.vec()[k] * T(inv_sigma_rad);
    }
    return true;
  }
};

ceres::Solver::Options solver_options(const CorrectionOptions& options) {
  ceres::Solver::Options s;
  s.max_num_iterations = options.max_iterations;
  s.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  s.num_threads = 1;  // deterministic
  s.logging_type = ceres::SILENT;
  s.minimizer_progress_to_stdout = false;
  return s;
}

void validate(const Problem& problem) {
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const Observation& o = problem.observations[i];
    const std::string where = "observation " + std::to_string(i);
    require(o.keyframe < problem.keyframes.size(), where,
            "keyframe " + std::to_string(o.keyframe) + " does not exist; expected < " +
                std::to_string(problem.keyframes.size()));
    require(o.landmark < problem.landmarks.size(), where,
            "landmark " + std::to_string(o.landmark) + " does not exist; expected < " +
                std::to_string(problem.landmarks.size()));
    require(std::isfinite(o.weight) && o.weight > 0, where, "weight must be > 0");
    require(o.centroid_in_cam.allFinite() && o.bias_in_world.allFinite(), where,
            "centroid and bias must be finite");
  }
  for (std::size_t i = 0; i < problem.links.size(); ++i) {
    const ViewLink& l = problem.links[i];
    const std::string where = "link " + std::to_string(i);
    require(l.a < problem.keyframes.size() && l.b < problem.keyframes.size() && l.a != l.b, where,
            "keyframes " + std::to_string(l.a) + " and " + std::to_string(l.b) +
                ": expected two different keyframes < " + std::to_string(problem.keyframes.size()));
    require(l.landmark < problem.landmarks.size(), where,
            "landmark " + std::to_string(l.landmark) + " does not exist");
    require(l.a_from_b.matrix().allFinite(), where, "relative pose must be finite");
    require(std::isfinite(l.sigma_m) && l.sigma_m >= 0 && std::isfinite(l.sigma_deg) &&
                l.sigma_deg >= 0,
            where, "sigmas must be finite and >= 0");
  }
}

// Residual of a relative pose a_from_b against poses, in sigmas (translation, rotation).
double relative_pose_sigmas(const Pose& measured, const Pose& a, const Pose& b, double sigma_m,
                            double sigma_deg) {
  const Pose actual = a.inverse() * b;
  const double et = (actual.translation() - measured.translation()).norm() / sigma_m;
  const double er = angle_deg(measured.linear().transpose() * actual.linear()) / sigma_deg;
  return std::sqrt(et * et + er * er);
}

// A link's std: its own, at least the options' floor.
double link_sigma_m(const CorrectionOptions& options, const ViewLink& l) {
  return std::max(options.link_sigma_m, l.sigma_m);
}
double link_sigma_deg(const CorrectionOptions& options, const ViewLink& l) {
  return std::max(options.link_sigma_deg, l.sigma_deg);
}

// RMS over the links of relative_pose_sigmas.
// (only the links flagged in `use` when it is given).
double link_rms_sigmas(const Problem& problem, const std::vector<Pose>& poses,
                       const CorrectionOptions& options, const std::vector<bool>& use = {}) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < problem.links.size(); ++i) {
    if (!use.empty() && !use[i]) continue;
    const ViewLink& l = problem.links[i];
    const double e = relative_pose_sigmas(l.a_from_b, poses[l.a], poses[l.b],
                                          link_sigma_m(options, l), link_sigma_deg(options, l));
    sum += e * e;
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

// Residual RMS of one keyframe's observations against given landmark positions.
double keyframe_rms(const Problem& problem, const std::vector<std::size_t>& obs, const Pose& pose,
                    const std::vector<Vec3>& landmarks) {
  if (obs.empty()) return 0.0;
  double sum = 0.0;
  for (std::size_t k : obs) {
    const Observation& o = problem.observations[k];
    sum += (pose * o.centroid_in_cam - landmarks[o.landmark] - o.bias_in_world).squaredNorm();
  }
  return std::sqrt(sum / obs.size());
}

}  // namespace

void CorrectionOptions::check() const {
  require(method == "graph" || method == "paper", "CorrectionOptions.method",
          "'" + method + "' is not a method; expected graph or paper");
  require(min_pairs >= 3, "CorrectionOptions.min_pairs",
          "must be >= 3 (three non-collinear points fix a pose), got " + std::to_string(min_pairs));
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0; };
  require(non_negative(min_spread_m), "CorrectionOptions.min_spread_m", "must be >= 0");
  require(positive(observation_sigma_m), "CorrectionOptions.observation_sigma_m", "must be > 0");
  require(positive(robust_sigmas), "CorrectionOptions.robust_sigmas", "must be > 0");
  require(positive(odometry_sigma_m), "CorrectionOptions.odometry_sigma_m", "must be > 0");
  require(non_negative(odometry_sigma_fraction), "CorrectionOptions.odometry_sigma_fraction",
          "must be >= 0");
  require(positive(odometry_sigma_deg), "CorrectionOptions.odometry_sigma_deg", "must be > 0");
  require(non_negative(odometry_sigma_deg_per_deg), "CorrectionOptions.odometry_sigma_deg_per_deg",
          "must be >= 0");
  require(non_negative(odometry_sigma_deg_per_m), "CorrectionOptions.odometry_sigma_deg_per_m",
          "must be >= 0");
  require(positive(max_translation_m), "CorrectionOptions.max_translation_m", "must be > 0");
  require(positive(max_rotation_deg), "CorrectionOptions.max_rotation_deg", "must be > 0");
  require(non_negative(min_translation_m), "CorrectionOptions.min_translation_m", "must be >= 0");
  require(non_negative(min_rotation_deg), "CorrectionOptions.min_rotation_deg", "must be >= 0");
  require(non_negative(max_translation_fraction), "CorrectionOptions.max_translation_fraction",
          "must be >= 0");
  require(non_negative(max_rotation_deg_per_m), "CorrectionOptions.max_rotation_deg_per_m",
          "must be >= 0");
  require(positive(link_sigma_m), "CorrectionOptions.link_sigma_m", "must be > 0");
  require(positive(link_sigma_deg), "CorrectionOptions.link_sigma_deg", "must be > 0");
  require(std::isfinite(min_held_out_link_improvement) && min_held_out_link_improvement < 1,
          "CorrectionOptions.min_held_out_link_improvement", "must be < 1");
  require(std::isfinite(min_improvement) && min_improvement >= 0 && min_improvement < 1,
          "CorrectionOptions.min_improvement", "must be in [0, 1)");
  require(std::isfinite(ray_sigma_factor) && ray_sigma_factor >= 1,
          "CorrectionOptions.ray_sigma_factor", "must be >= 1");
  require(reweight_rounds >= 0, "CorrectionOptions.reweight_rounds", "must be >= 0");
  require(std::isfinite(min_held_out_improvement) && min_held_out_improvement < 1,
          "CorrectionOptions.min_held_out_improvement", "must be < 1");
  require(max_iterations >= 1, "CorrectionOptions.max_iterations", "must be >= 1");
}

double median_scatter_m(const Problem& problem, const std::vector<Pose>& world_from_cam) {
  std::vector<int> count(problem.landmarks.size(), 0);
  for (const Observation& o : problem.observations) ++count[o.landmark];
  const std::vector<double> sigma = landmark_sigmas_m(problem, world_from_cam, 0.0);
  std::vector<double> seen;
  for (std::size_t j = 0; j < sigma.size(); ++j)
    if (count[j] >= 2) seen.push_back(sigma[j]);
  if (seen.empty()) return 0.0;
  std::sort(seen.begin(), seen.end());
  const std::size_t n = seen.size();
  return n % 2 ? seen[n / 2] : 0.5 * (seen[n / 2 - 1] + seen[n / 2]);
}

double observation_rms_m(const Problem& problem, const std::vector<Pose>& world_from_cam,
                         const std::vector<double>& landmark_sigma_m,
                         const std::vector<bool>& use_observation) {
  require(world_from_cam.size() == problem.keyframes.size(), "observation_rms_m",
          "one pose per keyframe expected");
  const std::size_t n_lm = problem.landmarks.size();
  const auto used = [&](std::size_t i) { return use_observation.empty() || use_observation[i]; };
  const auto weight = [&](std::size_t j) {
    return landmark_sigma_m.empty() ? 1.0 : 1.0 / (landmark_sigma_m[j] * landmark_sigma_m[j]);
  };
  std::vector<Vec3> sum(n_lm, Vec3::Zero());
  std::vector<int> count(n_lm, 0);
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const Observation& o = problem.observations[i];
    if (!used(i)) continue;
    sum[o.landmark] += world_from_cam[o.keyframe] * o.centroid_in_cam - o.bias_in_world;
    ++count[o.landmark];
  }
  double total = 0.0, weights = 0.0;
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const Observation& o = problem.observations[i];
    if (!used(i) || count[o.landmark] < 2) continue;
    const Vec3 mean = sum[o.landmark] / count[o.landmark];
    const double w = weight(o.landmark);
    total +=
        w * (world_from_cam[o.keyframe] * o.centroid_in_cam - o.bias_in_world - mean).squaredNorm();
    weights += w;
  }
  return weights > 0 ? std::sqrt(total / weights) : 0.0;
}

std::vector<double> landmark_sigmas_m(const Problem& problem,
                                      const std::vector<Pose>& world_from_cam, double floor_m) {
  const std::size_t n_lm = problem.landmarks.size();
  std::vector<Vec3> sum(n_lm, Vec3::Zero());
  std::vector<int> count(n_lm, 0);
  for (const Observation& o : problem.observations) {
    sum[o.landmark] += world_from_cam[o.keyframe] * o.centroid_in_cam - o.bias_in_world;
    ++count[o.landmark];
  }
  std::vector<double> squares(n_lm, 0.0);
  for (const Observation& o : problem.observations) {
    const Vec3 mean = sum[o.landmark] / count[o.landmark];
    squares[o.landmark] +=
        (world_from_cam[o.keyframe] * o.centroid_in_cam - o.bias_in_world - mean).squaredNorm();
  }
  std::vector<double> sigma(n_lm, floor_m);
  for (std::size_t j = 0; j < n_lm; ++j)
    if (count[j] >= 2)  // per-axis std of the observations about their mean
      sigma[j] = std::max(floor_m, std::sqrt(squares[j] / (3.0 * (count[j] - 1))));
  return sigma;
}

namespace {

struct Solution {
  std::vector<Pose> poses;
  std::vector<Vec3> landmarks;
  std::vector<std::string> reasons;
  int iterations = 0;
};

// Eqs 19-20, keyframe by keyframe against the fixed landmarks.
Solution solve_paper(const Problem& problem, const CorrectionOptions& options,
                     const std::vector<Pose>& input, const std::vector<Vec3>& landmarks,
                     const std::vector<double>& sigma, const std::vector<bool>& use) {
  Solution s;
  s.poses = input;
  s.landmarks = landmarks;
  s.reasons.assign(input.size(), "");
  // Path length travelled up to each keyframe: the drift budget of the prior.
  std::vector<double> travelled(input.size(), 0.0);
  for (std::size_t k = 1; k < input.size(); ++k)
    travelled[k] = travelled[k - 1] + (input[k].translation() - input[k - 1].translation()).norm();
  std::vector<std::vector<std::size_t>> of_keyframe(input.size());
  for (std::size_t i = 0; i < problem.observations.size(); ++i)
    if (use[i]) of_keyframe[problem.observations[i].keyframe].push_back(i);
  for (std::size_t k = 0; k < input.size(); ++k) {
    const auto& obs = of_keyframe[k];
    if (static_cast<int>(obs.size()) < options.min_pairs) {
      s.reasons[k] = "refused: " + std::to_string(obs.size()) + " matched objects, needs " +
                     std::to_string(options.min_pairs);
      continue;
    }
    std::vector<Vec3> source, target, matched;
    std::vector<double> weights;
    for (std::size_t i : obs) {
      const Observation& o = problem.observations[i];
      source.push_back(o.centroid_in_cam);
      target.push_back(landmarks[o.landmark] + o.bias_in_world);
      matched.push_back(landmarks[o.landmark]);
      weights.push_back(o.weight / (sigma[o.landmark] * sigma[o.landmark]));
    }
    const double spread = spread_m(matched);
    if (spread < options.min_spread_m) {
      s.reasons[k] = fmt("refused: objects nearly collinear (spread %.3f m < %.3f m)", spread,
                         options.min_spread_m);
      continue;
    }
    // 1. Closed form (Horn/Umeyama) on the pairs (c_in_cam, landmark + bias).
    const Pose closed_form = align_rigid(source, target, weights);
    // 2. Refinement with a robust loss, the pose on SO(3) × R³.
    PoseBlock block(closed_form);
    ceres::Problem cp;
    for (std::size_t i = 0; i < source.size(); ++i) {
      auto* cost = new ceres::AutoDiffCostFunction<PointFactor, 3, 4, 3>(
          new PointFactor{source[i], target[i], std::sqrt(weights[i])});
      cp.AddResidualBlock(cost, new ceres::HuberLoss(options.robust_sigmas), block.q, block.t);
    }
    if (options.paper_prior) {
      const double sigma_m = options.odometry_sigma_m + options.paper_prior_fraction * travelled[k];
      const double sigma_deg =
          options.odometry_sigma_deg + options.odometry_sigma_deg_per_m * travelled[k];
      cp.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorFactor, 6, 4, 3>(new PriorFactor{
                              Eigen::Quaterniond(input[k].linear()), input[k].translation(),
                              1.0 / sigma_m, kDegPerRad / sigma_deg}),
                          nullptr, block.q, block.t);
    }
    cp.SetManifold(block.q, new ceres::EigenQuaternionManifold);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options(options), &cp, &summary);
    s.iterations += static_cast<int>(summary.iterations.size());
    const Pose refined = block.pose();
    // 3. Accept only a decrease of the residual, within the bounds.
    const double before = keyframe_rms(problem, obs, input[k], landmarks);
    const double after = keyframe_rms(problem, obs, refined, landmarks);
    const double moved = (refined.translation() - input[k].translation()).norm();
    const double turned = angle_deg(refined.linear() * input[k].linear().transpose());
    if (!(after < before)) {
      s.reasons[k] = fmt("refused: residual %.4f -> %.4f m does not decrease", before, after);
    } else if (moved > options.max_translation_m || turned > options.max_rotation_deg) {
      s.reasons[k] = fmt("refused: correction %.3f m / %.2f deg over the bounds", moved, turned);
    } else {
      s.poses[k] = refined;
      s.reasons[k] = "corrected (eq 20, " + std::to_string(obs.size()) + " objects)";
    }
  }
  return s;
}

double odometry_sigma_m(const CorrectionOptions& o, const Pose& i_from_j) {
  return o.odometry_sigma_m + o.odometry_sigma_fraction * i_from_j.translation().norm();
}
double odometry_sigma_deg(const CorrectionOptions& o, const Pose& i_from_j) {
  return o.odometry_sigma_deg + o.odometry_sigma_deg_per_deg * angle_deg(i_from_j.linear()) +
         o.odometry_sigma_deg_per_m * i_from_j.translation().norm();
}

// One pose graph: every keyframe pose and every used landmark seen at least twice.
Solution solve_graph(const Problem& problem, const CorrectionOptions& options,
                     const std::vector<Pose>& input, const std::vector<Vec3>& landmarks,
                     const std::vector<double>& sigma, const std::vector<bool>& use,
                     const std::vector<bool>& use_link) {
  const std::size_t n_kf = input.size();
  std::vector<int> seen(problem.landmarks.size(), 0);
  std::vector<int> of_keyframe(n_kf, 0);
  for (std::size_t i = 0; i < problem.observations.size(); ++i)
    if (use[i]) ++seen[problem.observations[i].landmark];
  std::vector<PoseBlock> blocks;
  blocks.reserve(n_kf);
  for (const Pose& p : input) blocks.emplace_back(p);
  std::vector<Vec3> landmark_blocks = landmarks;
  ceres::Problem cp;
  // Relative-pose factors from the input trajectory (the SLAM run's odometry).
  for (std::size_t k = 0; k + 1 < n_kf; ++k) {
    const Pose i_from_j = input[k].inverse() * input[k + 1];
    auto* cost = new ceres::AutoDiffCostFunction<OdometryFactor, 6, 4, 3, 4, 3>(
        new OdometryFactor{Eigen::Quaterniond(i_from_j.linear()), i_from_j.translation(),
                           1.0 / odometry_sigma_m(options, i_from_j),
                           kDegPerRad / odometry_sigma_deg(options, i_from_j)});
    cp.AddResidualBlock(cost, nullptr, blocks[k].q, blocks[k].t, blocks[k + 1].q, blocks[k + 1].t);
  }
  // Object observation factors (robust), each landmark with its own noise.
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const Observation& o = problem.observations[i];
    if (!use[i] || seen[o.landmark] < 2) continue;
    ++of_keyframe[o.keyframe];
    auto* cost = new ceres::AutoDiffCostFunction<LandmarkFactor, 3, 4, 3, 3>(new LandmarkFactor{
        o.centroid_in_cam, o.bias_in_world, std::sqrt(o.weight) / sigma[o.landmark],
        1.0 / options.ray_sigma_factor});
    cp.AddResidualBlock(cost, new ceres::HuberLoss(options.robust_sigmas), blocks[o.keyframe].q,
                        blocks[o.keyframe].t, landmark_blocks[o.landmark].data());
  }
  // View links: the relative pose two views of one object measure (robust: a wrong alignment).
  for (std::size_t i = 0; i < problem.links.size(); ++i) {
    if (!use_link[i]) continue;
    const ViewLink& l = problem.links[i];
    auto* cost = new ceres::AutoDiffCostFunction<OdometryFactor, 6, 4, 3, 4, 3>(new OdometryFactor{
        Eigen::Quaterniond(l.a_from_b.linear()), l.a_from_b.translation(),
        1.0 / link_sigma_m(options, l), kDegPerRad / link_sigma_deg(options, l)});
    cp.AddResidualBlock(cost, new ceres::HuberLoss(options.robust_sigmas), blocks[l.a].q,
                        blocks[l.a].t, blocks[l.b].q, blocks[l.b].t);
  }
  for (auto& b : blocks)
    if (cp.HasParameterBlock(b.q)) cp.SetManifold(b.q, new ceres::EigenQuaternionManifold);
  // Gauge: the first keyframe stays where the SLAM run put it.
  if (n_kf > 0 && cp.HasParameterBlock(blocks[0].q)) {
    cp.SetParameterBlockConstant(blocks[0].q);
    cp.SetParameterBlockConstant(blocks[0].t);
  }
  Solution s;
  if (cp.NumResidualBlocks() > 0) {
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options(options), &cp, &summary);
    s.iterations = static_cast<int>(summary.iterations.size());
  }
  for (std::size_t k = 0; k < n_kf; ++k) s.poses.push_back(blocks[k].pose());
  s.landmarks = landmark_blocks;
  for (std::size_t k = 0; k < n_kf; ++k) {
    const int n = of_keyframe[k];
    s.reasons.push_back(k == 0 ? "fixed (gauge)"
                        : n >= options.min_pairs
                            ? "corrected (graph, " + std::to_string(n) + " objects)"
                            : "corrected through odometry only (" + std::to_string(n) +
                                  " objects)");
  }
  return s;
}

// The method with IRLS on the per-landmark noise: solve, re-estimate each landmark's sigma from
// the residuals of the solution, solve again.
Solution solve(const Problem& problem, const CorrectionOptions& options,
               const std::vector<Pose>& input, const std::vector<Vec3>& landmarks,
               const std::vector<bool>& use, const std::vector<bool>& use_link) {
  std::vector<double> sigma = landmark_sigmas_m(problem, input, options.observation_sigma_m);
  Solution s;
  for (int round = 0; round <= options.reweight_rounds; ++round) {
    s = options.method == "paper"
            ? solve_paper(problem, options, input, landmarks, sigma, use)
            : solve_graph(problem, options, input, landmarks, sigma, use, use_link);
    sigma = landmark_sigmas_m(problem, s.poses, options.observation_sigma_m);
  }
  return s;
}

// The problem's input: keyframe poses, landmark positions and each keyframe's observations.
struct Inputs {
  std::vector<Pose> poses;
  std::vector<Vec3> landmarks;
  std::vector<std::vector<std::size_t>> of_keyframe;
};

Inputs inputs_of(const Problem& problem) {
  const std::size_t n_kf = problem.keyframes.size();
  const std::size_t n_lm = problem.landmarks.size();
  Inputs in;
  in.poses.resize(n_kf);
  for (std::size_t k = 0; k < n_kf; ++k) in.poses[k] = problem.keyframes[k].world_from_cam;
  in.landmarks.resize(n_lm);
  for (std::size_t j = 0; j < n_lm; ++j) in.landmarks[j] = problem.landmarks[j].position_in_world;
  in.of_keyframe.resize(n_kf);
  for (std::size_t i = 0; i < problem.observations.size(); ++i)
    in.of_keyframe[problem.observations[i].keyframe].push_back(i);
  return in;
}

// The held-out check's figures: RMS of the held-out observations (m) and view links (sigmas)
// before and after, and the solver's iterations.
struct HeldOut {
  double before = 0.0, after = 0.0, link_before = 0.0, link_after = 0.0;
  int iterations = 0;
};

// Held-out check, two folds: corrections fitted to one half of the observations must make the
// other half more consistent too. Fitting noise does not; drift does. The folds split the objects
// (>= 4 objects), else the keyframes (alternately).
HeldOut held_out_check(const Problem& problem, const CorrectionOptions& options, const Inputs& in,
                       const std::vector<double>& sigma_in) {
  HeldOut h;
  if (!options.held_out_check) return h;
  const std::size_t n_obs = problem.observations.size();
  const std::size_t n_links = problem.links.size();
  const bool by_object = problem.landmarks.size() >= 4;
  for (int fold = 0; fold < 2; ++fold) {
    std::vector<bool> fit(n_obs), test(n_obs);
    for (std::size_t i = 0; i < n_obs; ++i) {
      const Observation& o = problem.observations[i];
      test[i] = static_cast<int>((by_object ? o.landmark : o.keyframe) % 2) == fold;
      fit[i] = !test[i];
    }
    std::vector<bool> fit_link(n_links);
    // Links by a hash of their index: the order of links follows their kind (the previous
    // view, the earliest...), and each fold must have some of every kind.
    for (std::size_t i = 0; i < n_links; ++i)
      fit_link[i] = static_cast<int>(((i * 2654435761u) >> 16) & 1u) != fold;
    const Solution s = solve(problem, options, in.poses, in.landmarks, fit, fit_link);
    h.iterations += s.iterations;
    const double b = observation_rms_m(problem, in.poses, sigma_in, test);
    const double a = observation_rms_m(problem, s.poses, sigma_in, test);
    h.before += b * b;
    h.after += a * a;
    std::vector<bool> test_link(n_links);
    for (std::size_t i = 0; i < n_links; ++i) test_link[i] = !fit_link[i];
    const double lb = link_rms_sigmas(problem, in.poses, options, test_link);
    const double la = link_rms_sigmas(problem, s.poses, options, test_link);
    h.link_before += lb * lb;
    h.link_after += la * la;
  }
  h.before = std::sqrt(h.before / 2.0);
  h.after = std::sqrt(h.after / 2.0);
  h.link_before = std::sqrt(h.link_before / 2.0);
  h.link_after = std::sqrt(h.link_after / 2.0);
  return h;
}

// Per-keyframe report and the bounds (which grow with the path travelled, as drift does); returns
// why the result is over the bounds (empty when it is not).
std::string keyframe_report(const Problem& problem, const CorrectionOptions& options,
                            const Inputs& in, const Solution& all, CorrectionResult& result) {
  const std::vector<Pose>& input = in.poses;
  const std::vector<Pose>& proposed = all.poses;
  double travelled = 0.0;
  std::string over_bounds;
  for (std::size_t k = 0; k < problem.keyframes.size(); ++k) {
    std::vector<Vec3> matched;
    for (std::size_t i : in.of_keyframe[k])
      matched.push_back(in.landmarks[problem.observations[i].landmark]);
    KeyframeCorrection kc;
    kc.index = k;
    kc.timestamp = problem.keyframes[k].timestamp;
    kc.matched = static_cast<int>(in.of_keyframe[k].size());
    kc.spread_m = spread_m(matched);
    kc.residual_before_m = keyframe_rms(problem, in.of_keyframe[k], input[k], in.landmarks);
    kc.residual_after_m = keyframe_rms(problem, in.of_keyframe[k], proposed[k], all.landmarks);
    kc.translation_m = (proposed[k].translation() - input[k].translation()).norm();
    kc.rotation_deg = angle_deg(proposed[k].linear() * input[k].linear().transpose());
    if (k > 0) travelled += (input[k].translation() - input[k - 1].translation()).norm();
    const double bound_m = options.max_translation_m + options.max_translation_fraction * travelled;
    const double bound_deg = options.max_rotation_deg + options.max_rotation_deg_per_m * travelled;
    if (over_bounds.empty() && (kc.translation_m > bound_m || kc.rotation_deg > bound_deg))
      over_bounds =
          fmt("refused: a keyframe would move %.3f m / %.2f deg, over the bounds", kc.translation_m,
              kc.rotation_deg) +
          fmt(" (%.3f m / %.2f deg", bound_m, bound_deg) +
          fmt(" for keyframe %.0f after %.2f m of path)", static_cast<double>(k), travelled);
    kc.corrected = kc.translation_m > 0.0 || kc.rotation_deg > 0.0;
    kc.reason = all.reasons[k];
    result.max_translation_m = std::max(result.max_translation_m, kc.translation_m);
    result.max_rotation_deg = std::max(result.max_rotation_deg, kc.rotation_deg);
    result.corrected_keyframes += kc.corrected;
    result.keyframes.push_back(kc);
  }
  return over_bounds;
}

// The consistency of the whole result: observation RMS before and after; with the graph, the
// odometry RMS and the view links' RMS in sigmas.
void consistency(const Problem& problem, const CorrectionOptions& options, const Inputs& in,
                 const std::vector<double>& sigma_in, const std::vector<Pose>& proposed,
                 CorrectionResult& result) {
  const std::vector<Pose>& input = in.poses;
  const std::size_t n_kf = problem.keyframes.size();
  result.residual_before_m = observation_rms_m(problem, input, sigma_in);
  result.residual_after_m = observation_rms_m(problem, proposed, sigma_in);
  if (options.method != "graph") return;
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < n_kf; ++k) {
    const Pose i_from_j = input[k].inverse() * input[k + 1];
    const double e = relative_pose_sigmas(i_from_j, proposed[k], proposed[k + 1],
                                          odometry_sigma_m(options, i_from_j),
                                          odometry_sigma_deg(options, i_from_j));
    sum += e * e;
  }
  result.odometry_rms_sigmas = n_kf > 1 ? std::sqrt(sum / (n_kf - 1)) : 0.0;
  result.link_rms_before_sigmas = link_rms_sigmas(problem, input, options);
  result.link_rms_after_sigmas = link_rms_sigmas(problem, proposed, options);
}

// The guardrails: the result is refused when it moves a pose beyond the bounds, does not make the
// observations consistent enough, or does not generalise to held-out objects. Sets accepted and
// the reason.
void guardrails(const Problem& problem, const CorrectionOptions& options, const HeldOut& held,
                const std::string& over_bounds, CorrectionResult& result) {
  const double needed = result.residual_before_m * (1.0 - options.min_improvement);
  const double held_needed = held.before * (1.0 - options.min_held_out_improvement);
  if (result.corrected_keyframes == 0) {
    result.reason = "refused: no keyframe has enough evidence for a correction";
  } else if (!over_bounds.empty()) {
    result.reason = over_bounds;
  } else if (!(result.residual_after_m <= needed)) {
    result.reason = fmt(
        "refused: object observations not consistent enough: residual RMS %.4f -> %.4f m, needs "
        "<= %.4f m",
        result.residual_before_m, result.residual_after_m, needed);
  } else if (options.held_out_check && !problem.links.empty() &&
             !(held.link_after <=
               held.link_before * (1.0 - options.min_held_out_link_improvement))) {
    result.reason =
        fmt("refused: too little gain on held-out view links (RMS %.2f -> %.2f sigmas, needs <= "
            "%.2f): the views of the objects do not confirm the correction",
            held.link_before, held.link_after,
            held.link_before * (1.0 - options.min_held_out_link_improvement));
  } else if (options.held_out_check && !(held.after <= held_needed)) {
    result.reason =
        fmt("refused: too little gain on held-out observations (residual RMS %.4f -> %.4f m, needs "
            "<= %.4f m): the correction would fit noise or a systematic bias, not drift",
            held.before, held.after, held_needed);
  } else if (result.max_translation_m < options.min_translation_m &&
             result.max_rotation_deg < options.min_rotation_deg) {
    result.reason =
        fmt("refused: nothing to correct: the largest change, %.4f m / %.3f deg, is",
            result.max_translation_m, result.max_rotation_deg) +
        fmt(" below %.4f m / %.3f deg", options.min_translation_m, options.min_rotation_deg);
  } else {
    result.accepted = true;
    result.reason = fmt("accepted: residual RMS %.4f -> %.4f m, held-out %.4f",
                        result.residual_before_m, result.residual_after_m, held.before) +
                    fmt(" -> %.4f m, ", held.after) + std::to_string(result.corrected_keyframes) +
                    " keyframes corrected";
  }
}

}  // namespace

CorrectionResult correct_poses(const Problem& problem, const CorrectionOptions& options) {
  options.check();
  validate(problem);
  const auto t_start = Clock::now();
  CorrectionResult result;
  result.method = options.method;
  const Inputs in = inputs_of(problem);

  // 1. Solve with every landmark.
  const Solution all = solve(problem, options, in.poses, in.landmarks,
                             std::vector<bool>(problem.observations.size(), true),
                             std::vector<bool>(problem.links.size(), true));

  // 2. Held-out check, two folds: fitted to one half, the other half must get more consistent.
  const std::vector<double> sigma_in =
      landmark_sigmas_m(problem, in.poses, options.observation_sigma_m);
  const HeldOut held = held_out_check(problem, options, in, sigma_in);
  result.held_out_link_before_sigmas = held.link_before;
  result.held_out_link_after_sigmas = held.link_after;
  result.held_out_before_m = held.before;
  result.held_out_after_m = held.after;

  // 3. Per-keyframe report, the bounds and the consistency of the proposed poses.
  result.proposed = all.poses;
  const std::string over_bounds = keyframe_report(problem, options, in, all, result);
  consistency(problem, options, in, sigma_in, all.poses, result);
  result.iterations = all.iterations + held.iterations;

  // 4. The guardrails: a refused result keeps the input poses.
  guardrails(problem, options, held, over_bounds, result);
  result.world_from_cam = result.accepted ? all.poses : in.poses;
  result.landmarks_in_world = result.accepted ? all.landmarks : in.landmarks;
  if (!result.accepted)
    for (auto& kc : result.keyframes) kc.corrected = false;
  result.seconds = seconds_since(t_start);
  return result;
}

Trajectory apply_corrections(const Trajectory& input, const std::vector<StampedPose>& before,
                             const std::vector<Pose>& after) {
  require(before.size() == after.size(), "apply_corrections",
          std::to_string(before.size()) + " keyframes before and " + std::to_string(after.size()) +
              " after; expected the same count");
  Trajectory out = input;
  if (before.empty()) return out;
  // World-side corrections at the keyframes.
  std::vector<Pose> correction(before.size());
  for (std::size_t k = 0; k < before.size(); ++k)
    correction[k] = after[k] * before[k].world_from_cam.inverse();
  for (StampedPose& p : out.poses) {
    const auto it =
        std::lower_bound(before.begin(), before.end(), p.timestamp,
                         [](const StampedPose& s, double t) { return s.timestamp < t; });
    Pose c;
    if (it == before.begin()) {
      c = correction.front();
    } else if (it == before.end()) {
      c = correction.back();
    } else {
      const std::size_t j = static_cast<std::size_t>(it - before.begin());
      const double t0 = before[j - 1].timestamp, t1 = before[j].timestamp;
      const double a = t1 > t0 ? (p.timestamp - t0) / (t1 - t0) : 1.0;
      const Eigen::Quaterniond q0(correction[j - 1].linear()), q1(correction[j].linear());
      c = Pose::Identity();
      c.linear() = q0.slerp(a, q1).toRotationMatrix();
      c.translation() =
          (1.0 - a) * correction[j - 1].translation() + a * correction[j].translation();
    }
    p.world_from_cam = c * p.world_from_cam;
  }
  return out;
}

}  // namespace objmap::pose
