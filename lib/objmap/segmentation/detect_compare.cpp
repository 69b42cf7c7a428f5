#include "objmap/segmentation/detect_compare.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace objmap::segmentation {

namespace {

// The instance's mask, or its box filled in a mask of `like`'s size when it has none.
Mask mask_of(const Instance& instance, const Mask& like) {
  if (instance.mask && !instance.mask->empty()) return *instance.mask;
  Mask box{like.width, like.height, std::vector<std::uint8_t>(like.data.size(), 0)};
  const int u0 = std::max(0, static_cast<int>(std::floor(instance.bbox.x)));
  const int v0 = std::max(0, static_cast<int>(std::floor(instance.bbox.y)));
  const int u1 =
      std::min(like.width, static_cast<int>(std::ceil(instance.bbox.x + instance.bbox.w)));
  const int v1 =
      std::min(like.height, static_cast<int>(std::ceil(instance.bbox.y + instance.bbox.h)));
  for (int v = v0; v < v1; ++v)
    std::fill_n(box.data.begin() + static_cast<std::ptrdiff_t>(v) * like.width + u0,
                std::max(0, u1 - u0), std::uint8_t{1});
  return box;
}

}  // namespace

double MaskAgreement::min_iou() const {
  return ious.empty() ? 1.0 : *std::min_element(ious.begin(), ious.end());
}

double MaskAgreement::median_iou() const {
  if (ious.empty()) return 1.0;
  std::vector<double> sorted = ious;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t n = sorted.size();
  return n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

void MaskAgreement::add(const MaskAgreement& more) {
  ious.insert(ious.end(), more.ious.begin(), more.ious.end());
  reference += more.reference;
  other += more.other;
  unmatched_reference += more.unmatched_reference;
  unmatched_other += more.unmatched_other;
}

double mask_iou(const Mask& a, const Mask& b) {
  if (a.empty() || b.empty() || a.width != b.width || a.height != b.height) return 0.0;
  std::size_t both = 0, either = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    both += a.data[i] && b.data[i];
    either += a.data[i] || b.data[i];
  }
  return either ? static_cast<double>(both) / static_cast<double>(either) : 0.0;
}

MaskAgreement compare_masks(const std::vector<Instance>& reference,
                            const std::vector<Instance>& other) {
  MaskAgreement out;
  out.reference = reference.size();
  out.other = other.size();
  // A mask of the frame's size, for instances that have only a box.
  Mask like;
  for (const auto* list : {&reference, &other})
    for (const Instance& i : *list)
      if (i.mask && !i.mask->empty()) like = {i.mask->width, i.mask->height, {}};
  like.data.assign(static_cast<std::size_t>(like.width) * like.height, 0);
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;  // IoU, reference, other
  for (std::size_t r = 0; r < reference.size(); ++r)
    for (std::size_t o = 0; o < other.size(); ++o) {
      if (reference[r].class_name != other[o].class_name) continue;
      const double iou = mask_iou(mask_of(reference[r], like), mask_of(other[o], like));
      if (iou > 0) pairs.emplace_back(iou, r, o);
    }
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) { return a > b; });
  std::vector<bool> used_r(reference.size(), false), used_o(other.size(), false);
  for (const auto& [iou, r, o] : pairs) {
    if (used_r[r] || used_o[o]) continue;
    used_r[r] = used_o[o] = true;
    out.ious.push_back(iou);
  }
  out.unmatched_reference = reference.size() - out.ious.size();
  out.unmatched_other = other.size() - out.ious.size();
  return out;
}

}  // namespace objmap::segmentation
