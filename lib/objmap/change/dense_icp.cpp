#include "objmap/change/dense_icp.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/transformation_estimation.h>
#include <flann/flann.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "objmap/geometry/voxel_key.h"

namespace objmap::change::detail {

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Pose yaw_pose(double yaw_rad, const Vec3& t) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_rad, Vec3::UnitZ()).matrix();
  p.translation() = t;
  return p;
}

// Unit normals of a cloud (PCA of its 10 nearest points; +z where fewer are found), each
// computed when first asked for: ICP and the uncertainty need those of the paired points only.
class LazyNormals {
 public:
  LazyNormals(const pcl::KdTreeFLANN<pcl::PointXYZ>& tree, const Cloud& cloud)
      : tree_(tree), cloud_(cloud), normals_(cloud.size()), done_(cloud.size(), 0) {}
  const Vec3& operator[](std::size_t i) const {
    if (!done_[i]) {
      normals_[i] = compute(i);
      done_[i] = 1;
    }
    return normals_[i];
  }

 private:
  Vec3 compute(std::size_t i) const {
    pcl::Indices nn;
    std::vector<float> d2;
    if (tree_.nearestKSearch(cloud_[i], 10, nn, d2) < 5) return Vec3::UnitZ();
    Vec3 mean = Vec3::Zero();
    for (int k : nn) mean += Vec3(cloud_[k].x, cloud_[k].y, cloud_[k].z);
    mean /= static_cast<double>(nn.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int k : nn) {
      const Vec3 d = Vec3(cloud_[k].x, cloud_[k].y, cloud_[k].z) - mean;
      cov += d * d.transpose();
    }
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  }
  const pcl::KdTreeFLANN<pcl::PointXYZ>& tree_;
  const Cloud& cloud_;
  mutable std::vector<Vec3> normals_;
  mutable std::vector<char> done_;
};

// PCL's transformation step of ICP, restricted to a yaw about z and a translation (the two maps'
// up directions are known). With the correspondences (what IterativeClosestPoint calls): one
// Gauss-Newton step of the point-to-plane distances n·(R(θ)(p − c) + c + t − q) about the pairs'
// centroid c, the target normals given; two differently sampled scans of one surface then agree
// to a millimetre where point-to-point pairs would pull along the sampling. The other overloads:
// point-to-point least squares (fit_yaw_translation).
class YawTranslationEstimation
    : public pcl::registration::TransformationEstimation<pcl::PointXYZ, pcl::PointXYZ, float> {
 public:
  using Matrix4 = Eigen::Matrix4f;
  explicit YawTranslationEstimation(const LazyNormals& target_normals) : normals_(target_normals) {}
  // From now on all three rotations (the last round: where the two maps' up estimates disagree).
  void set_full_rotation(bool full) { full_ = full; }
  void estimateRigidTransformation(const Cloud& src, const Cloud& tgt, Matrix4& m) const override {
    std::vector<Vec3> s, t;
    for (std::size_t i = 0; i < std::min(src.size(), tgt.size()); ++i) add(src[i], tgt[i], s, t);
    m = fit_yaw_translation(s, t).matrix().cast<float>();
  }
  void estimateRigidTransformation(const Cloud& src, const pcl::Indices& is, const Cloud& tgt,
                                   Matrix4& m) const override {
    std::vector<Vec3> s, t;
    for (std::size_t i = 0; i < std::min(is.size(), tgt.size()); ++i) add(src[is[i]], tgt[i], s, t);
    m = fit_yaw_translation(s, t).matrix().cast<float>();
  }
  void estimateRigidTransformation(const Cloud& src, const pcl::Indices& is, const Cloud& tgt,
                                   const pcl::Indices& it, Matrix4& m) const override {
    std::vector<Vec3> s, t;
    for (std::size_t i = 0; i < std::min(is.size(), it.size()); ++i)
      add(src[is[i]], tgt[it[i]], s, t);
    m = fit_yaw_translation(s, t).matrix().cast<float>();
  }
  void estimateRigidTransformation(const Cloud& src, const Cloud& tgt,
                                   const pcl::Correspondences& c, Matrix4& m) const override {
    m = point_to_plane_step(src, tgt, c).matrix().cast<float>();
  }

 private:
  static void add(const pcl::PointXYZ& a, const pcl::PointXYZ& b, std::vector<Vec3>& s,
                  std::vector<Vec3>& t) {
    s.emplace_back(a.x, a.y, a.z);
    t.emplace_back(b.x, b.y, b.z);
  }
  Pose point_to_plane_step(const Cloud& src, const Cloud& tgt,
                           const pcl::Correspondences& pairs) const {
    if (pairs.size() < 6) return Pose::Identity();
    Vec3 c = Vec3::Zero();
    for (const pcl::Correspondence& k : pairs) c += pt(src[k.index_query]);
    c /= static_cast<double>(pairs.size());
    // Unknowns: small rotations about x, y, z (about c) and the translation; 4 DoF fixes x, y.
    Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    for (const pcl::Correspondence& k : pairs) {
      const Vec3 p = pt(src[k.index_query]), q = pt(tgt[k.index_match]);
      const Vec3& n = normals_[k.index_match];
      Eigen::Matrix<double, 6, 1> jac;
      jac << (p - c).cross(n), n;
      if (!full_) jac(0) = jac(1) = 0.0;
      const double r = n.dot(p - q);
      h += jac * jac.transpose();
      g += jac * r;
    }
    // A direction the surfaces do not constrain (a lone plane) stays put: a light damping.
    h += Eigen::Matrix<double, 6, 6>::Identity() * (1e-9 + 1e-6 * h.trace());
    const Eigen::Matrix<double, 6, 1> x = -h.ldlt().solve(g);
    const Vec3 w = x.head<3>();
    Pose step = Pose::Identity();
    if (w.norm() > 0) step.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).matrix();
    step.translation() = c - step.linear() * c + x.tail<3>();
    return step;
  }
  static Vec3 pt(const pcl::PointXYZ& a) { return Vec3(a.x, a.y, a.z); }
  const LazyNormals& normals_;
  bool full_ = false;
};

