#include "objmap/segmentation/instance_masks.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/geometry/backproject.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::segmentation {

namespace {

std::string size_text(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Non-zero pixels of `mask` inside `bounds`.
std::size_t mask_pixels(const Mask& mask, const cv::Rect& bounds) {
  std::size_t n = 0;
  for (int v = bounds.y; v < bounds.y + bounds.height; ++v) {
    const std::uint8_t* row = mask.data.data() + static_cast<std::size_t>(v) * mask.width;
    for (int u = bounds.x; u < bounds.x + bounds.width; ++u) n += row[u] != 0;
  }
  return n;
}

// Pixels set in both masks (of one size).
std::size_t shared_pixels(const InstanceMask& a, const InstanceMask& b) {
  const cv::Rect both = a.bounds & b.bounds;
  const Mask& ma = a.mask();
  const Mask& mb = b.mask();
  std::size_t n = 0;
  for (int v = both.y; v < both.y + both.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * ma.width;
    for (int u = both.x; u < both.x + both.width; ++u)
      n += ma.data[row + u] != 0 && mb.data[row + u] != 0;
  }
  return n;
}

// The share of the smaller box that lies inside the other (0 when either is empty).
double box_share(const Box& a, const Box& b) {
  const double w = std::min(a.x + a.w, b.x + b.w) - std::max(a.x, b.x);
  const double h = std::min(a.y + a.h, b.y + b.h) - std::max(a.y, b.y);
  const double smaller = std::min(a.w * a.h, b.w * b.h);
  return w > 0 && h > 0 && smaller > 0 ? w * h / smaller : 0.0;
}

std::size_t pixels(InstanceMask& m) {
  if (m.pixels == InstanceMask::kPixelsUnknown) m.pixels = mask_pixels(m.mask(), m.bounds);
  return m.pixels;
}

// Takes a clean-up's mask (refine_mask, gate_mask_depth) when it removed pixels, and counts the
// instance and the pixels.
template <typename CleanUp>
void adopt(CleanUp&& r, InstanceMask& m, std::size_t& instances, std::uint64_t& removed) {
  if (r.removed_pixels == 0) return;
  ++instances;
  removed += r.removed_pixels;
  m.owned = std::move(r.mask);
  m.given = nullptr;
  m.bounds = r.bounds;
}

// A given mask after refine_mask (the parts across a depth edge from the rest go) and the depth
// gate (pixels whose depth disagrees with the rest of the observation go), each counted.
void clean_given_mask(const InstanceMaskOptions& options, const Camera& camera,
                      const cv::Mat& depth, InstanceMask& m, InstanceMaskCounts& counts) {
  if (options.refine.enabled)
    adopt(refine_mask(m.mask(), m.bounds, depth, camera, options.refine), m, counts.refined,
          counts.refine_pixels_removed);
  if (options.gate.enabled && !m.bounds.empty())
    adopt(gate_mask_depth(m.mask(), m.bounds, depth, camera, options.gate), m, counts.depth_gated,
          counts.gate_pixels_removed);
}

void check_inputs(const FrameSegmentation& seg, const cv::Mat& depth, const Camera& camera) {
  require(depth.type() == CV_16UC1 && depth.cols == camera.width && depth.rows == camera.height,
          "make_instance_masks: depth",
          "expected a 16-bit single-channel image of the camera's size " +
              size_text(camera.width, camera.height));
  for (std::size_t i = 0; i < seg.instances.size(); ++i) {
    const auto& mask = seg.instances[i].mask;
    if (!mask) continue;
    require(mask->width == depth.cols && mask->height == depth.rows &&
                mask->data.size() == static_cast<std::size_t>(depth.cols) * depth.rows,
            "make_instance_masks: " + seg.source + ": instances[" + std::to_string(i) + "].mask",
            "mask is " + size_text(mask->width, mask->height) + " with " +
                std::to_string(mask->data.size()) + " values; expected " +
                size_text(depth.cols, depth.rows) + " like the depth image");
  }
}

}  // namespace

void InstanceMaskOptions::check() const {
  require(std::isfinite(min_score) && min_score >= 0 && min_score <= 1,
          "InstanceMaskOptions.min_score", "must be in [0, 1], got " + number_text(min_score));
  require(std::isfinite(duplicate_overlap) && duplicate_overlap > 0 && duplicate_overlap <= 1,
          "InstanceMaskOptions.duplicate_overlap",
          "must be in (0, 1], got " + number_text(duplicate_overlap));
  box.check();
  refine.check();
  gate.check();
}

std::vector<InstanceMask> make_instance_masks(const FrameSegmentation& seg, const cv::Mat& depth,
                                              const Camera& camera,
                                              const InstanceMaskOptions& options,
                                              InstanceMaskCounts& counts) {
  options.check();
  check_inputs(seg, depth, camera);
  std::vector<InstanceMask> made;
  made.reserve(seg.instances.size());
  for (const auto& instance : seg.instances) {
    ++counts.instances;
    if (instance.score < options.min_score) {
      ++counts.below_score;
      continue;
    }
    InstanceMask m;
    m.instance = &instance;
    if (!instance.mask) {
      ++counts.from_box;
      auto box = mask_from_box(instance.bbox, depth, camera, options.box);
      if (box.status != BoxMaskStatus::kOk) {
        ++counts.empty;
        continue;
      }
      m.owned = std::move(box.mask);
      m.bounds = box.bounds;  // what mask_bounds() finds, known without a scan of the image
      m.pixels = box.pixels;
    } else {
      m.given = &*instance.mask;
      m.bounds = geometry::mask_bounds(*m.given);
      clean_given_mask(options, camera, depth, m, counts);
    }
    if (m.bounds.empty()) {
      ++counts.empty;
      continue;
    }
    m.cls = canonical_class(instance.class_name);
    made.push_back(std::move(m));
  }
  return made;
}

void drop_duplicates(std::vector<InstanceMask>& masks, double overlap, InstanceMaskCounts& counts) {
  require(std::isfinite(overlap) && overlap > 0 && overlap <= 1, "drop_duplicates: overlap",
          "must be in (0, 1], got " + number_text(overlap));
  if (overlap >= 1.0) return;
  std::vector<std::size_t> order(masks.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return masks[a].instance->score > masks[b].instance->score;
  });
  std::vector<bool> keep(masks.size(), true);
  std::vector<std::size_t> kept;
  for (std::size_t i : order) {
    for (std::size_t k : kept) {
      if (masks[k].cls != masks[i].cls) continue;
      if (box_share(masks[i].instance->bbox, masks[k].instance->bbox) < overlap) continue;
      const std::size_t smaller = std::min(pixels(masks[i]), pixels(masks[k]));
      if (smaller > 0 && static_cast<double>(shared_pixels(masks[i], masks[k])) >=
                             overlap * static_cast<double>(smaller)) {
        keep[i] = false;
        ++counts.duplicates;
        break;
      }
    }
    if (keep[i]) kept.push_back(i);
  }
  std::size_t out = 0;
  for (std::size_t i = 0; i < masks.size(); ++i)
    if (keep[i]) {
      if (out != i) masks[out] = std::move(masks[i]);
      ++out;
    }
  masks.resize(out);
}

std::vector<InstanceMask> clean_instance_masks(const FrameSegmentation& seg, const cv::Mat& depth,
                                               const Camera& camera,
                                               const InstanceMaskOptions& options,
                                               InstanceMaskCounts& counts) {
  std::vector<InstanceMask> masks = make_instance_masks(seg, depth, camera, options, counts);
  drop_duplicates(masks, options.duplicate_overlap, counts);
  return masks;
}

}  // namespace objmap::segmentation
