#include "objmap/sim/seg_noise.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "objmap/core/error.h"
#include "objmap/sim/text.h"

namespace objmap::sim {

namespace seg = objmap::segmentation;

namespace {
bool probability(double p) { return std::isfinite(p) && p >= 0.0 && p <= 1.0; }

// Classes a spurious detection may get.
const char* const kFalsePositiveClasses[] = {"person", "chair",        "cup",        "book",
                                             "bottle", "potted plant", "cell phone", "laptop"};

// A reported mask: the exact one eroded (radius < 0) or dilated by |radius|, then grown by its
// bleed region (bleed_px > 0), which reaches out from the exact silhouette whatever the boundary
// noise did. Empty when the erosion left nothing; adds the bleed's new pixels to *bleed_pixels.
cv::Mat noisy_mask(const cv::Mat& exact, int radius, int bleed_px, const cv::Mat& depth_exact_m,
                   long long* bleed_pixels) {
  // A copy when the bleed follows: it is or-ed in place, and `exact` is read after the noise.
  cv::Mat mask = bleed_px > 0 ? exact.clone() : exact;
  if (radius != 0) {
    const int r = std::abs(radius);
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1});
    if (radius > 0)
      cv::dilate(mask, mask, kernel);
    else
      cv::erode(mask, mask, kernel);
  }
  if (cv::countNonZero(mask) == 0) return cv::Mat();
  if (bleed_px > 0) {
    const cv::Mat bleed = bleed_region(exact, depth_exact_m, bleed_px);
    cv::Mat added;
    cv::bitwise_and(bleed, mask == 0, added);
    *bleed_pixels += cv::countNonZero(added);
    cv::bitwise_or(mask, bleed, mask);
  }
  return mask;
}
}  // namespace

void SegNoiseOptions::check() const {
  require(min_area_px >= 1, "--min-area", "must be >= 1 pixel, got " + std::to_string(min_area_px));
  require(boundary_px >= 0 && boundary_px <= 20, "--mask-boundary",
          "must be in [0, 20] pixels, got " + std::to_string(boundary_px));
  require(probability(miss_prob), "--miss-rate",
          "must be a probability in [0, 1], got " + num(miss_prob));
  require(std::isfinite(false_positives_per_frame) && false_positives_per_frame >= 0.0 &&
              false_positives_per_frame <= 20.0,
          "--false-positives",
          "must be in [0, 20] per frame, got " + num(false_positives_per_frame));
  for (const auto& c : confusions)
    require(probability(c.probability) && !c.from.empty() && !c.to.empty(), "--confusion-rate",
            "'" + c.from + "' -> '" + c.to + "' has probability " + num(c.probability) +
                "; expected two class names and a probability in [0, 1]");
  require(probability(id_switch_prob), "--id-switch-rate",
          "must be a probability in [0, 1], got " + num(id_switch_prob));
  require(probability(id_reuse_prob), "--id-reuse",
          "must be a probability in [0, 1], got " + num(id_reuse_prob));
  require(new_track_after_frames >= 0, "SegNoiseOptions.new_track_after_frames",
          "must be >= 0 frames, got " + std::to_string(new_track_after_frames));
  require(std::isfinite(score_min) && std::isfinite(score_max) && 0.0 <= score_min &&
              score_min <= score_max && score_max <= 1.0,
          "SegNoiseOptions.score_min", "scores must satisfy 0 <= score_min <= score_max <= 1");
  require(probability(merge_touching_prob), "--merge-touching-rate",
          "must be a probability in [0, 1], got " + num(merge_touching_prob));
  require(touch_px >= 0 && touch_px <= 20, "SegNoiseOptions.touch_px",
          "must be in [0, 20] pixels, got " + std::to_string(touch_px));
  require(bleed_px >= 0 && bleed_px <= 20, "--mask-bleed-px",
          "must be in [0, 20] pixels (0 = no bleed), got " + std::to_string(bleed_px));
}

SegNoiseOptions SegNoiseOptions::none() {
  SegNoiseOptions o;
  o.boundary_px = 0;
  o.miss_prob = 0.0;
  o.false_positives_per_frame = 0.0;
  o.confusions.clear();
  o.id_switch_prob = 0.0;
  o.id_reuse_prob = 0.0;
  o.score_min = o.score_max = 1.0;
  return o;
}

cv::Mat to_mat(const seg::Mask& mask) {
  cv::Mat m(mask.height, mask.width, CV_8UC1, cv::Scalar::all(0));
  if (!mask.data.empty()) std::copy(mask.data.begin(), mask.data.end(), m.data);
  return m;
}