// At most max_points of `points`, evenly spaced in input order (all when max_points is 0).
std::vector<Vec3f> every_nth(const std::vector<Vec3f>& points, std::size_t max_points) {
  if (max_points == 0 || points.size() <= max_points) return points;
  std::vector<Vec3f> thinned;
  thinned.reserve(max_points);
  const double step = static_cast<double>(points.size()) / static_cast<double>(max_points);
  for (std::size_t i = 0; i < max_points; ++i)
    thinned.push_back(points[static_cast<std::size_t>(i * step)]);
  return thinned;
}

Cloud::Ptr to_pcl(const std::vector<Vec3f>& points) {
  auto cloud = std::make_shared<Cloud>();
  cloud->reserve(points.size());
  for (const Vec3f& p : points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return cloud;
}

// Share of `query` points (moved by `target_from_query`) within `inlier_m` of `tree`'s cloud; the
// RMS of their distances; and, when `pairs` is given, the inlier pairs (query moved, target).
double inlier_share(const pcl::KdTreeFLANN<pcl::PointXYZ>& tree, const Cloud& query,
                    const Pose& target_from_query, double inlier_m, double* rms_m,
                    std::vector<std::pair<Vec3, int>>* pairs) {
  if (query.empty()) return 0.0;
  pcl::Indices index(1);
  std::vector<float> d2(1);
  std::size_t inliers = 0;
  double sum2 = 0.0;
  for (const pcl::PointXYZ& q : query) {
    const Vec3 p = target_from_query * Vec3(q.x, q.y, q.z);
    const pcl::PointXYZ moved(static_cast<float>(p.x()), static_cast<float>(p.y()),
                              static_cast<float>(p.z()));
    if (tree.nearestKSearch(moved, 1, index, d2) < 1 || d2[0] > inlier_m * inlier_m) continue;
    ++inliers;
    sum2 += d2[0];
    if (pairs) pairs->emplace_back(p, index[0]);
  }
  if (rms_m) *rms_m = inliers ? std::sqrt(sum2 / inliers) : 0.0;
  return static_cast<double>(inliers) / query.size();
}

// The uncertainty of the alignment from its inlier pairs: point-to-plane residuals r = n·(p − q)
// with the target normal n (PCA of 10 neighbours), unknowns (yaw about the pairs' centroid, t),
// covariance = rms² · H⁻¹. Correlated neighbouring residuals make it a lower bound.
void uncertainty(const Cloud& target, const LazyNormals& normals,
                 const std::vector<std::pair<Vec3, int>>& pairs, DenseFit& fit) {
  if (pairs.size() < 10) {
    fit.sigma_translation_m = fit.sigma_yaw_deg = std::numeric_limits<double>::infinity();
    return;
  }
  Vec3 centre = Vec3::Zero();
  for (const auto& pr : pairs) centre += pr.first;
  centre /= static_cast<double>(pairs.size());
  Eigen::Matrix4d h = Eigen::Matrix4d::Zero();
  double sum2 = 0.0;
  for (const auto& [p, j] : pairs) {
    const Vec3& n = normals[j];
    const Vec3 q(target[j].x, target[j].y, target[j].z);
    const Vec3 arm = p - centre;
    const Eigen::Vector4d jac(n.dot(Vec3(-arm.y(), arm.x(), 0.0)), n.x(), n.y(), n.z());
    h += jac * jac.transpose();
    const double r = n.dot(p - q);
    sum2 += r * r;
  }
  const double sigma2 = sum2 / std::max(1.0, static_cast<double>(pairs.size()) - 4.0);
  const Eigen::FullPivLU<Eigen::Matrix4d> lu(h);
  if (!lu.isInvertible()) {
    fit.sigma_translation_m = fit.sigma_yaw_deg = std::numeric_limits<double>::infinity();
    return;
  }
  const Eigen::Matrix4d cov = sigma2 * lu.inverse();
  fit.sigma_yaw_deg = std::sqrt(std::max(0.0, cov(0, 0))) * 180.0 / M_PI;
  const Eigen::Matrix3d ct = cov.block<3, 3>(1, 1);
  fit.sigma_translation_m =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(ct).eigenvalues()(2)));
}

}  // namespace

