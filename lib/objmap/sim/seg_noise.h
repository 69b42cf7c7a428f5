#pragma once
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "objmap/segmentation/types.h"
#include "objmap/sim/random.h"
#include "objmap/sim/scene.h"

// Instance segmentation from the rendered label image: the exact one (the ground truth) and a noisy
// one that looks like a detector + tracker (Mask R-CNN / YOLACT with a tracker) output.
namespace objmap::sim {

struct ClassConfusion {
  std::string from;    // true class
  std::string to;      // reported class
  double probability;  // per instance and frame
};

struct SegNoiseOptions {
  // Instances with fewer visible pixels are not reported (neither in the exact nor the noisy
  // output).
  int min_area_px = 50;
  // Each reported mask is eroded or dilated by a radius drawn uniformly from [-boundary_px,
  // boundary_px] (elliptic kernel); 0 = exact boundaries.
  int boundary_px = 2;
  double miss_prob = 0.08;  // a visible object is not detected in a frame
  double false_positives_per_frame =
      0.05;  // mean number of spurious detections per frame (Poisson)
  // Class confusion, as the paper reports for its detector.
  std::vector<ClassConfusion> confusions{{"teddy bear", "person", 0.15}, {"mouse", "cup", 0.15}};
  double id_switch_prob = 0.01;  // a track gets a new ID (per instance and frame)
  double id_reuse_prob = 0.3;    // share of new IDs that re-use an ID another track dropped earlier
  double score_min = 0.55;       // scores of true detections are uniform in [score_min, score_max]
  double score_max = 0.99;
  // Mask bleed, as real instance masks have (YCB-Video's labels overlap the silhouette by 1-4 px):
  // each reported mask also covers bleed_region() of its exact mask, the pixels within bleed_px
  // that lie behind the object, never an occluder in front. Where the background is far (an object
  // at a table's edge, the floor behind) they back-project far behind the object. Deterministic (no
  // random draws); needs the frames' exact depth. 0 = off.
  int bleed_px = 0;
  // A tracker loses an object that has been out of view (not in the exact segmentation) for more
  // than this many frames: seen again, it gets a new track ID, as on a walk-through's revisit.
  // 0 = never (the object keeps its ID).
  int new_track_after_frames = 0;
  // Packed objects: two reported instances of one class whose masks touch (within touch_px) are
  // given as one mask, in this share of the frames in which they touch (a detector's one mask over
  // chairs packed along a table); the tracker gives it the track ID of the larger. Chains join
  // (three chairs in a row). Drawn from a stream of its own: 0 leaves every other draw as it was.
  double merge_touching_prob = 0.0;
  int touch_px = 2;

  void check() const;             // throws InputError naming the bad field
  static SegNoiseOptions none();  // no error at all: the noisy output equals the exact one
};

// The object ids present in a label image with at least `min_area_px` pixels, and their masks.
// Instances are sorted by object id; class from the scene, score 1, track_id = object id.
segmentation::FrameSegmentation exact_segmentation(const cv::Mat& labels, const Scene& scene,
                                                   double timestamp, int min_area_px);

// Stateful across frames (track IDs): call apply() on the frames in time order.
class SegmentationNoise {
 public:
  SegmentationNoise(const SegNoiseOptions& options, std::uint64_t seed);
  // The noisy segmentation of one frame, from its exact segmentation. `depth_exact_m` is the
  // frame's rendered exact depth (CV_32FC1, width x height, SynthFrame::depth_exact_m), needed
  // only for the mask bleed: with options.bleed_px > 0 an empty or mis-sized one throws InputError.
  segmentation::FrameSegmentation apply(const segmentation::FrameSegmentation& exact, int width,
                                        int height, const cv::Mat& depth_exact_m = cv::Mat());

  // Counts of what was done so far (for tests and the summary).
  struct Stats {
    int true_instances = 0;  // exact instances seen
    int missed = 0;
    int confused = 0;
    int false_positives = 0;
    int id_switches = 0;
    int id_reuses = 0;
    int revisit_ids = 0;         // new IDs given to objects seen again after new_track_after_frames
    long long bleed_pixels = 0;  // pixels added to reported masks by the bleed
    int merged = 0;              // instances given as part of another's mask (merge_touching_prob)
  };
  const Stats& stats() const { return stats_; }

 private:
  void add_false_positives(int width, int height, segmentation::FrameSegmentation* out);
  // merge_touching_prob: joins touching instances of one class of `out` (its true instances).
  void merge_touching(segmentation::FrameSegmentation* out);

  SegNoiseOptions options_;
  Rng rng_;
  Rng merge_rng_;                       // merge_touching_prob's draws, apart from the others
  std::map<int, int> track_of_object_;  // object id -> current track id
  std::map<int, int> last_seen_frame_;  // object id -> the last frame it was in view
  int frame_ = 0;                       // frames applied so far
  std::vector<int> dropped_ids_;        // IDs given up by a switch, candidates for re-use
  int next_track_id_ = 1;
  Stats stats_;
};

// Conversions between a 0/1 mask and a CV_8UC1 image.
cv::Mat to_mat(const segmentation::Mask& mask);
segmentation::Mask to_mask(const cv::Mat& binary);
// The pixels an exact mask (CV_8UC1, non-zero = object) bleeds onto: within bleed_px of it (the
// elliptic kernel of boundary_px), not in it, and behind the object: their exact depth is larger
// than that of every mask pixel within bleed_px, or 0 (nothing hit: as far as it gets). So the
// table, floor, wall or a farther object behind the silhouette, never an occluder in front.
// CV_8UC1, 1 on those pixels; all 0 for bleed_px = 0 or an empty mask.
cv::Mat bleed_region(const cv::Mat& exact_mask, const cv::Mat& depth_exact_m, int bleed_px);

// Tight box of the non-zero pixels (COCO x, y, w, h); all zero for an empty mask.
segmentation::Box mask_box(const segmentation::Mask& mask);

}  // namespace objmap::sim
