#include "objmap/track/appearance.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "objmap/core/error.h"

namespace objmap::track {

void AppearanceOptions::check() const {
  require(hue_bins >= 1 && hue_bins <= 180, "AppearanceOptions.hue_bins",
          "must be in [1, 180], got " + std::to_string(hue_bins));
  require(saturation_bins >= 1 && saturation_bins <= 256, "AppearanceOptions.saturation_bins",
          "must be in [1, 256], got " + std::to_string(saturation_bins));
  require(value_bins >= 0 && value_bins <= 256, "AppearanceOptions.value_bins",
          "must be in [0, 256], got " + std::to_string(value_bins));
}

Descriptor colour_descriptor(const cv::Mat& bgr, const segmentation::Instance& instance,
                             const AppearanceOptions& options) {
  require(bgr.type() == CV_8UC3, "colour_descriptor", "image is not 8-bit BGR; expected CV_8UC3");
  const int hs = options.hue_bins * options.saturation_bins;
  Descriptor d = Descriptor::Zero(hs + options.value_bins);
  const segmentation::Box& b = instance.bbox;
  const int u0 = std::clamp(static_cast<int>(std::floor(b.x)), 0, bgr.cols);
  const int v0 = std::clamp(static_cast<int>(std::floor(b.y)), 0, bgr.rows);
  const int u1 = std::clamp(static_cast<int>(std::ceil(b.x + b.w)), 0, bgr.cols);
  const int v1 = std::clamp(static_cast<int>(std::ceil(b.y + b.h)), 0, bgr.rows);
  if (u1 <= u0 || v1 <= v0) return d;
  const segmentation::Mask* mask = instance.mask ? &*instance.mask : nullptr;
  if (mask)
    require(mask->width == bgr.cols && mask->height == bgr.rows, "colour_descriptor",
            "mask is " + std::to_string(mask->width) + "x" + std::to_string(mask->height) +
                ", image " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) +
                "; expected the same size");
  cv::Mat hsv;
  cv::cvtColor(bgr(cv::Rect(u0, v0, u1 - u0, v1 - v0)), hsv, cv::COLOR_BGR2HSV);
  for (int v = v0; v < v1; ++v) {
    const cv::Vec3b* row = hsv.ptr<cv::Vec3b>(v - v0);
    for (int u = u0; u < u1; ++u) {
      if (mask && !mask->at(u, v)) continue;
      const cv::Vec3b& p = row[u - u0];
      const int h = std::min(p[0] * options.hue_bins / 180, options.hue_bins - 1);
      const int s = p[1] * options.saturation_bins / 256;
      d(h * options.saturation_bins + s) += 1.0;
      if (options.value_bins > 0) d(hs + p[2] * options.value_bins / 256) += 1.0;
    }
  }
  const double norm = d.norm();
  if (norm > 0) d /= norm;
  return d;
}

double cosine_distance(const Descriptor& a, const Descriptor& b) {
  if (a.size() != b.size()) return 1.0;
  return 1.0 - a.dot(b);
}

}  // namespace objmap::track
