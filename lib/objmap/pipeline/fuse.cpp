// `objmap fuse` as an outline (run_fuse): each step is a function in a file of its own.
//  - steps 1-2, inputs and keyframes: fuse_inputs.cpp; which segmentation frame each keyframe
//    takes: segmentation_frames.cpp
//  - step 3, the keyframe loop and its threads: fuse_keyframes.cpp
//  - step 4, the objects after the keyframes (merge pass, records, oversize cut, sightings,
//    meshes): fuse_objects.cpp; the dense map as a cloud: dense_cloud.cpp; the scene:
//    fuse_scene.cpp
//  - step 5, the run folder's files: run_folder.cpp
//  - the options' tables, preset and checks: fuse_options.cpp
#include "objmap/pipeline/fuse.h"

#include <future>
#include <optional>

#include "objmap/core/clock.h"
#include "objmap/core/error.h"
#include "objmap/core/parallel.h"
#include "objmap/core/version.h"
#include "objmap/io/atomic.h"
#include "objmap/io/ply.h"
#include "objmap/pipeline/dense_cloud.h"
#include "objmap/pipeline/fuse_inputs.h"
#include "objmap/pipeline/fuse_keyframes.h"
#include "objmap/pipeline/fuse_maps.h"
#include "objmap/pipeline/fuse_objects.h"
#include "objmap/pipeline/fuse_scene.h"
#include "objmap/pipeline/run_folder.h"
#include "objmap/segmentation/class_sizes.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

FuseMaps make_fuse_maps(const FuseOptions& options, const FuseChoices& choices,
                        const FuseResult& result) {
  FuseMaps maps{
      dense_map_options(options, result.threads),
      fusion::VoxelMap(dense_map_options(options, result.threads)),
      fusion::ObjectMap(object_map_options(options, choices, result.keyframes.still_camera)),
      std::nullopt,
      std::nullopt,
      std::nullopt,
      {},
      {}};
  if (choices.meshes.objects) maps.object_views.emplace();
  if (choices.meshes.scene)
    maps.scene_model.emplace(unbounded_box(), options.mesh.scene_voxel_m,
                             scene_tsdf_options(options.mesh));
  if (maps.objects.options().min_detected_share > 0.0) maps.view_log.emplace(result.camera);
  return maps;
}

FuseResult run_fuse(const FuseOptions& options, const FuseProgress& progress) {
  const FuseChoices choices = options.check();  // the option strings parsed, once
  io::require_not_an_input({"--out", options.out}, {{"--dataset", options.dataset},
                                                    {"--trajectory", options.trajectory},
                                                    {"--segmentation", options.segmentation}});
  io::require_replaceable(options.out, io::kRunFolder);  // before the work, not after it
  const segmentation::ClassSizes class_sizes =
      segmentation::ClassSizes::from_spec(options.class_sizes);
  const auto t_start = Clock::now();
  FuseResult result;
  // 1-2. Inputs (the TUM folder, the camera, the trajectory, the segmentation) and keyframes.
  const FuseInputs inputs = load_inputs(options, result);
  result.threads = fuse_threads(options.threads);

  // 3. Back-project and fuse, keyframe by keyframe, with the worker pipeline; the maps do not
  //    depend on the thread count.
  const auto t0 = Clock::now();
  FuseMaps maps = make_fuse_maps(options, choices, result);
  fuse_keyframes(options, choices, progress, inputs, options.dense_map ? &maps.dense : nullptr,
                 maps.objects, maps.object_views ? &*maps.object_views : nullptr,
                 maps.scene_model ? &*maps.scene_model : nullptr,
                 maps.view_log ? &*maps.view_log : nullptr, result);
  result.times.push_back({"back-project and fuse", seconds_since(t0)});

  // 4-5. The objects, the scene and the run folder's files, written under a temporary name and
  //      renamed when complete.
  io::StagingDir staging(options.out, io::kRunFolder);
  finish_fuse(options, choices, inputs, class_sizes, maps, staging.path(), t_start, result);
  staging.commit();
  return result;
}

