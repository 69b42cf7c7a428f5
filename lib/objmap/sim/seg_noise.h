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
  // The noisy segmentation of one frame, from its exact segmentation.
  segmentation::FrameSegmentation apply(const segmentation::FrameSegmentation& exact, int width,
                                        int height);

  // Counts of what was done so far (for tests and the summary).
  struct Stats {
    int true_instances = 0;  // exact instances seen
    int missed = 0;
    int confused = 0;
    int false_positives = 0;
    int id_switches = 0;
    int id_reuses = 0;
  };
  const Stats& stats() const { return stats_; }

 private:
  SegNoiseOptions options_;
  Rng rng_;
  std::map<int, int> track_of_object_;  // object id -> current track id
  std::vector<int> dropped_ids_;        // IDs given up by a switch, candidates for re-use
  int next_track_id_ = 1;
  Stats stats_;
};

// Conversions between a 0/1 mask and a CV_8UC1 image.
cv::Mat to_mat(const segmentation::Mask& mask);
segmentation::Mask to_mask(const cv::Mat& binary);
// Tight box of the non-zero pixels (COCO x, y, w, h); all zero for an empty mask.
segmentation::Box mask_box(const segmentation::Mask& mask);

}  // namespace objmap::sim
