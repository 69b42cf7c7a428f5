#pragma once
#include "objmap/core/types.h"

// Boxes and centroids of point sets (an object's position and extent in objects.json).
namespace objmap::geometry {

// Mean of the points (0 for an empty cloud), accumulated in double.
Vec3 centroid(const PointCloud& cloud);

// Smallest axis-aligned box holding every point (zero box for an empty cloud).
Aabb compute_aabb(const PointCloud& cloud);

// Oriented box from PCA: axes = eigenvectors of the points' covariance (largest variance first,
// right-handed, each axis signed so that its largest component is positive, for a deterministic
// result), extent = the points' min/max along each axis, centre = the middle of that range.
Obb compute_obb(const PointCloud& cloud);

// Oriented box standing on the up axis (unit `up`): its third axis is `up`, its first the largest
// horizontal variance (PCA of the points projected on the plane normal to `up`, signed so that its
// largest component is positive), its second `up` × first. The box of an object as it stands:
// height along up, turned only about up.
Obb compute_upright_obb(const PointCloud& cloud, const Vec3& up);

// Centre of the box spanned by the q- and (1 − q)-quantiles of the points along each axis of the
// frame `frame_from_world` (a rotation; identity: the world axes), in world coordinates (0 when
// empty).
Vec3 percentile_box_centre(const PointCloud& cloud, double q,
                           const Eigen::Matrix3d& frame_from_world = Eigen::Matrix3d::Identity());

// The surface an object rests on, in its cloud: a mask that bleeds past the object's outline onto
// the table or floor it stands on (real masks overlap by a few pixels; behind the object they land
// on the table, at grazing angles centimetres away) brings a strip of that surface, consistently,
// view after view, that the voxel support and eq 18 keep. The support is a horizontal plane of the
// map (scene::Surface) near the object's lowest height and larger than the object's footprint; the
// strip is the object's points within `band_m` of the plane's height that lie outside the
// footprint of its points above that layer (cells of `cell_m`, widened by one cell). The object's
// own lowest parts (a chair's feet, a box's bottom edge) lie under or beside points of the object
// above them and stay; a flat part of the object that is not on such a plane (a chair's seat seen
// over a table) is no support.
struct SupportPlane {
  double height_m = 0.0;  // along up (the third axis of gravity_from_world)
  double area_m2 = 0.0;
};

struct SupportStripOptions {
  double band_m = 0.02;         // the strip: points within this of the plane's height
  double reach_m = 0.03;        // the plane: within this of the object's 1st-percentile height
  double area_factor = 2.0;     // ... and at least this times the object's footprint area
  double cell_m = 0.02;         // footprint grid cell (widened by one cell each way)
  double min_body_share = 0.5;  // no strip unless the points above the layer are this share
  // ... and unless the strip is at least this share of the points: a smaller one is left to the
  // position's 1–99 % box, which trims 1 % at each end (an object's own corner under a part of it
  // that was not seen, such as a book under another, is such a handful of points).
  double min_strip_share = 0.02;
  std::size_t min_points = 20;  // smaller clouds: no strip
  void check() const;           // throws InputError naming the bad field
};

// Marks (true) the points of `cloud` that are the strip of its support (SupportStripOptions) among
// `planes`, in the frame `gravity_from_world` (a rotation whose third axis is up). All false when
// there is none.
std::vector<bool> support_strip(const PointCloud& cloud, const Eigen::Matrix3d& gravity_from_world,
                                const std::vector<SupportPlane>& planes,
                                const SupportStripOptions& options = {});

// The points of `cloud` (with their colours) whose `drop` entry is false.
PointCloud without(const PointCloud& cloud, const std::vector<bool>& drop);

}  // namespace objmap::geometry
