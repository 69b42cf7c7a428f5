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
#include "objmap/pipeline/fuse_objects.h"
#include "objmap/pipeline/fuse_scene.h"
#include "objmap/pipeline/run_folder.h"
#include "objmap/segmentation/class_sizes.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

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
  auto t0 = Clock::now();
  const fusion::VoxelMapOptions dense_options = dense_map_options(options, result.threads);
  fusion::VoxelMap dense(dense_options);
  const fusion::ObjectMapOptions object_options =
      object_map_options(options, choices, result.keyframes.still_camera);
  fusion::ObjectMap objects(object_options);
  const mesh::MeshSelection& meshes = choices.meshes;
  std::optional<ObjectViews> object_views;
  if (meshes.objects) object_views.emplace();
  std::optional<mesh::TsdfModel> scene_model;
  if (meshes.scene)
    scene_model.emplace(unbounded_box(), options.mesh.scene_voxel_m,
                        scene_tsdf_options(options.mesh));
  std::optional<fusion::ViewLog> view_log;
  if (object_options.min_detected_share > 0.0) view_log.emplace(result.camera);
  fuse_keyframes(options, choices, progress, inputs, options.dense_map ? &dense : nullptr, objects,
                 object_views ? &*object_views : nullptr, scene_model ? &*scene_model : nullptr,
                 view_log ? &*view_log : nullptr, result);
  result.times.push_back({"back-project and fuse", seconds_since(t0)});

  // 4-5. The run folder is written under a temporary name and renamed when complete. The dense
  //      map's cloud, the up direction and the support surfaces (docs/scene.md) are made on a
  //      second thread meanwhile the objects are merged and filtered (they do not depend on each
  //      other).
  io::StagingDir staging(options.out, io::kRunFolder);
  const fs::path dir = staging.path();
  io::PlyWriteOptions ply;
  ply.comment = std::string("objmap ") + objmap::version();
  auto t_dense = Clock::now();
  double dense_seconds = 0.0;
  std::vector<Pose> cameras;
  for (const Keyframe& k : result.keyframes.keyframes) cameras.push_back(k.world_from_cam);
  std::future<DenseCloud> dense_future = std::async(std::launch::async, [&] {
    DenseCloud cloud = options.dense_map ? take_dense_cloud(dense, dense_options) : DenseCloud{};
    dense_seconds = seconds_since(t_dense);
    scene::find_up_and_surfaces(cameras, cloud.cloud.points, options.scene, result.scene);
    return cloud;
  });

  // 4. The final merge pass (ID-switch repair), then each confirmed object's filtered record.
  t0 = Clock::now();
  merge_and_filter_objects(options, objects, view_log ? &*view_log : nullptr, result);
  result.times.push_back({"merge and filter objects", seconds_since(t0)});

  DenseCloud dense_cloud = dense_future.get();
  result.times.push_back({"dense map (parallel to the objects)", dense_seconds});
  result.times.push_back({"up and surfaces (parallel to the objects)",
                          result.scene.seconds_up + result.scene.seconds_surfaces});
  for (const auto& w : result.scene.up.warnings) result.warnings.push_back("up direction: " + w);

  // 4a. Objects wider than their class allows are cut, now that the up is known.
  cut_oversize_objects(options, class_sizes, objects, view_log ? &*view_log : nullptr, result);

  // 4b. What moves is not the map: the objects of a mover class (a person, a dog) are sightings.
  take_sightings(choices, result);
  result.dense_voxels_of_sightings =
      drop_sighting_voxels(dense_cloud, result.sightings, result.objects, options.map_voxel_m);

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
  make_meshes(options, objects, object_views ? &*object_views : nullptr, scene_model, result);

  // 5. The maps (dense, semantic, objects, one PLY per object) and objects.json.
  t0 = Clock::now();
  result.dense_points_map = dense_cloud.cloud.size();
  MapPoints map_points;
  const ordered_json objects_json = write_maps(options, dir, ply, dense_cloud, result, map_points);
  dense_cloud = DenseCloud();
  write_objects_json(dir, objects_json, result.sightings, result.scene);
  result.times.push_back({"write outputs", seconds_since(t0)});
  result.seconds_total = seconds_since(t_start);
  result.peak_rss_kb = peak_rss_kb();

  // 5b. run.json: options, inputs with checksums, counts per stage, Table 6, time per stage,
  //     memory.
  write_run_json(dir, options, inputs, object_options, map_points, result);
  if (options.trajectory.empty()) write_dataset_trajectory(dir, options, inputs, result);
  staging.commit();
  return result;
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