seg::Mask to_mask(const cv::Mat& binary) {
  seg::Mask mask;
  mask.width = binary.cols;
  mask.height = binary.rows;
  mask.data.resize(static_cast<std::size_t>(binary.rows) * binary.cols);
  for (int v = 0; v < binary.rows; ++v) {
    const auto* row = binary.ptr<std::uint8_t>(v);
    for (int u = 0; u < binary.cols; ++u)
      mask.data[static_cast<std::size_t>(v) * binary.cols + u] = row[u] ? 1 : 0;
  }
  return mask;
}

seg::Box mask_box(const seg::Mask& mask) {
  if (mask.data.empty()) return {};
  const cv::Mat view(mask.height, mask.width, CV_8UC1, const_cast<std::uint8_t*>(mask.data.data()));
  const cv::Rect r = cv::boundingRect(view);
  if (r.area() == 0) return {};
  return {static_cast<double>(r.x), static_cast<double>(r.y), static_cast<double>(r.width),
          static_cast<double>(r.height)};
}

cv::Mat bleed_region(const cv::Mat& exact_mask, const cv::Mat& depth_exact_m, int bleed_px) {
  require(exact_mask.type() == CV_8UC1 && depth_exact_m.type() == CV_32FC1 &&
              exact_mask.size() == depth_exact_m.size(),
          "bleed_region", "expected a CV_8UC1 mask and a CV_32FC1 depth image of the same size");
  cv::Mat region(exact_mask.size(), CV_8UC1, cv::Scalar::all(0));
  const cv::Rect box = cv::boundingRect(exact_mask);
  if (bleed_px <= 0 || box.area() == 0) return region;
  // Work in the mask's box grown by the kernel's reach.
  const cv::Rect roi = cv::Rect(box.x - bleed_px, box.y - bleed_px, box.width + 2 * bleed_px,
                                box.height + 2 * bleed_px) &
                       cv::Rect(0, 0, exact_mask.cols, exact_mask.rows);
  const cv::Mat mask = exact_mask(roi);
  const cv::Mat depth_m = depth_exact_m(roi);
  const cv::Mat kernel =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * bleed_px + 1, 2 * bleed_px + 1});
  // Within reach of the mask, and the farthest object depth within reach of each pixel.
  cv::Mat reach, object_depth_m(mask.size(), CV_32FC1, cv::Scalar::all(0)), farthest_object_m;
  cv::dilate(mask, reach, kernel);
  depth_m.copyTo(object_depth_m, mask);
  cv::dilate(object_depth_m, farthest_object_m, kernel);
  cv::Mat out = region(roi);
  for (int v = 0; v < mask.rows; ++v) {
    const auto* in_mask = mask.ptr<std::uint8_t>(v);
    const auto* in_reach = reach.ptr<std::uint8_t>(v);
    const auto* d = depth_m.ptr<float>(v);
    const auto* object_d = farthest_object_m.ptr<float>(v);
    auto* o = out.ptr<std::uint8_t>(v);
    for (int u = 0; u < mask.cols; ++u)
      o[u] = in_reach[u] && !in_mask[u] && (d[u] == 0.0f || d[u] > object_d[u]) ? 1 : 0;
  }
  return region;
}

seg::FrameSegmentation exact_segmentation(const cv::Mat& labels, const Scene& scene,
                                          double timestamp, int min_area_px) {
  require(labels.type() == CV_16UC1, "exact_segmentation", "expected a CV_16UC1 label image");
  seg::FrameSegmentation frame;
  frame.timestamp = timestamp;
  frame.source = "synthetic";
  struct Extent {
    int pixels = 0, u0 = 1 << 30, v0 = 1 << 30, u1 = -1, v1 = -1;
  };
  std::map<int, Extent> extents;
  for (int v = 0; v < labels.rows; ++v) {
    const auto* row = labels.ptr<std::uint16_t>(v);
    for (int u = 0; u < labels.cols; ++u) {
      if (!row[u]) continue;
      Extent& e = extents[row[u]];
      ++e.pixels;
      e.u0 = std::min(e.u0, u);
      e.u1 = std::max(e.u1, u);
      e.v0 = std::min(e.v0, v);
      e.v1 = std::max(e.v1, v);
    }
  }
  for (const auto& [id, e] : extents) {
    if (e.pixels < min_area_px) continue;
    const SceneObject* object = scene.find(id);
    if (!object) continue;
    seg::Instance instance;
    instance.class_name = object->class_name;
    instance.score = 1.0;
    instance.track_id = id;
    seg::Mask mask;
    mask.width = labels.cols;
    mask.height = labels.rows;
    mask.data.assign(static_cast<std::size_t>(labels.rows) * labels.cols, 0);
    for (int v = e.v0; v <= e.v1; ++v) {
      const auto* row = labels.ptr<std::uint16_t>(v);
      for (int u = e.u0; u <= e.u1; ++u)
        if (row[u] == id) mask.data[static_cast<std::size_t>(v) * labels.cols + u] = 1;
    }
    instance.mask = std::move(mask);
    instance.bbox = {static_cast<double>(e.u0), static_cast<double>(e.v0),
                     static_cast<double>(e.u1 - e.u0 + 1), static_cast<double>(e.v1 - e.v0 + 1)};
    frame.instances.push_back(std::move(instance));
  }
  return frame;
}

