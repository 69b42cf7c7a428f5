// ObjectMap's records (voxel support, eq 18, position) and the semantic maps.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <deque>
#include <iterator>
#include <limits>
#include <optional>
#include <set>
#include <string>

#include "objmap/core/error.h"
#include "objmap/fusion/object_map_object.h"
#include "objmap/fusion/palette.h"
#include "objmap/fusion/record_cache.h"
#include "objmap/fusion/split.h"
#include "objmap/geometry/bounds.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

void ObjectMap::filter_record(const Object& o, const RecordOptions& options,
                              ObjectRecord& r) const {
  // Voxel support: only voxels seen in enough of the object's observations (see RecordOptions).
  const bool support = options.min_voxel_support > 0.0;
  const double need = std::min(255.0, std::max(1.0, options.min_voxel_support * o.observations));
  const auto supported = [&](VoxelKey key) {
    const std::uint8_t* hits = o.near->find(key);
    return hits && *hits >= need;
  };
  const auto outliers = [&](PointCloud& cloud) {  // eq 18
    filters::OutlierResult filtered = filters::remove_outliers(cloud, options.outlier);
    cloud = std::move(filtered.kept);
    r.outlier_threshold = filtered.threshold;
  };
  if (options.outlier_on_points || options.voxel_nearest_centre) {
    // The paper's order (§3.3): eq 18 on the back-projected points, then the voxel filter.
    require(options_.keep_points, "RecordOptions",
            "outlier_on_points and voxel_nearest_centre need ObjectMapOptions.keep_points");
    PointCloud points = o.points;
    if (options.outlier_filter && options.outlier_on_points) outliers(points);
    std::function<bool(VoxelKey)> keep;
    if (support) keep = supported;
    if (options.voxel_nearest_centre) {
      r.cloud = voxel_nearest_centre(points, options_.voxel_m, keep);
    } else {
      VoxelMap voxels(VoxelMapOptions{options_.voxel_m, 1});
      voxels.insert(points);
      for (const auto& [key, v] : voxels.sorted_voxels())
        if (!keep || keep(key))
          r.cloud.push_back(voxels.mean_position(key, *v).cast<float>(), v->mean_color());
    }
    r.points_voxel = r.cloud.size();
    if (options.outlier_filter && !options.outlier_on_points) outliers(r.cloud);
    r.points_filtered = r.cloud.size();
    return;
  }
  // The voxel filter is the object's voxel set itself: one point per voxel, sorted by key.
  PointCloud voxel_cloud;
  if (support) {
    const auto voxels = o.voxels->sorted_voxels(supported);
    voxel_cloud.reserve(voxels.size());
    for (const auto& [key, v] : voxels)
      voxel_cloud.push_back(o.voxels->mean_position(key, *v).cast<float>(), v->mean_color());
  } else {
    voxel_cloud = o.voxels->to_cloud();
  }
  r.points_voxel = voxel_cloud.size();
  if (options.outlier_filter) outliers(voxel_cloud);  // eq 18 on the voxel cloud
  r.cloud = std::move(voxel_cloud);
  r.points_filtered = r.cloud.size();
}

std::uint64_t ObjectMap::record_content(const Object& o, const RecordOptions& options) const {
  const bool support = options.min_voxel_support > 0.0;
  OrderFreeHash voxels;
  o.voxels->for_each([&](VoxelKey key, const VoxelData& v) {
    std::uint64_t h = voxel_content(key, v);
    if (support) {
      const std::uint8_t* hits = o.near->find(key);
      h = content_mix(h ^ (hits ? *hits : 0u));
    }
    voxels.add(h);
  });
  std::uint64_t h = voxels.value(o.voxels->size());
  for (const std::uint64_t field :
       {content_bits(o.observations), content_bits(options.min_voxel_support),
        content_bits(options.outlier_filter), content_bits(options.outlier.neighbours),
        content_bits(options.outlier.std_ratio), content_bits(options.position_percentile),
        content_bits(options.position_is_centroid), content_bits(options.outlier_on_points),
        content_bits(options.voxel_nearest_centre)})
    h = content_mix(h ^ field);
  return h | 1;  // never 0 (0: no cache)
}

std::vector<ObjectRecord> ObjectMap::records(const RecordOptions& options) const {
  std::set<int> all;
  for (const auto& op : objects_)
    if (op->alive) all.insert(op->id);
  return records(options, all);
}

