#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <opencv2/core/mat.hpp>

#include "objmap/core/camera.h"
#include "objmap/segmentation/types.h"

// A mask for an instance that has only a box: the pixels inside the box that lie on the object's
// depth surface, without the background behind the object and without the table/floor it stands on.
//
//   1. valid depths inside the (clipped) box;
//   2. the object's depth: a histogram of the depths, weighted toward the box centre; the NEAREST
//      peak holding a good share of the largest peak wins (the object is in front of what is behind
//      it);
//   3. the supporting surface: a plane fitted (deterministic RANSAC) to the box's bottom rows and
//      the rows just below the box. It is accepted when well supported and when the object of step
//      2 stands on it (its central pixels above the plane, not on it: the object's own face; not
//      behind it: an occluder's face); otherwise its samples are dropped and the next plane is
//      tried. Box pixels on or beyond the accepted plane are set aside (they would bridge object
//      and table) and the object's depth is taken again without them;
//   4. seeds: the central pixels at that depth, the smooth-connected components of them with a
//      good share of the heaviest one's centre weight; region growing (4-connected) across smooth
//      depth (|Δz| below the depth change of a steep surface at that z, plus sensor noise) within
//      a depth band around the mode sized from the box's metric size. Plane pixels whose local
//      normal is off the plane's (the object's lowest centimetre) are taken back while growing;
//   5. occluders: when the region runs on beyond the box on most of its border pixels (an
//      occluder or background cut by the box), the next histogram peak farther away is tried;
//   6. a 3×3 morphological closing; a mask below the minimum area is returned empty.
//
// Cost: O(box area) with buffers reused per thread (no allocation per pixel, a full-image mask per
// call): 0.7–0.9 ms CPU for a 152×133 box, 1–2 ms for the 170×190 YCB boxes, ~1.2 ms for
// fr1's detector boxes (bench_fusion BM_MaskFromBoxReal; docs/fusion.md). Pixel rays use the
// pinhole model (fx, fy, cx, cy); lens distortion is neglected, which only bends the support plane
// slightly near the image border.
namespace objmap::segmentation {

struct BoxMaskOptions {
  // Valid depth range, metres. TUM/Kinect depth is unreliable below ~0.4 m and beyond ~8 m.
  double min_depth_m = 0.1;  // smaller depths are treated as invalid
  double max_depth_m = 8.0;  // larger depths are treated as invalid

  // Depth histogram. 2 cm bins: well above Kinect noise at 1–2 m (~3–7 mm) and small against
  // object-to-background gaps (≥ 10 cm). Peaks are read on a 3-bin sum, so a surface split across
  // two bins still forms one peak.
  double bin_m = 0.02;
  // Centre weighting: a pixel weighs exp(-½((du/(σx·w))² + (dv/(σy·h))²)) with σ = this fraction of
  // the box size; 0.25 gives the box border 14 % of the centre's weight (detection boxes are loose
  // and their borders hold background).
  double center_sigma_fraction = 0.25;
  // A peak counts as the object when it holds at least this share of the largest peak; the nearest
  // such peak wins. 0.3: a thin object (chair) in front of a wall still wins, a few flying pixels
  // at an object border (a small peak in front) do not.
  double near_mode_min_share = 0.3;

  // Seeds: pixels within seed_tolerance_bins · bin_m of the mode depth in the central part of the
  // box (this fraction of its width and height). When the centre has none, the whole box is used.
  double seed_tolerance_bins = 1.5;
  double seed_center_fraction = 0.5;
  // The seed pixels form smooth-connected components; those with at least this share of the
  // centre weight of the heaviest one seed the growing (an object cut in two by a thin occluder
  // keeps both halves; a few pixels of another surface crossing the mode depth do not count).
  double seed_component_min_share = 0.6;

  // Region growing: neighbours p, q join when |z_p − z_q| ≤ step(z_p) = tan(smooth_max_slope_deg) ·
  // z/f + smooth_noise_m_per_m2 · z², f = (fx + fy)/2. The first term is the depth change per pixel
  // of a surface slanted by that angle (its footprint z/f grows with z); steeper "surfaces" are
  // depth edges, including the ramps of mixed pixels that a registered Kinect/Xtion depth image
  // draws between an occluder and what is behind it. The second term is the sensor's depth
  // quantisation (Kinect v1: ~3 mm at 1 m, growing with z²; 5 mm leaves room for noise). E.g. fr3
  // at 1 m: 15.6 mm; at 2 m: 41 mm.
  double smooth_max_slope_deg = 80.0;
  double smooth_noise_m_per_m2 = 0.005;
  int connectivity = 4;  // 4 or 8; 4 leaks less through single diagonal pixels

  // Depth band around the mode: ±clamp(band_size_factor · max(metric width, metric height) of the
  // box at the mode depth, band_min_m, band_max_m). 0.75: a box-shaped object seen from above spans
  // about its diagonal in depth and the mode sits inside that span.
  double band_size_factor = 0.75;
  double band_min_m = 0.05;
  double band_max_m = 1.5;
  // The band's near side is this fraction of its far side: the mode is already the object's near
  // surface, and what is much nearer is usually an occluder standing in front.
  double band_near_fraction = 0.5;