void finish_fuse(const FuseOptions& options, const FuseChoices& choices, const FuseInputs& inputs,
                 const segmentation::ClassSizes& class_sizes, FuseMaps& maps, const fs::path& dir,
                 Clock::time_point started, FuseResult& result) {
  fusion::ObjectMap& objects = maps.objects;
  const fusion::ViewLog* view_log = maps.view_log ? &*maps.view_log : nullptr;
  // The dense map's cloud, the up direction and the support surfaces (docs/scene.md) are made on
  // a second thread meanwhile the objects are merged and filtered (they do not depend on each
  // other); objmap follow hands the cloud in made (maps.dense_cloud), and the up and surfaces
  // (maps.scene).
  io::PlyWriteOptions ply;
  ply.comment = std::string("objmap ") + objmap::version();
  auto t_dense = Clock::now();
  double dense_seconds = 0.0;
  std::vector<Pose> cameras;
  for (const Keyframe& k : result.keyframes.keyframes) cameras.push_back(k.world_from_cam);
  std::shared_ptr<const DenseCloud> handed;  // maps.dense_cloud's, once made
  std::future<DenseCloud> dense_future = std::async(std::launch::async, [&] {
    if (maps.dense_cloud.valid()) handed = maps.dense_cloud.get();
    DenseCloud cloud = options.dense_map && !handed
                           ? take_dense_cloud(maps.dense, maps.dense_options)
                           : DenseCloud{};
    dense_seconds = seconds_since(t_dense);
    const DenseCloud& made = handed ? *handed : cloud;
    if (maps.scene.valid())
      result.scene = *maps.scene.get();
    else
      scene::find_up_and_surfaces(cameras, made.cloud.points, options.scene, result.scene);
    return cloud;
  });

  // 4. The final merge pass (ID-switch repair), then each confirmed object's filtered record.
  auto t0 = Clock::now();
  merge_and_filter_objects(options, objects, view_log, result);
  result.times.push_back({"merge and filter objects", seconds_since(t0)});

  DenseCloud own_dense_cloud = dense_future.get();  // empty when the cloud was handed in
  result.times.push_back({"dense map (parallel to the objects)", dense_seconds});
  result.times.push_back({"up and surfaces (parallel to the objects)",
                          result.scene.seconds_up + result.scene.seconds_surfaces});
  for (const auto& w : result.scene.up.warnings) result.warnings.push_back("up direction: " + w);

  // 4a. Objects wider than their class allows are cut, now that the up is known.
  cut_oversize_objects(options, class_sizes, objects, view_log, result);

  // 4b. What moves is not the map: the objects of a mover class (a person, a dog) are sightings.
  take_sightings(choices, result);
  if (handed && !result.sightings.empty()) own_dense_cloud = *handed;
  const DenseCloud& dense_cloud = handed && result.sightings.empty() ? *handed : own_dense_cloud;
  result.dense_voxels_of_sightings =
      drop_sighting_voxels(own_dense_cloud, result.sightings, result.objects, options.map_voxel_m);

  // 4c. Suspected duplicates: confirmed objects of one class that overlap or touch, with the merge
  //     pass's reason for keeping them apart (no ground truth needed), on the boxes of
  //     the records (before the scene step turns them upright).
  t0 = Clock::now();
  result.duplicates = fusion::find_duplicates(result.objects, objects, options.duplicates);
  result.times.push_back({"duplicate check", seconds_since(t0)});

  // 4d. The objects' boxes stand on up; the surfaces that are objects' tops; the relations (on,
  //     near, above, under).
  relate_to_scene(result.objects, options.scene, record_options(options, result.threads),
                  result.scene);
  result.times.push_back({"boxes upright and relations", result.scene.seconds_relations});

  // 4e. The meshes: each object's TSDF model from the observations that joined it (merged objects
  //     union theirs), in its box; the scene's model, fused keyframe by keyframe, meshed.
  make_meshes(options, objects, maps.object_views ? &*maps.object_views : nullptr, maps.scene_model,
              result);

  // 5. The maps (dense, semantic, objects, one PLY per object) and objects.json.
  t0 = Clock::now();
  result.dense_points_map = dense_cloud.cloud.size();
  MapPoints map_points;
  const ordered_json objects_json = write_maps(options, dir, ply, dense_cloud, result, map_points);
  own_dense_cloud = DenseCloud();
  write_objects_json(dir, objects_json, result.sightings, result.scene);
  result.times.push_back({"write outputs", seconds_since(t0)});
  result.seconds_total = seconds_since(started);
  result.peak_rss_kb = peak_rss_kb();

  // 5b. run.json: options, inputs with checksums, counts per stage, Table 6, time per stage,
  //     memory.
  write_run_json(dir, options, inputs, objects.options(), map_points, result);
  if (options.trajectory.empty()) write_dataset_trajectory(dir, options, inputs, result);
}

std::vector<fusion::Observation> remake_observations(const FuseOptions& options,
                                                     const std::vector<int>& keyframe_indices) {
  {
    FuseOptions checked = options;  // nothing is written: `out` may be empty
    if (checked.out.empty()) checked.out = "unused";
    checked.check();
  }
  FuseResult result;
  const FuseInputs inputs = load_inputs(options, result);
  const auto& keyframes = result.keyframes.keyframes;
  for (int i : keyframe_indices)
    require(i >= 0 && static_cast<std::size_t>(i) < keyframes.size(), options.dataset.string(),
            "keyframe " + std::to_string(i) + " does not exist (" +
                std::to_string(keyframes.size()) +
                " keyframes); expected the inputs and options the run was fused with");
  const int threads = fuse_threads(options.threads);
  const geometry::RayTable rays = geometry::make_ray_table(result.camera, threads);
  std::vector<std::vector<fusion::Observation>> per_keyframe(keyframe_indices.size());
  parallel_for(keyframe_indices.size(), threads, [&](std::size_t j) {
    const std::size_t i = static_cast<std::size_t>(keyframe_indices[j]);
    per_keyframe[j] = keyframe_observations(options, result.camera, rays, inputs, keyframes, i);
  });
  std::vector<fusion::Observation> out;
  for (auto& v : per_keyframe)
    for (auto& o : v) out.push_back(std::move(o));
  return out;
}

}  // namespace objmap::pipeline
