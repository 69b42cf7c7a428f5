#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/core/types.h"
#include "objmap/fusion/voxel_map.h"

// Noise voxels of the dense map. Depth noise scatters a surface's points along the viewing rays
// over a slab a few σ(z) thick (σ grows with the square of the depth: ±1 cm at 1.5 m, several cm at
// 3–4 m for a Kinect), and every new view fills more of that slab: a map of the same surfaces grows
// with the frames (a synthetic table circled for 300 and 1200 frames: 3.0 M and 5.1 M voxels, where
// the exact depth gives 1.0 M and 1.2 M). The later views contradict such a voxel: they measure the
// surface in front of it or behind it, not at it.
//
// The test is a truncated signed distance, as in a TSDF (KinectFusion), with a median: each voxel
// is judged once, every_keyframes to 2 × every_keyframes keyframes after it was opened, against the
// depth images of the last every_keyframes keyframes, latest first, until max_views of them saw it
// (the cost of a verdict is bounded). Its mean point is projected into each of them;
// where the pixel (the nearest of every second pixel and row) has a depth, s = measured depth − the
// point's depth (along the optical axis), truncated at +truncation_m (the ray went on through the
// voxel: free space); a view that measured more than truncation_m in front of the point saw
// something else there (occluded) and says nothing. With at least min_views views, the voxel is
// noise when |median s| > tolerance_voxels voxels: the views put the surface elsewhere along the
// ray. A surface seen repeatedly has the median of its measurements at its voxels and is kept; a
// voxel that fewer recent views see is kept.
//
// The peak rule (peak_ratio > 0) judges instead by the map itself, as non-maximum suppression along
// the ray: the noise spreads a surface's points along the rays with a density that peaks at the
// surface, so a voxel is noise when a voxel its ray crosses within ±peak_sigmas σ(z) (the ray from
// the latest recent view that has it in its image, else from the latest view) holds more than
// count / peak_ratio points. The kept slab is as thick as the band where the density is at least
// peak_ratio of its peak (±0.76 σ at 0.75), whatever the number of frames. With rejudge > 0 a
// survivor is judged again 2, 4, 8, ... prunes later (VoxelMap::remember_new_voxels): a voxel that
// passed while its neighbours were young goes once their counts have grown.
namespace objmap::fusion {

struct DensePruneOptions {
  int every_keyframes = 0;    // judge the voxels opened earlier after every n keyframes; 0: never
  int min_views = 3;          // recent views that must see a voxel's point for a verdict
  int max_views = 5;          // the latest views that see it are enough (the cost of a verdict)
  double truncation_m = 0.1;  // s beyond +this counts as +this; below -this: occluded
  double tolerance_voxels = 1.0;  // |median s| allowed, in voxels
  int rejudge = 0;  // a surviving voxel is judged again 2, 4, 8, ... prunes later, this many times
  double peak_ratio = 0.0;   // peak rule: noise when count < ratio x the ray's peak; 0: median rule
  double peak_sigmas = 2.0;  // the ray is searched within ± this many σ(z)
  double sigma_base_m = 0.0012;     // σ(z) = base + quadratic (z − ref)² (Nguyen et al. 2012)
  double sigma_quadratic = 0.0019;  // 1/m
  double sigma_ref_z_m = 0.4;
  void check() const;  // throws InputError naming the bad field
};

// The last keyframes' depth images and poses, to judge the dense map's new voxels against.
class RecentViews {
 public:
  // Keeps up to `capacity` views (the oldest goes first).
  RecentViews(const Camera& camera, std::size_t capacity);
  // A keyframe's raw depth (CV_16UC1, the camera's size and depth factor), kept at half resolution.
  void add(const cv::Mat& depth, const Pose& world_from_cam);
  std::size_t size() const { return views_.size(); }

  // The test above for voxels' mean points (voxel edge voxel_m): noise[i] = 1 when the views
  // contradict points[i], else 0. The views are visited one at a time (each view's depth stays in
  // the cache). Thread-safe (reads only).
  void judge(const std::vector<Vec3>& points, double voxel_m, const DensePruneOptions& options,
             std::vector<std::uint8_t>& noise) const;
  // The peak rule for voxels' mean points and point counts in `map`: noise[i] = 1 when a voxel
  // within ±peak_sigmas σ(z) along the ray from the latest view that has the point in its image
  // (else the latest view) holds more than counts[i] / peak_ratio points. Reads only.
  void judge_peaks(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& counts,
                   const VoxelMap& map, const DensePruneOptions& options,
                   std::vector<std::uint8_t>& noise) const;
  // judge() of one point.
  bool contradicted(const Vec3& point_in_world, double voxel_m,
                    const DensePruneOptions& options) const;

 private:
  static constexpr int kStep = 2;         // the depth is kept at every kStep-th pixel and row
  static constexpr int kMaxSamples = 64;  // samples along a ray in the peak rule (±16 voxels)
  struct PeakRay;                         // the peak rule's search for one voxel
  PeakRay peak_ray(const Vec3& point, std::uint32_t count, double voxel_m,
                   const DensePruneOptions& options) const;
  struct View {
    cv::Mat depth;  // every kStep-th pixel of every kStep-th row
    Eigen::Matrix3d cam_from_world_r;
    Vec3 cam_from_world_t;
    Vec3 centre_in_world;
  };
  Camera camera_;
  bool distorted_ = false;
  std::size_t capacity_;
  std::deque<View> views_;
};

}  // namespace objmap::fusion