  // Supporting surface (table, floor).
  bool remove_support_plane = true;
  double support_inlier_m = 0.012;        // point-to-plane distance of a plane inlier (1.2 cm)
  double support_bottom_fraction = 0.2;   // bottom rows of the box sampled for the plane
  double support_below_fraction = 0.15;   // rows just below the box sampled, as a fraction of box h
  double support_min_inlier_share = 0.4;  // "well supported": this share of the samples are inliers
  int support_min_inliers = 30;           // ... and at least this many
  int support_max_samples = 400;          // samples are taken on a regular grid up to this count
  int support_ransac_iterations = 60;     // deterministic (fixed seed): same input, same plane
  // Planes tried in turn: a rejected plane (an occluder's or the object's own face in the bottom
  // rows) gives up its samples and the next one is fitted to the rest.
  int support_max_planes = 3;
  // The plane is kept only when the object found without it (the central pixels at the first near
  // mode) stands on it: at least this share of them more than support_inlier_m on the camera's side
  // (a plane fitted to the object's own face has them on it; a flat object such as a keyboard has
  // the table at the same depth in the centre, hence not more) ...
  double support_min_above_share = 0.3;
  // ... and at most this share beyond it (a plane fitted to an occluder's face has the object
  // behind it).
  double support_max_beyond_share = 0.2;
  // Pixels within support_inlier_m of the plane are taken back into the mask (while growing) when
  // their surface normal is more than this angle off the plane's normal: the object's lowest
  // centimetre, not the table. 90 = never.
  double support_reclaim_angle_deg = 45.0;

  // Occluders: a region whose surface runs on beyond the box on more than max_border_leak of its
  // box-border pixels (box sides inside the image; the support plane outside does not count) is an
  // occluder or background cut by the box, not the object the box was drawn around; the next
  // histogram peak farther away is tried, up to depth_candidates in all. When all leak, the
  // nearest is kept. A fitting box ends where the object ends (little leak); a box cut through the
  // object leaks for every candidate and keeps the nearest.
  int depth_candidates = 3;
  double max_border_leak = 0.5;

  // Clean-up: morphological closing with a (2r+1)² square inside the box, restricted to valid depth
  // within the band (fills one-pixel cracks of noisy depth); 0 = none.
  int close_radius_px = 1;

  // Minimum mask: fewer pixels than max(min_pixels, min_box_fraction · box area) → empty mask.
  int min_pixels = 20;
  double min_box_fraction = 0.01;

  void check() const;  // throws objmap::InputError naming the bad field ("BoxMaskOptions.<field>")
};

enum class BoxMaskStatus {
  kOk,            // mask found
  kOutsideImage,  // the box does not overlap the image
  kNoValidDepth,  // no depth inside the box within [min_depth_m, max_depth_m]
  kTooSmall,      // the region grown was below the minimum area
};
const char* to_string(BoxMaskStatus status);

struct BoxMaskResult {
  // Full-image mask (width and height of the depth image, 0/1 per pixel); all zero unless status is
  // kOk. It is left without data (mask.empty()) only when the depth image itself is empty.
  Mask mask;
  double mode_depth_m = 0;  // depth of the object surface chosen (0 when none)
  std::size_t pixels = 0;   // pixels in the mask
  // Bounding rectangle of the mask's pixels (as geometry::mask_bounds(mask), without scanning the
  // whole image); empty unless status is kOk.
  cv::Rect bounds;
  bool support_plane_removed = false;  // a support plane was accepted and its inliers left out
  BoxMaskStatus status = BoxMaskStatus::kOk;
  // Diagnostics.
  int u0 = 0, v0 = 0, u1 = 0, v1 = 0;      // the clipped box, pixels [u0, u1) × [v0, v1)
  std::size_t valid_pixels = 0;            // valid depths inside the clipped box
  std::size_t seed_pixels = 0;             // seeds of the region growing
  std::size_t support_inliers = 0;         // plane inliers among the plane samples (0 = no plane)
  std::size_t support_pixels_removed = 0;  // box pixels set aside as plane inliers
  Eigen::Vector4d support_plane_in_cam = Eigen::Vector4d::Zero();  // n·X + d = 0, |n| = 1, d > 0
  double band_half_width_m = 0;  // far half-width of the band (near: × band_near_fraction)
  double border_leak = 0;        // share of the region's box-border pixels that go on outside
};

// depth: CV_16UC1, metres = value / camera.depth_factor, 0 = no depth. camera: fx, fy, cx, cy for
// the metric reasoning (the depth image's size is authoritative). Throws InputError for a depth
// image of another type or a camera without positive focal lengths/depth factor; an unusable box
// (outside the image, no depth) is not an error: the result is an empty mask with the status saying
// why.
BoxMaskResult mask_from_box(const Box& box, const cv::Mat& depth, const Camera& camera,
                            const BoxMaskOptions& options);

}  // namespace objmap::segmentation