std::vector<ObjectRecord> ObjectMap::records(const RecordOptions& options,
                                             const std::set<int>& ids) const {
  std::vector<ObjectRecord> out;
  for (int id : ids) {
    if (id < 0 || id >= static_cast<int>(objects_.size())) continue;
    const Object& o = *objects_[id];
    if (!o.alive) continue;
    const int views = count_views(o.provenance, options_);
    const bool is_confirmed = confirmed(o);
    if (options.confirmed_only && !is_confirmed) continue;
    ObjectRecord r;
    r.id = o.id;
    r.class_name = voted_class(o);
    r.class_histogram = o.histogram;
    r.mean_score = o.observations > 0 ? o.score_sum / o.observations : 0.0;
    r.observations = o.observations;
    r.views = views;
    r.confirmed = is_confirmed;
    r.frames_detected = static_cast<int>(o.frames.size());
    r.frames_in_view = o.frames_in_view;
    r.first_seen = o.first_seen;
    r.last_seen = o.last_seen;
    r.track_ids.assign(o.track_ids.begin(), o.track_ids.end());
    r.provenance = o.provenance;
    r.merges = o.merges;
    r.points_raw = o.voxels->points_inserted();
    const std::uint64_t content =
        record_cache_ && !options_.keep_points ? record_content(o, options) : 0;
    std::optional<RecordCache::Filtered> made;
    if (content) made = record_cache_->find(o.id, content);
    if (!made) {
      made.emplace();
      filter_record(o, options, r);
      made->content = content;
      made->points_voxel = r.points_voxel;
      made->points_filtered = r.points_filtered;
      made->outlier_threshold = r.outlier_threshold;
      made->centroid = geometry::centroid(r.cloud);  // eq 16: the mean of the points
      made->position = options.position_is_centroid
                           ? made->centroid
                           : geometry::percentile_box_centre(r.cloud, options.position_percentile);
      made->aabb = geometry::compute_aabb(r.cloud);
      made->obb = geometry::compute_obb(r.cloud);
      made->cloud = std::move(r.cloud);
      if (content) record_cache_->put(o.id, *made);
    }
    r.cloud = std::move(made->cloud);
    r.points_voxel = made->points_voxel;
    r.points_filtered = made->points_filtered;
    r.outlier_threshold = made->outlier_threshold;
    r.centroid = made->centroid;
    r.position = made->position;
    r.aabb = made->aabb;
    r.obb = made->obb;
    out.push_back(std::move(r));
  }
  return out;
}

geometry::VoxelHashTable<std::uint32_t> voxel_owners(const std::vector<ObjectRecord>& records,
                                                     double voxel_m) {
  const float inv_voxel_m = static_cast<float>(1.0 / voxel_m);  // as VoxelMap::key_of
  geometry::VoxelHashTable<std::uint32_t> owner;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const ObjectRecord& r = records[i];
    if (!r.confirmed) continue;
    for (const Vec3f& p : r.cloud.points) {
      const VoxelKey key = geometry::voxel_key(p, inv_voxel_m);
      if (key == geometry::kNoVoxel) continue;
      std::uint32_t& slot = owner[key];
      if (slot != 0) {
        const ObjectRecord& other = records[slot - 1];
        const bool better = r.observations > other.observations ||
                            (r.observations == other.observations && r.id < other.id);
        if (!better) continue;
      }
      slot = static_cast<std::uint32_t>(i + 1);
    }
  }
  return owner;
}

SemanticMaps make_semantic_maps(const VoxelMap& dense, const std::vector<ObjectRecord>& records) {
  SemanticMaps maps;
  const geometry::VoxelHashTable<std::uint32_t> owner = voxel_owners(records, dense.voxel_m());
  const auto voxels = dense.sorted_voxels();
  maps.semantic.reserve(voxels.size());
  for (const auto& [key, v] : voxels) {
    const std::uint32_t* slot = owner.find(key);
    const Vec3f p = dense.mean_position(key, *v).cast<float>();
    if (slot) {
      maps.semantic.push_back(p, class_color(records[*slot - 1].class_name));
      ++maps.voxels_painted;
    } else {
      maps.semantic.push_back(p, v->mean_color());
    }
  }
  for (const ObjectRecord& r : records) {
    if (!r.confirmed) continue;
    const Rgb c = class_color(r.class_name);
    for (const Vec3f& p : r.cloud.points) maps.objects_only.push_back(p, c);
  }
  return maps;
}

}  // namespace objmap::fusion
