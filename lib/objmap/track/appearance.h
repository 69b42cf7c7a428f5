#pragma once
#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "objmap/segmentation/types.h"

// The appearance descriptor of an instance, from its own pixels: DeepSORT uses a CNN re-ID
// embedding; objmap uses a normalised colour histogram in HSV (hue x saturation joint histogram and
// a value histogram) over the instance's mask, or over its box when it has no mask. Cosine distance
// between unit descriptors compares them, as DeepSORT's nn_matching does.
namespace objmap::track {

using Descriptor = Eigen::VectorXd;

struct AppearanceOptions {
  int hue_bins = 8;         // joint hue x saturation histogram: hue bins (OpenCV hue 0..179)
  int saturation_bins = 4;  // ... and saturation bins
  int value_bins = 8;       // separate histogram of the value (brightness) channel
  void check() const;       // throws InputError naming the bad field
};

// Unit-length (L2) descriptor of the pixels of `instance` in `bgr` (CV_8UC3). The mask must have
// the image's size; the box is clipped to the image. An instance without any pixel gives a zero
// vector (which is at cosine distance 1 from everything).
Descriptor colour_descriptor(const cv::Mat& bgr, const segmentation::Instance& instance,
                             const AppearanceOptions& options = {});

// 1 - a.b for unit vectors a and b: 0 same, 1 orthogonal (histograms are never further than 1).
double cosine_distance(const Descriptor& a, const Descriptor& b);

}  // namespace objmap::track
