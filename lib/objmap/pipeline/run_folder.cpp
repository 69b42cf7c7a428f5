#include "objmap/pipeline/run_folder.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <future>
#include <string>

#include "objmap/core/checksum.h"
#include "objmap/core/json_vec.h"
#include "objmap/core/version.h"
#include "objmap/fusion/palette.h"
#include "objmap/io/atomic.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/fuse_scene.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

namespace {

// The dataset's own poses, written into the run folder when no --trajectory is given.
const char* const kDatasetTrajectory = "dataset_trajectory.txt";

std::string read_all(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
// FNV-1a 64 (core/checksum.h) of a file's bytes, as 16 hex digits (input provenance in run.json).
std::string file_checksum(const fs::path& file) { return hex64(fnv1a(read_all(file))); }
// Over the sorted relative names and contents of every file of a folder.
std::string folder_checksum(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::uint64_t h = kFnv1aOffset;
  for (const auto& f : files) {
    h = fnv1a(f.lexically_relative(dir).generic_string(), h);  // no syscalls: f lies under dir
    h = fnv1a(read_all(f), h);
  }
  return hex64(h);
}

// A file-name-safe class name: "teddy bear" -> "teddy_bear".
std::string file_safe(const std::string& name) {
  std::string s;
  for (char c : name) s += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return s.empty() ? "object" : s;
}

ordered_json object_json(const fusion::ObjectRecord& r, const std::string& ply_name) {
  ordered_json o;
  o["id"] = r.id;
  o["class"] = r.class_name;
  ordered_json hist = ordered_json::object();
  for (const auto& [name, vote] : r.class_histogram)
    hist[name] = {{"count", vote.count}, {"score_sum", vote.score_sum}};
  o["class_histogram"] = hist;
  o["score"] = r.mean_score;
  o["centroid"] = vec3_json(r.centroid);
  o["position"] = vec3_json(r.position);
  o["aabb"] = {{"min", vec3_json(r.aabb.min)}, {"max", vec3_json(r.aabb.max)}};
  ordered_json rot = ordered_json::array();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rot.push_back(r.obb.rotation(i, j));
  o["obb"] = {{"center", vec3_json(r.obb.center)},
              {"rotation", rot},
              {"half_extent", vec3_json(r.obb.half_extent)}};
  o["points"] = {
      {"raw", r.points_raw},
      {"voxel_filtered", r.points_voxel},
      {"outlier_filtered", r.points_filtered},
      {"support_strip", r.points_support},
      {"outlier_threshold", std::isfinite(r.outlier_threshold) ? ordered_json(r.outlier_threshold)
                                                               : ordered_json(nullptr)}};
  o["observation_count"] = r.observations;
  o["view_count"] = r.views;
  o["frames_detected"] = r.frames_detected;
  o["frames_in_view"] =
      r.frames_in_view >= 0 ? ordered_json(r.frames_in_view) : ordered_json(nullptr);
  o["first_seen"] = r.first_seen;
  o["last_seen"] = r.last_seen;
  o["track_ids"] = r.track_ids;
  o["ply"] = ply_name;
  ordered_json obs = ordered_json::array();
  for (const auto& l : r.provenance) {
    ordered_json e;
    e["timestamp"] = l.timestamp;
    e["track_id"] = l.track_id ? ordered_json(*l.track_id) : ordered_json(nullptr);
    e["class"] = l.class_name;
    e["score"] = l.score;
    e["keyframe"] = l.keyframe_index ? ordered_json(*l.keyframe_index) : ordered_json(nullptr);
    e["points"] = l.points;
    e["centroid"] = vec3_json(l.centroid_in_world);
    e["centroid_in_cam"] =
        l.centroid_in_cam ? vec3_json(*l.centroid_in_cam) : ordered_json(nullptr);
    e["why"] = l.created ? "new" : "match";
    e["p_id"] = l.p_id;
    e["distance_m"] = l.distance_m;
    e["overlap"] = l.overlap;
    e["p"] = l.score_p;
    obs.push_back(e);
  }
  o["observations"] = obs;
  ordered_json merges = ordered_json::array();
  for (const auto& mlink : r.merges)
    merges.push_back({{"absorbed", mlink.absorbed},
                      {"p_id", mlink.p_id},
                      {"distance_m", mlink.distance_m},
                      {"overlap", mlink.overlap},
                      {"p", mlink.score_p},
                      {"rule", mlink.part              ? "parts of one instance"
                               : mlink.fragment        ? "fragment in box"
                               : mlink.class_confusion ? "class confusion"
                                                       : "same class"}});
  o["merged"] = merges;
  return o;
}

// run.json "duplicates": the suspected duplicates and why the merge pass kept each pair apart.
ordered_json duplicates_json(const fusion::DuplicateReport& report,
                             const fusion::DuplicateOptions& options,
                             const fusion::ObjectMapOptions& map_options) {
  ordered_json pairs = ordered_json::array();
  for (const fusion::DuplicatePair& p : report.pairs) {
    const fusion::MergeVerdict& v = p.merge;
    pairs.push_back({{"a", p.a},
                     {"b", p.b},
                     {"class", p.class_name},
                     {"obb_overlap", p.obb_overlap},
                     {"surface_distance_m", p.surface_distance_m},
                     {"touching_share", p.touching_share},
                     {"merge",
                      {{"p_id", v.p_id},
                       {"distance_m", v.distance_m},
                       {"overlap", v.overlap},
                       {"score_p", v.score_p},
                       {"shared_frames", v.shared_frames},
                       {"smaller_frames", v.smaller_frames}}},
                     {"merge_refused", fusion::to_string(v.refused)},
                     {"merge_reason", fusion::describe_refusal(v, map_options)}});
  }
  return {{"touch_distance_m", options.touch_distance_m},
          {"obb_samples_per_axis", options.obb_samples_per_axis},
          {"min_obb_overlap", options.min_obb_overlap},
          {"pairs_checked", report.pairs_checked},
          {"count", report.pairs.size()},
          {"pairs", pairs}};
}

// A sighting of objects.json: a thing that moves by itself, where and when it was seen.
ordered_json sighting_json(const fusion::ObjectRecord& r) {
  return {{"id", r.id},
          {"class", r.class_name},
          {"score", r.mean_score},
          {"position", vec3_json(r.position)},
          {"aabb", {{"min", vec3_json(r.aabb.min)}, {"max", vec3_json(r.aabb.max)}}},
          {"first_seen", r.first_seen},
          {"last_seen", r.last_seen},
          {"frames", r.frames_detected},
          {"observation_count", r.observations},
          {"track_ids", r.track_ids},
          {"points", r.points_filtered}};
}

// run.json "inputs": the paths with their checksums, the camera and why it was chosen. The
// trajectory of a run on the dataset's own poses is the copy written into the run folder.
ordered_json inputs_json(const FuseOptions& options, const FuseInputs& inputs,
                         const FuseResult& result) {
  ordered_json dataset = {{"path", options.dataset.string()}, {"layout", result.layout}};
  if (!inputs.dataset.topics.empty()) dataset["topics"] = inputs.dataset.topics;
  if (result.layout == "tum") {
    dataset["rgb.txt"] = file_checksum(options.dataset / "rgb.txt");
    dataset["depth.txt"] = file_checksum(options.dataset / "depth.txt");
  } else {
    std::string names;
    for (const io::FramePair& f : inputs.dataset.frames)
      names += f.rgb_file.filename().string() + " " + f.depth_file.filename().string() + "\n";
    dataset["frames"] = hex64(fnv1a(names));
  }
  ordered_json trajectory;
  if (options.trajectory.empty()) {
    const std::string text = io::format_trajectory(inputs.trajectory);
    trajectory = {{"path", (options.out / kDatasetTrajectory).string()},
                  {"from", "dataset"},
                  {"source", inputs.trajectory.source},
                  {"checksum", hex64(fnv1a(text))}};
  } else {
    trajectory = {{"path", options.trajectory.string()},
                  {"checksum", file_checksum(options.trajectory)}};
  }
  return {{"dataset", dataset},
          {"trajectory", trajectory},
          {"segmentation",
           {{"path", options.segmentation.string()},
            {"format", result.seg_format},
            {"checksum", folder_checksum(options.segmentation)}}},
          {"camera", nlohmann::ordered_json::parse(io::camera_json(result.camera))},
          {"camera_reason", result.camera_reason}};
}

std::size_t mesh_triangles(const std::vector<ObjectMesh>& meshes) {
  std::size_t n = 0;
  for (const ObjectMesh& m : meshes) n += m.model.mesh.triangles.size();
  return n;
}

// run.json "counts": per stage.
ordered_json counts_json(const FuseInputs& inputs, const FuseResult& result) {
  return {
      {"frames", result.frames},
      {"frames_with_pose", result.keyframes.frames_with_pose},
      {"keyframe_mode", result.keyframes.mode},
      {"keyframe_mode_reason", result.keyframes.reason},
      {"keyframes", result.keyframes.keyframes.size()},
      {"keyframes_with_segmentation", inputs.with_seg},
      {"instances", result.instances_seen},
      {"instances_below_min_score", result.instances_skipped_score},
      {"instances_mask_from_box", result.instances_from_box},
      {"instances_mask_refined", result.instances_refined},
      {"instances_duplicate", result.instances_duplicate},
      {"mask_pixels_removed", result.mask_pixels_removed},
      {"instances_depth_gated", result.instances_depth_gated},
      {"depth_gate_pixels_removed", result.depth_gate_pixels_removed},
      {"instances_without_points", result.instances_empty},
      {"instances_bleed", result.instances_bleed},
      {"instances_spanning", result.instances_spanning},
      {"observations", result.observations},
      {"objects_before_confirmation", result.objects_total},
      {"objects_below_detected_share", result.objects_below_share},
      {"objects_confirmed", result.objects.size()},
      {"sightings", result.sightings.size()},
      {"merges", result.merges.size()},
      {"objects_split", result.splits.size()},
      {"objects_cut_for_size", result.oversize.size()},
      {"objects_named_for_size", result.renamed.size()},
      {"objects_joined_as_parts", result.part_joins.size()},
      {"object_meshes", std::count_if(result.object_meshes.begin(), result.object_meshes.end(),
                                      [](const ObjectMesh& m) { return !m.model.mesh.empty(); })},
      {"object_mesh_triangles", mesh_triangles(result.object_meshes)},
      {"scene_mesh_vertices", result.scene_mesh.mesh.vertices.size()},
      {"scene_mesh_triangles", result.scene_mesh.mesh.triangles.size()}};
}

// run.json "points": Table 6, the point counts and their reductions. The paper's Table 6 figure
// is reduction_objects_vs_dense (the objects-only map against the dense map); eq 18's own is
// reduction_eq18 (voxel-filtered -> outlier-filtered object points).
ordered_json points_json(const FuseResult& result, const MapPoints& maps) {
  const auto reduction = [](double before, double after) {
    return before > 0 ? 1.0 - after / before : 0.0;
  };
  return {
      {"dense_back_projected", result.dense_points_raw},
      {"dense_map", result.dense_points_map},
      {"dense_pruned", result.dense_voxels_pruned},
      {"dense_sightings", result.dense_voxels_of_sightings},
      {"objects_raw", result.object_points_raw},
      {"objects_voxel_filtered", result.object_points_voxel},
      {"objects_outlier_filtered", result.object_points_filtered},
      {"semantic_map", maps.semantic},
      {"objects_map", maps.objects},
      {"reduction_objects_voxel", reduction(result.object_points_raw, result.object_points_voxel)},
      {"reduction_objects_total",
       reduction(result.object_points_raw, result.object_points_filtered)},
      {"reduction_dense", reduction(result.dense_points_raw, result.dense_points_map)},
      {"reduction_eq18", reduction(result.object_points_voxel, result.object_points_filtered)},
      {"reduction_objects_vs_dense", reduction(result.dense_points_map, maps.objects)}};
}

// run.json "performance": time per stage and memory; the only part of the run folder that differs
// between two runs of the same inputs.
ordered_json performance_json(const FuseResult& result) {
  const auto& keyframes = result.keyframes.keyframes;
  ordered_json perf;
  for (const auto& t : result.times) perf["seconds"][t.stage] = t.seconds;
  perf["seconds"]["total"] = result.seconds_total;
  perf["ms_per_keyframe"] =
      keyframes.empty() ? 0.0 : 1000.0 * result.seconds_total / keyframes.size();
  perf["peak_rss_mb"] = result.peak_rss_kb / 1024.0;
  perf["threads"] = result.threads;
  return perf;
}

}  // namespace

ordered_json write_maps(const FuseOptions& options, const fs::path& dir,
                        const io::PlyWriteOptions& ply, const DenseCloud& dense_cloud,
                        const FuseResult& result, MapPoints& points) {
  points.semantic = dense_cloud.cloud.size();
  std::vector<Rgb> record_color(result.objects.size());
  for (std::size_t i = 0; i < result.objects.size(); ++i)
    record_color[i] = fusion::class_color(result.objects[i].class_name);
  // Both read dense_cloud and neither changes it; declared after it, they are joined before it
  // goes, even when an exception unwinds.
  std::future<void> dense_write_future, semantic_future;
  if (options.dense_map) {
    dense_write_future = std::async(
        std::launch::async, [&] { io::write_ply(dir / "map_dense.ply", dense_cloud.cloud, ply); });
    semantic_future = std::async(std::launch::async, [&] {
      const std::vector<Rgb> colors =
          semantic_colors(dense_cloud, options.map_voxel_m, result.objects, record_color);
      io::write_ply(dir / "map_semantic.ply", dense_cloud.cloud, colors, ply);
    });
  }
  PointCloud objects_only;
  for (std::size_t i = 0; i < result.objects.size(); ++i) {
    if (!result.objects[i].confirmed) continue;
    for (const Vec3f& p : result.objects[i].cloud.points)
      objects_only.push_back(p, record_color[i]);
  }
  points.objects = objects_only.size();
  io::write_ply(dir / "map_objects.ply", objects_only, ply);
  objects_only = PointCloud();
  io::create_output_folders(dir / "objects");
  ordered_json objects_json = ordered_json::array();
  for (std::size_t i = 0; i < result.objects.size(); ++i) {
    const fusion::ObjectRecord& r = result.objects[i];
    const std::string stem = "objects/" + std::to_string(r.id) + "_" + file_safe(r.class_name);
    io::write_ply(dir / (stem + ".ply"), r.cloud, ply);
    objects_json.push_back(object_json(r, stem + ".ply"));
    if (i < result.object_meshes.size()) {
      const ObjectMesh& m = result.object_meshes[i];
      ordered_json mesh_json = {{"file", nullptr},
                                {"vertices", m.model.mesh.vertices.size()},
                                {"triangles", m.model.mesh.triangles.size()},
                                {"voxel_m", m.model.voxel_m},
                                {"views", m.views}};
      if (!m.model.mesh.empty()) {
        mesh_json["file"] = stem + "_mesh.ply";
        io::write_mesh_ply(dir / (stem + "_mesh.ply"), m.model.mesh, ply);
      }
      objects_json.back()["mesh"] = mesh_json;
    }
  }
  if (!result.scene_mesh.mesh.empty())
    io::write_mesh_ply(dir / "map_mesh.ply", result.scene_mesh.mesh, ply);
  if (options.dense_map) {
    dense_write_future.get();
    semantic_future.get();
  }
  return objects_json;
}

void write_objects_json(const fs::path& dir, const ordered_json& objects_json,
                        const std::vector<fusion::ObjectRecord>& sightings,
                        const scene::SceneGraph& scene) {
  ordered_json doc;
  doc["schema_version"] = 1;
  doc["generator"] = std::string("objmap ") + objmap::version();
  doc["frame"] = "world";
  doc["units"] = "metres";
  doc["objects"] = objects_json;
  doc["sightings"] = ordered_json::array();
  for (const fusion::ObjectRecord& r : sightings) doc["sightings"].push_back(sighting_json(r));
  add_scene_json(scene, doc);
  io::write_file_atomic(dir / "objects.json", doc.dump(2) + "\n");
}

void write_run_json(const fs::path& dir, const FuseOptions& options, const FuseInputs& inputs,
                    const fusion::ObjectMapOptions& object_options, const MapPoints& maps,
                    const FuseResult& result) {
  FuseOptions echo = options;
  ordered_json run;
  run["schema_version"] = 1;
  run["generator"] = std::string("objmap ") + objmap::version();
  run["command"] = "fuse";
  run["inputs"] = inputs_json(options, inputs, result);
  run["options"] = ordered_json::parse(config_to_json(fuse_config_fields(echo)));
  run["counts"] = counts_json(inputs, result);
  if (result.detected_share_bar > 0.0)
    run["confirmation"] = {{"detected_share_bar", result.detected_share_bar},
                           {"objects_below", result.objects_below_share}};
  run["points"] = points_json(result, maps);
  run["duplicates"] = duplicates_json(result.duplicates, options.duplicates, object_options);
  run["scene"] = scene_run_json(result.scene);
  run["performance"] = performance_json(result);
  io::write_file_atomic(dir / "run.json", run.dump(2) + "\n");
}

void write_dataset_trajectory(const fs::path& dir, const FuseOptions& options,
                              const FuseInputs& inputs, const FuseResult& result) {
  io::write_trajectory(dir / kDatasetTrajectory, inputs.trajectory,
                       "the camera poses of " + options.dataset.string() + " (" + result.layout +
                           " layout: " + inputs.trajectory.source + ")");
}

}  // namespace objmap::pipeline
