#include "objmap/fusion/duplicates.h"
#include "objmap/core/format.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>

#include "objmap/core/error.h"
#include "objmap/fusion/record_cache.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

void DuplicateOptions::check() const {
  require(std::isfinite(touch_distance_m) && touch_distance_m >= 0.0,
          "DuplicateOptions.touch_distance_m",
          "must be >= 0 metres, got " + std::to_string(touch_distance_m));
  require(obb_samples_per_axis >= 1 && obb_samples_per_axis <= 200,
          "DuplicateOptions.obb_samples_per_axis",
          "must be in [1, 200], got " + std::to_string(obb_samples_per_axis));
  require(std::isfinite(min_obb_overlap) && min_obb_overlap >= 0.0 && min_obb_overlap <= 1.0,
          "DuplicateOptions.min_obb_overlap",
          "must be in [0, 1], got " + std::to_string(min_obb_overlap));
}

double obb_containment(const Obb& small, const Obb& large, int samples_per_axis) {
  // Boxes whose bounding spheres are apart share nothing.
  if ((small.center - large.center).norm() > small.half_extent.norm() + large.half_extent.norm())
    return 0.0;
  const int n = std::max(1, samples_per_axis);
  std::size_t inside = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        // Cell centre in the small box's frame: -h + (2·index + 1)·h / n along each axis.
        const Vec3 f((2.0 * i + 1.0) / n - 1.0, (2.0 * j + 1.0) / n - 1.0,
                     (2.0 * k + 1.0) / n - 1.0);
        const Vec3 point_in_world =
            small.center + small.rotation * f.cwiseProduct(small.half_extent);
        inside += large.contains(point_in_world);
      }
  return static_cast<double>(inside) / (static_cast<double>(n) * n * n);
}

namespace {

// FLANN's single kd-tree over one record's cloud (exact search, as
// filters/neighbour_distances.cpp).
using KdIndex = flann::Index<flann::L2_Simple<float>>;

std::unique_ptr<KdIndex> make_tree(const PointCloud& cloud) {
  static_assert(sizeof(Vec3f) == 3 * sizeof(float), "points must be packed xyz floats");
  flann::Matrix<float> data(const_cast<float*>(cloud.points.front().data()), cloud.size(), 3);
  auto tree = std::make_unique<KdIndex>(data, flann::KDTreeSingleIndexParams(15));
  tree->buildIndex();
  return tree;
}

struct Contact {
  double distance_m = std::numeric_limits<double>::infinity();
  double share = 0.0;  // of `query`'s points within the touch distance
};

// Nearest point of `tree`'s cloud for each point of `query`, a block of points at a time.
Contact surface_contact(const PointCloud& query, KdIndex& tree, double touch_m) {
  Contact c;
  constexpr std::size_t kBlock = 4096;
  std::vector<int> idx(kBlock);
  std::vector<float> sq(kBlock);
  const flann::SearchParams params(-1, 0.0f, /*sorted=*/true);
  std::size_t touching = 0;
  const double touch_sq = touch_m * touch_m;
  for (std::size_t b = 0; b < query.size(); b += kBlock) {
    const std::size_t rows = std::min(kBlock, query.size() - b);
    flann::Matrix<float> queries(const_cast<float*>(query.points[b].data()), rows, 3);
    flann::Matrix<int> idx_m(idx.data(), rows, 1);
    flann::Matrix<float> sq_m(sq.data(), rows, 1);
    tree.knnSearch(queries, idx_m, sq_m, 1, params);
    for (std::size_t r = 0; r < rows; ++r) {
      const double d2 = sq[r];
      c.distance_m = std::min(c.distance_m, std::sqrt(d2));
      touching += d2 <= touch_sq;
    }
  }
  c.share = query.empty() ? 0.0 : static_cast<double>(touching) / query.size();
  return c;
}

// A 64-bit hash of a cloud's points (their float bits, in order), seeded with `seed`.
std::uint64_t cloud_hash(const PointCloud& cloud, std::uint64_t seed) {
  std::uint64_t h = seed ^ (cloud.size() * 0x9E3779B97F4A7C15ULL);
  for (const Vec3f& p : cloud.points)
    for (int k = 0; k < 3; ++k) {
      std::uint32_t bits;
      std::memcpy(&bits, &p[k], sizeof bits);
      h = (h ^ bits) * 0x100000001B3ULL;
      h ^= h >> 29;
    }
  return h;
}

// Distance between two axis-aligned boxes (0 when they overlap).
double aabb_gap(const Aabb& x, const Aabb& y) {
  const Vec3 gap = (x.min - y.max).cwiseMax(y.min - x.max).cwiseMax(Vec3::Zero());
  return gap.norm();
}

double volume(const Obb& box) { return 8.0 * box.half_extent.prod(); }

}  // namespace