Pose fit_yaw_translation(const std::vector<Vec3>& source, const std::vector<Vec3>& target) {
  const std::size_t n = std::min(source.size(), target.size());
  if (n == 0) return Pose::Identity();
  Vec3 cs = Vec3::Zero(), ct = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    cs += source[i];
    ct += target[i];
  }
  cs /= static_cast<double>(n);
  ct /= static_cast<double>(n);
  // The yaw that best turns the source's horizontal offsets onto the target's (2D Procrustes).
  double sin_sum = 0.0, cos_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = source[i] - cs, b = target[i] - ct;
    sin_sum += a.x() * b.y() - a.y() * b.x();
    cos_sum += a.x() * b.x() + a.y() * b.y();
  }
  const double yaw = (sin_sum == 0.0 && cos_sum == 0.0) ? 0.0 : std::atan2(sin_sum, cos_sum);
  const Pose r = yaw_pose(yaw, Vec3::Zero());
  return yaw_pose(yaw, ct - r.linear() * cs);
}

std::vector<Vec3f> thin_cloud(const std::vector<Vec3f>& points, double voxel_m,
                              std::size_t max_points) {
  geometry::VoxelHashTable<std::uint8_t> seen(points.size() / 8 + 16);
  std::vector<Vec3f> kept;
  const float inv = static_cast<float>(1.0 / voxel_m);
  Eigen::Vector3i ijk;
  Eigen::Vector3f offset;
  for (const Vec3f& p : points) {
    if (!geometry::voxel_coords(p, inv, ijk, offset)) continue;
    std::uint8_t& flag = seen[geometry::pack_voxel(ijk.x(), ijk.y(), ijk.z())];
    if (!flag) kept.push_back(p);
    flag = 1;
  }
  return every_nth(kept, max_points);
}