SegmentationNoise::SegmentationNoise(const SegNoiseOptions& options, std::uint64_t seed)
    : options_(options),
      rng_(derive_seed(seed, 0, 0x5E6)),
      merge_rng_(derive_seed(seed, 0, 0x3E6E)) {
  options_.check();
}

// False positives: an ellipse somewhere, a plausible class, a low score, a fresh ID each time.
void SegmentationNoise::add_false_positives(int width, int height, seg::FrameSegmentation* out) {
  const SegNoiseOptions& o = options_;
  const int spurious =
      o.false_positives_per_frame > 0.0 ? rng_.poisson(o.false_positives_per_frame) : 0;
  for (int k = 0; k < spurious; ++k) {
    const cv::Point centre(rng_.uniform_int(width), rng_.uniform_int(height));
    const cv::Size axes(5 + rng_.uniform_int(std::max(1, width / 12)),
                        5 + rng_.uniform_int(std::max(1, height / 12)));
    const double angle = rng_.uniform(0.0, 180.0);
    const int cls = rng_.uniform_int(static_cast<int>(std::size(kFalsePositiveClasses)));
    const double score = rng_.uniform(0.3, 0.6);
    cv::Mat mask(height, width, CV_8UC1, cv::Scalar::all(0));
    cv::ellipse(mask, centre, axes, angle, 0.0, 360.0, cv::Scalar(1), cv::FILLED);
    seg::Instance instance;
    instance.class_name = kFalsePositiveClasses[cls];
    instance.score = score;
    instance.track_id = next_track_id_++;
    if (cv::countNonZero(mask) == 0) continue;
    instance.mask = to_mask(mask);
    instance.bbox = mask_box(*instance.mask);
    out->instances.push_back(std::move(instance));
    ++stats_.false_positives;
  }
}