DuplicateReport find_duplicates(const std::vector<ObjectRecord>& records, const ObjectMap& map,
                                const DuplicateOptions& options) {
  options.check();
  DuplicateReport report;
  std::vector<std::string> cls(records.size());
  for (std::size_t i = 0; i < records.size(); ++i)
    cls[i] = segmentation::canonical_class(records[i].class_name);
  std::vector<std::unique_ptr<KdIndex>> trees(records.size());  // built when first needed
  const auto tree_of = [&](std::size_t i) -> KdIndex& {
    if (!trees[i]) trees[i] = make_tree(records[i].cloud);
    return *trees[i];
  };
  // With the map's contact cache, each cloud's hash (the touch distance folded into the query's).
  ContactCache* const cache = map.contact_cache();
  if (cache) cache->begin_pass();
  std::vector<std::optional<std::uint64_t>> hashes(records.size());
  const auto hash_of = [&](std::size_t i) {
    if (!hashes[i]) hashes[i] = cloud_hash(records[i].cloud, 0);
    return *hashes[i];
  };
  const auto contact_of = [&](std::size_t query, std::size_t other) {
    std::uint64_t hq = 0, ht = 0;
    if (cache) {
      const double touch = options.touch_distance_m;
      std::uint64_t touch_bits;
      std::memcpy(&touch_bits, &touch, sizeof touch_bits);
      hq = hash_of(query) ^ (touch_bits * 0xC2B2AE3D27D4EB4FULL);
      ht = hash_of(other);
      if (const std::optional<ContactCache::Contact> c = cache->find(hq, ht))
        return Contact{c->distance_m, c->share};
    }
    const Contact c =
        surface_contact(records[query].cloud, tree_of(other), options.touch_distance_m);
    if (cache) cache->put(hq, ht, {c.distance_m, c.share});
    return c;
  };
  std::vector<std::size_t> order(records.size());  // by id, so that pairs come out as (a < b)
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t x, std::size_t y) { return records[x].id < records[y].id; });
  for (std::size_t oi = 0; oi < order.size(); ++oi) {
    const std::size_t i = order[oi];
    const ObjectRecord& ra = records[i];
    if (!ra.confirmed || ra.cloud.empty()) continue;
    for (std::size_t oj = oi + 1; oj < order.size(); ++oj) {
      const std::size_t j = order[oj];
      const ObjectRecord& rb = records[j];
      if (!rb.confirmed || rb.cloud.empty() || cls[i] != cls[j]) continue;
      ++report.pairs_checked;
      // 1. Box overlap: the smaller box (by volume; ties: the lower id) sampled in the larger.
      const bool a_small = volume(ra.obb) <= volume(rb.obb);
      const double overlap = obb_containment(a_small ? ra.obb : rb.obb, a_small ? rb.obb : ra.obb,
                                             options.obb_samples_per_axis);
      // Surfaces further apart than their axis-aligned boxes cannot touch.
      const bool boxes_overlap = overlap > 0.0 && overlap >= options.min_obb_overlap;
      if (!boxes_overlap && aabb_gap(ra.aabb, rb.aabb) > options.touch_distance_m) continue;
      // 2. Surface contact: the smaller cloud (fewer points; ties: the lower id) against the
      //    larger's kd-tree.
      const bool a_fewer = ra.cloud.size() <= rb.cloud.size();
      const Contact contact = a_fewer ? contact_of(i, j) : contact_of(j, i);
      if (!boxes_overlap && contact.distance_m > options.touch_distance_m) continue;
      DuplicatePair p;
      p.a = ra.id;
      p.b = rb.id;
      p.class_name = cls[i];
      p.obb_overlap = overlap;
      p.surface_distance_m = contact.distance_m;
      p.touching_share = contact.share;
      // 3. The merge pass's verdict on the two.
      p.merge = map.merge_verdict(ra.id, rb.id);
      report.pairs.push_back(std::move(p));
    }
  }
  return report;
}

std::string describe_refusal(const MergeVerdict& v, const ObjectMapOptions& options) {
  if (!options.final_merge) return "no merge pass (objects.final_merge false)";
  const std::string m = to_string(options.overlap_measure);  // M of the pass
  switch (v.refused) {
    case MergeRefusal::kNone:
      return "would merge";
    case MergeRefusal::kClass:
      return "different voted classes";
    case MergeRefusal::kSharedFrames:
      return "seen together in " + std::to_string(v.shared_frames) + " of " +
             std::to_string(v.smaller_frames) + " keyframes (more than " +
             fixed_text(100.0 * options.merge_max_shared_frames, 0) + "%)";
    case MergeRefusal::kScore:
      return "score P " + fixed_text(v.score_p, 2) +
             " <= " + fixed_text(options.merge_threshold, 2) + " (same track " +
             (v.p_id > 0 ? "yes" : "no") + ", centroids " + fixed_text(v.distance_m, 2) +
             " m apart, " + m + " " + fixed_text(v.overlap, 2) + ")";
    case MergeRefusal::kOverlap:
      return m + " M " + fixed_text(v.overlap, 2) + " < " +
             fixed_text(options.merge_min_overlap, 2);
  }
  return "";
}

}  // namespace objmap::fusion