namespace {

// align_dense with `source` the cloud moved: ICP on at most icp_max_points of it; the fitness's
// backward share looks its target points up in the whole of it (a thinned one would miss them).
DenseFit align_oriented(const std::vector<Vec3f>& target_points,
                        const std::vector<Vec3f>& source_points, const Pose& guess,
                        const RegistrationOptions& options, bool refine) {
  DenseFit fit;
  fit.target_from_source = guess;
  const Cloud::Ptr target = to_pcl(target_points);
  const Cloud::Ptr whole_source = to_pcl(source_points);
  const Cloud::Ptr source =
      to_pcl(thin_cloud(source_points, options.icp_voxel_m, options.icp_max_points));
  fit.source_points = source->size();
  if (target->size() < 10 || source->size() < 10) return fit;
  pcl::KdTreeFLANN<pcl::PointXYZ> target_tree, source_tree;
  target_tree.setInputCloud(target);
  source_tree.setInputCloud(whole_source);
  const LazyNormals normals(target_tree, *target);
  if (refine) {
    // ICP in three rounds of shrinking correspondence distance: a coarse guess some 10 cm off
    // first gets its pairs, the last round pairs only points on the same surface.
    pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
    const auto estimation = std::make_shared<YawTranslationEstimation>(normals);
    icp.setTransformationEstimation(estimation);
    icp.setInputTarget(target);
    icp.setInputSource(source);
    icp.setMaximumIterations(options.icp_max_iterations);
    icp.setTransformationEpsilon(1e-10);
    icp.setEuclideanFitnessEpsilon(1e-10);
    const double c0 = options.icp_max_correspondence_m, c2 = options.icp_final_correspondence_m;
    Eigen::Matrix4f current = guess.matrix().cast<float>();
    for (const double c : {c0, std::sqrt(c0 * c2), c2, -c2}) {
      if (c < 0 && !options.refine_tilt) break;
      estimation->set_full_rotation(c < 0);  // the last round, optional: 6 DoF
      icp.setMaxCorrespondenceDistance(std::abs(c));
      Cloud aligned;
      icp.align(aligned, current);
      current = icp.getFinalTransformation();
    }
    // Re-orthonormalise (float accumulation); a yaw + translation stays one.
    const Eigen::Matrix4d m = current.cast<double>();
    const Eigen::Matrix3d r = m.block<3, 3>(0, 0);
    if (options.refine_tilt) {
      fit.target_from_source.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
      fit.target_from_source.translation() = m.block<3, 1>(0, 3);
    } else {
      fit.target_from_source = yaw_pose(std::atan2(r(1, 0), r(0, 0)), m.block<3, 1>(0, 3));
    }
  }
  std::vector<std::pair<Vec3, int>> pairs;
  const double forward = inlier_share(target_tree, *source, fit.target_from_source,
                                      options.inlier_m, &fit.rms_m, &pairs);
  // The other direction on as many target points as the ICP source has (evenly thinned).
  const Cloud::Ptr sampled = to_pcl(every_nth(target_points, source->size()));
  const double backward = inlier_share(source_tree, *sampled, fit.target_from_source.inverse(),
                                       options.inlier_m, nullptr, nullptr);
  fit.fitness = std::max(forward, backward);
  fit.fitness_both = std::min(forward, backward);
  uncertainty(*target, normals, pairs, fit);
  return fit;
}

}  // namespace

DenseFit align_dense(const std::vector<Vec3f>& target, const std::vector<Vec3f>& source,
                     const Pose& guess, const RegistrationOptions& options, bool refine) {
  if (!refine || source.size() <= 1.5 * target.size())
    return align_oriented(target, source, guess, options, refine);
  DenseFit fit = align_oriented(source, target, guess.inverse(), options, refine);
  fit.target_from_source = fit.target_from_source.inverse();
  return fit;
}

namespace {

// FLANN's nearest-neighbour result for "the nearest point within a radius": the search prunes
// every branch beyond the radius from the start, so a point far from the map (as under a wrong
// placement) ends quickly where an unbounded nearest search walks much of the tree.
class NearestWithin : public flann::ResultSet<float> {
 public:
  explicit NearestWithin(float radius2) : best_(radius2) {}
  bool full() const override { return true; }
  void addPoint(float dist2, std::size_t) override {
    if (dist2 <= best_) best_ = dist2, found_ = true;
  }
  float worstDist() const override { return best_; }
  bool found() const { return found_; }

 private:
  float best_;
  bool found_ = false;
};

}  // namespace

std::vector<double> overlap_shares(const std::vector<Vec3f>& target_points,
                                   const std::vector<Vec3f>& source_points,
                                   const std::vector<Pose>& guesses, double inlier_m) {
  std::vector<double> shares(guesses.size(), 0.0);
  if (target_points.size() < 10 || source_points.empty()) return shares;
  const flann::Matrix<float> data(const_cast<float*>(target_points.front().data()),
                                  target_points.size(), 3, sizeof(Vec3f));
  flann::KDTreeSingleIndex<flann::L2_Simple<float>> tree(data, flann::KDTreeSingleIndexParams(15));
  tree.buildIndex();
  const flann::SearchParams params;
  const float radius2 = static_cast<float>(inlier_m * inlier_m);
  for (std::size_t g = 0; g < guesses.size(); ++g) {
    const Eigen::Matrix3f r = guesses[g].linear().cast<float>();
    const Vec3f t = guesses[g].translation().cast<float>();
    std::size_t inliers = 0;
    for (const Vec3f& q : source_points) {
      const Vec3f moved = r * q + t;
      NearestWithin nearest(radius2);
      tree.findNeighbors(nearest, moved.data(), params);
      inliers += nearest.found();
    }
    shares[g] = static_cast<double>(inliers) / source_points.size();
  }
  return shares;
}

}  // namespace objmap::change::detail
