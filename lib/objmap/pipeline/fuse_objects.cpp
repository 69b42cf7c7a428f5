#include "objmap/pipeline/fuse_objects.h"

#include <algorithm>
#include <set>

#include "objmap/core/clock.h"
#include "objmap/fusion/movers.h"

namespace objmap::pipeline {

namespace {

// The point counts of the records (Table 6).
void count_points(FuseResult& result) {
  result.object_points_raw = result.object_points_voxel = result.object_points_filtered = 0;
  for (const auto& r : result.objects) {
    result.object_points_raw += r.points_raw;
    result.object_points_voxel += r.points_voxel;
    result.object_points_filtered += r.points_filtered;
  }
}

// Each confirmed object's filtered record, and their point counts.
void make_records(const FuseOptions& options, const fusion::ObjectMap& objects,
                  FuseResult& result) {
  result.objects = objects.records(record_options(options, result.threads));
  count_points(result);
}

// Where each object was in view (with `view_log`), then each confirmed object's filtered record.
void judge_and_record(const FuseOptions& options, fusion::ObjectMap& objects,
                      const fusion::ViewLog* view_log, FuseResult& result) {
  result.objects_total = objects.size();
  if (view_log) {
    objects.judge_visibility(*view_log, options.visibility);
    result.objects_below_share = objects.below_share_count();
    result.detected_share_bar = objects.detected_share_bar();
  }
  make_records(options, objects, result);
}

}  // namespace

fusion::ObjectMapOptions object_map_options(const FuseOptions& options, const FuseChoices& choices,
                                            bool still_camera) {
  fusion::ObjectMapOptions object_options = options.objects;
  object_options.overlap_measure = choices.overlap_measure;
  object_options.distance_score = choices.distance_score;
  object_options.confirmation = choices.confirmation;
  object_options.keep_points = options.outlier_on_points || options.voxel_nearest_centre;
  if (still_camera) {
    // A camera that hardly moves has one viewpoint: its frames are the views.
    object_options.view_min_translation_m = 0.0;
    object_options.view_min_rotation_deg = 0.0;
  }
  return object_options;
}

fusion::RecordOptions record_options(const FuseOptions& options, int threads) {
  fusion::RecordOptions r;
  r.confirmed_only = true;
  r.outlier_filter = options.outlier_filter;
  r.outlier = options.outlier;
  r.outlier.threads = threads;
  r.min_voxel_support = options.min_voxel_support;
  r.outlier_on_points = options.outlier_on_points;
  r.voxel_nearest_centre = options.voxel_nearest_centre;
  r.position_is_centroid = options.position_is_centroid;
  r.position_without_support = options.position_without_support;
  r.support_strip = options.support_strip;
  return r;
}

void merge_and_filter_objects(const FuseOptions& options, fusion::ObjectMap& objects,
                              const fusion::ViewLog* view_log, FuseResult& result) {
  result.merges = objects.merge_pass();
  result.splits = objects.split_pass();
  judge_and_record(options, objects, view_log, result);
}

void cut_oversize_objects(const FuseOptions& options, const segmentation::ClassSizes& sizes,
                          fusion::ObjectMap& objects, const fusion::ViewLog* view_log,
                          FuseResult& result) {
  const auto t0 = Clock::now();
  result.oversize = objects.split_oversize(result.scene.up.up, sizes, &result.renamed);
  result.part_joins = objects.join_parts(result.scene.up.up, sizes);
  std::set<int> cut;
  for (const fusion::SplitLink& link : result.oversize) {
    cut.insert(link.from);
    cut.insert(link.parts.begin(), link.parts.end());
  }
  for (const fusion::MergeLink& link : result.part_joins) cut.insert({link.into, link.absorbed});
  for (const fusion::ClassRename& r : result.renamed) cut.insert(r.id);
  if (!cut.empty()) {
    const double bar = result.detected_share_bar;
    result.objects_total = objects.size();
    if (view_log) {
      objects.judge_visibility(*view_log, options.visibility, /*only_unjudged=*/true);
      result.objects_below_share = objects.below_share_count();
      result.detected_share_bar = objects.detected_share_bar();
    }
    if (result.detected_share_bar != bar) {
      make_records(options, objects, result);
    } else {
      std::vector<fusion::ObjectRecord> records;
      for (auto& r : result.objects)
        if (!cut.count(r.id)) records.push_back(std::move(r));
      for (auto& r : objects.records(record_options(options, result.threads), cut))
        records.push_back(std::move(r));
      std::sort(
          records.begin(), records.end(),
          [](const fusion::ObjectRecord& x, const fusion::ObjectRecord& y) { return x.id < y.id; });
      result.objects = std::move(records);
      count_points(result);
    }
  }
  result.times.push_back({"oversize objects", seconds_since(t0)});
}

void take_sightings(const FuseChoices& choices, FuseResult& result) {
  result.sightings = fusion::take_movers(result.objects, choices.movers);
}

void make_meshes(const FuseOptions& options, const fusion::ObjectMap& objects,
                 const ObjectViews* object_views, std::optional<mesh::TsdfModel>& scene_model,
                 FuseResult& result) {
  if (object_views) {
    const auto t0 = Clock::now();
    result.object_meshes =
        mesh_objects(result.objects, *object_views, objects, options.mesh,
                     0.5 * (result.camera.fx + result.camera.fy), result.threads);
    result.times.push_back({"object meshes", seconds_since(t0)});
  }
  if (scene_model) {
    const auto t0 = Clock::now();
    result.scene_mesh = scene_model->mesh();
    scene_model.reset();
    result.times.push_back(
        {"scene mesh (and its fusion's share after the keyframes)", seconds_since(t0)});
  }
}

}  // namespace objmap::pipeline