seg::FrameSegmentation SegmentationNoise::apply(const seg::FrameSegmentation& exact, int width,
                                                int height, const cv::Mat& depth_exact_m) {
  const SegNoiseOptions& o = options_;
  if (o.bleed_px > 0)
    require(depth_exact_m.type() == CV_32FC1 && depth_exact_m.cols == width &&
                depth_exact_m.rows == height,
            "SegmentationNoise::apply",
            "the mask bleed (bleed_px > 0) needs the frame's exact depth, CV_32FC1 " +
                std::to_string(width) + "x" + std::to_string(height));
  seg::FrameSegmentation out;
  out.timestamp = exact.timestamp;
  out.source = "synthetic";
  for (const auto& truth : exact.instances) {
    ++stats_.true_instances;
    // Same number of draws per instance, whatever the knobs.
    const double miss_draw = rng_.uniform();
    const double confusion_draw = rng_.uniform();
    const double switch_draw = rng_.uniform();
    const double reuse_draw = rng_.uniform();
    const double reuse_pick = rng_.uniform();
    const int radius =
        o.boundary_px > 0 ? rng_.uniform_int(2 * o.boundary_px + 1) - o.boundary_px : 0;
    const double score = rng_.uniform(o.score_min, o.score_max);
    const int object_id = truth.track_id.value_or(0);

    // Track identity: the tracker keeps an ID per object, switching now and then, and gives a
    // new one to an object it lost while out of view.
    auto it = track_of_object_.find(object_id);
    const auto seen = last_seen_frame_.find(object_id);
    const bool lost = o.new_track_after_frames > 0 && seen != last_seen_frame_.end() &&
                      frame_ - seen->second > o.new_track_after_frames;
    last_seen_frame_[object_id] = frame_;
    if (it == track_of_object_.end()) {
      it = track_of_object_.emplace(object_id, next_track_id_++).first;
    } else if (lost) {
      ++stats_.revisit_ids;
      it->second = next_track_id_++;
    } else if (switch_draw < o.id_switch_prob) {
      ++stats_.id_switches;
      const int old_id = it->second;
      // Re-use an ID dropped by another track (never this object's own previous ID).
      std::vector<int> candidates;
      for (int id : dropped_ids_)
        if (id != old_id) candidates.push_back(id);
      bool in_use = false;
      if (reuse_draw < o.id_reuse_prob && !candidates.empty()) {
        const int id = candidates[static_cast<std::size_t>(reuse_pick * candidates.size())];
        for (const auto& [obj, track] : track_of_object_)
          in_use |= (track == id && obj != object_id);
        if (!in_use) {
          it->second = id;
          dropped_ids_.erase(std::find(dropped_ids_.begin(), dropped_ids_.end(), id));
          ++stats_.id_reuses;
        }
      }
      if (it->second == old_id) it->second = next_track_id_++;
      dropped_ids_.push_back(old_id);
    }

    if (miss_draw < o.miss_prob) {
      ++stats_.missed;
      continue;
    }
    seg::Instance instance;
    instance.class_name = truth.class_name;
    for (const auto& c : o.confusions) {
      if (c.from == truth.class_name) {
        if (confusion_draw < c.probability) {
          instance.class_name = c.to;
          ++stats_.confused;
        }
        break;
      }
    }
    instance.score = score;
    instance.track_id = it->second;
    const cv::Mat mask =
        noisy_mask(to_mat(*truth.mask), radius, o.bleed_px, depth_exact_m, &stats_.bleed_pixels);
    if (mask.empty()) {  // eroded away: the detector saw nothing
      ++stats_.missed;
      continue;
    }
    instance.mask = to_mask(mask);
    instance.bbox = mask_box(*instance.mask);
    out.instances.push_back(std::move(instance));
  }

  if (o.merge_touching_prob > 0.0) merge_touching(&out);
  add_false_positives(width, height, &out);
  ++frame_;
  return out;
}

void SegmentationNoise::merge_touching(seg::FrameSegmentation* out) {
  auto& instances = out->instances;
  const int n = static_cast<int>(instances.size());
  if (n < 2) return;
  const int t = options_.touch_px;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, {2 * t + 1, 2 * t + 1});
  std::vector<cv::Mat> masks;
  std::vector<cv::Rect> boxes;
  for (const auto& in : instances) {
    masks.push_back(to_mat(*in.mask));
    boxes.push_back(cv::boundingRect(masks.back()));
  }
  // Union-find over the pairs that touch and draw a merge; one draw per touching pair.
  std::vector<int> root(n);
  for (int i = 0; i < n; ++i) root[i] = i;
  const auto find = [&](int i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      if (instances[i].class_name != instances[j].class_name) continue;
      const cv::Rect grown(boxes[i].x - t, boxes[i].y - t, boxes[i].width + 2 * t,
                           boxes[i].height + 2 * t);
      const cv::Rect common = grown & boxes[j];
      if (common.area() == 0) continue;
      const cv::Rect roi = (grown | boxes[j]) & cv::Rect(0, 0, masks[i].cols, masks[i].rows);
      cv::Mat near_i;
      cv::dilate(masks[i](roi), near_i, kernel);
      if (cv::countNonZero(near_i & masks[j](roi)) == 0) continue;
      if (merge_rng_.uniform() < options_.merge_touching_prob) root[find(j)] = find(i);
    }
  // Each group: one mask (the union), the larger's track ID, the highest score.
  std::vector<seg::Instance> kept;
  for (int i = 0; i < n; ++i) {
    if (find(i) != i) continue;
    int largest = i;
    cv::Mat joined = masks[i].clone();
    double score = instances[i].score;
    for (int j = i + 1; j < n; ++j) {
      if (find(j) != i) continue;
      cv::bitwise_or(joined, masks[j], joined);
      score = std::max(score, instances[j].score);
      if (cv::countNonZero(masks[j]) > cv::countNonZero(masks[largest])) largest = j;
      ++stats_.merged;
    }
    seg::Instance in = instances[largest];
    in.score = score;
    in.mask = to_mask(joined);
    in.bbox = mask_box(*in.mask);
    kept.push_back(std::move(in));
  }
  instances = std::move(kept);
}

}  // namespace objmap::sim
