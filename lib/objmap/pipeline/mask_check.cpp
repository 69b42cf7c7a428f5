#include "objmap/pipeline/mask_check.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "objmap/io/ply.h"
#include "objmap/io/run_path.h"
#include "objmap/io/trajectory.h"
#include "objmap/io/tum_dataset.h"
#include "objmap/pipeline/run_json.h"
#include "objmap/segmentation/box_mask.h"
#include "objmap/segmentation/read.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using run_json::field;
using run_json::json;

void MaskCheckOptions::check() const {
  require(std::isfinite(depth_tolerance_m) && depth_tolerance_m >= 0,
          "MaskCheckOptions.depth_tolerance_m",
          "must be finite and >= 0, got " + std::to_string(depth_tolerance_m));
  require(std::isfinite(depth_tolerance_per_m) && depth_tolerance_per_m >= 0,
          "MaskCheckOptions.depth_tolerance_per_m",
          "must be finite and >= 0, got " + std::to_string(depth_tolerance_per_m));
}

MaskViewCount count_inside_mask(const PointCloud& points_in_world, const Pose& world_from_cam,
                                const Camera& camera, const cv::Mat& depth,
                                const segmentation::Mask& mask, const MaskCheckOptions& options) {
  require(depth.type() == CV_16UC1 && depth.cols == camera.width && depth.rows == camera.height &&
              mask.width == camera.width && mask.height == camera.height,
          "count_inside_mask", "the depth image and the mask must have the camera's size");
  MaskViewCount count;
  const Pose cam_from_world = world_from_cam.inverse();
  for (const Vec3f& p : points_in_world.points) {
    const Vec3 point_in_cam = cam_from_world * p.cast<double>();
    if (point_in_cam.z() <= 0.01) continue;
    const Eigen::Vector2d px = camera.project(point_in_cam);
    const int u = static_cast<int>(std::floor(px.x())), v = static_cast<int>(std::floor(px.y()));
    if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) continue;
    const std::uint16_t raw = depth.at<std::uint16_t>(v, u);
    if (raw == 0) continue;  // a hole: no evidence either way
    const double z = raw / camera.depth_factor;
    const double tolerance =
        options.depth_tolerance_m + options.depth_tolerance_per_m * point_in_cam.z();
    if (std::abs(z - point_in_cam.z()) > tolerance) continue;  // occluded, or not on the surface
    ++count.visible;
    count.inside += mask.at(u, v) != 0;
  }
  return count;
}

namespace {

// One observation of objects.json: where to find its instance again.
struct ObservationRef {
  std::size_t object = 0;  // index into the result's objects
  double timestamp = 0.0;
  std::string class_name;
  double score = 0.0;
  std::optional<int> track_id;
};

// The run's inputs, as fuse used them.
struct RunInputs {
  Camera camera;
  io::Dataset dataset;
  Trajectory trajectory;
  segmentation::Segmentation segmentation;
  segmentation::BoxMaskOptions box_mask;
  double max_diff_s = 0.02;
};

RunInputs read_inputs(const fs::path& run) {
  const fs::path file = run / "run.json";
  require(fs::exists(file), run.string(), "no run.json; expected a folder written by objmap fuse");
  const json doc = run_json::read_file(file);
  RunInputs in;
  in.camera = run_json::camera(doc, file);
  in.max_diff_s = field<json>(doc, "options", file, "").value("max_diff_s", 0.02);
  in.dataset = run_json::dataset(doc, file);
  in.trajectory = io::read_trajectory(run_json::input_path(doc, file, "trajectory"));
  segmentation::ReadOptions read;
  read.format = field<std::string>(
      field<json>(field<json>(doc, "inputs", file, ""), "segmentation", file, "inputs"), "format",
      file, "inputs.segmentation");
  read.image_width = in.camera.width;
  read.image_height = in.camera.height;
  in.segmentation =
      segmentation::read_segmentation(run_json::input_path(doc, file, "segmentation"), read);
  return in;
}

// objects.json: each object (id, class, points from its PLY) and its observations.
std::vector<ObservationRef> read_objects(const fs::path& run, MaskCheckResult& result,
                                         std::vector<PointCloud>& clouds) {
  const fs::path file = run / "objects.json";
  const json doc = run_json::read_file(file);
  std::vector<ObservationRef> refs;
  const json objects = field<json>(doc, "objects", file, "");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const json& o = objects[i];
    ObjectMaskCheck check;
    check.id = field<int>(o, "id", file, "objects[]");
    check.class_name = field<std::string>(o, "class", file, "objects[]");
    const std::string where = "objects[" + std::to_string(i) + "]";
    const std::string ply = field<std::string>(o, "ply", file, where);
    clouds.push_back(io::read_ply(io::path_in_run(run, ply, file, where + ".ply")));
    for (const json& l : field<json>(o, "observations", file, "objects[]")) {
      ObservationRef ref;
      ref.object = result.objects.size();
      ref.timestamp = field<double>(l, "timestamp", file, "objects[].observations[]");
      ref.class_name = field<std::string>(l, "class", file, "objects[].observations[]");
      ref.score = field<double>(l, "score", file, "objects[].observations[]");
      if (l.contains("track_id") && l["track_id"].is_number_integer())
        ref.track_id = l["track_id"].get<int>();
      refs.push_back(ref);
    }
    result.objects.push_back(check);
  }
  return refs;
}

// The instance of `frame` an observation came from: same class, score (to 1e-6) and track id.
const segmentation::Instance* find_instance(const segmentation::FrameSegmentation& frame,
                                            const ObservationRef& ref) {
  for (const auto& instance : frame.instances)
    if (instance.class_name == ref.class_name && std::abs(instance.score - ref.score) < 1e-6 &&
        instance.track_id == ref.track_id)
      return &instance;
  return nullptr;
}

}  // namespace

MaskCheckResult check_run_masks(const fs::path& run, const MaskCheckOptions& options) {
  options.check();
  // 1. The run's inputs and objects.
  const RunInputs in = read_inputs(run);
  MaskCheckResult result;
  std::vector<PointCloud> clouds;
  const std::vector<ObservationRef> refs = read_objects(run, result, clouds);
  std::map<double, std::vector<const ObservationRef*>> by_time;
  for (const auto& ref : refs) by_time[ref.timestamp].push_back(&ref);

  // 2. Keyframe by keyframe: its depth, pose and segmentation frame; each observation's mask.
  io::PoseLookupOptions lookup;
  lookup.max_diff_s = in.max_diff_s;
  lookup.interpolate = true;
  for (const auto& [t, observations] : by_time) {
    const auto frame =
        std::find_if(in.dataset.frames.begin(), in.dataset.frames.end(),
                     [&](const io::FramePair& f) { return std::abs(f.rgb_timestamp - t) < 1e-4; });
    const auto seg = std::find_if(
        in.segmentation.frames.begin(), in.segmentation.frames.end(),
        [&](const segmentation::FrameSegmentation& f) { return std::abs(f.timestamp - t) < 1e-3; });
    const std::optional<Pose> pose = io::lookup_pose(in.trajectory, t, lookup);
    if (frame == in.dataset.frames.end() || seg == in.segmentation.frames.end() || !pose) {
      result.unmatched_observations += observations.size();
      continue;
    }
    const cv::Mat depth = io::read_frame_depth(in.dataset, *frame, in.camera);
    for (const ObservationRef* ref : observations) {
      const segmentation::Instance* instance = find_instance(*seg, *ref);
      if (!instance) {
        ++result.unmatched_observations;
        continue;
      }
      segmentation::Mask box_mask;
      if (!instance->mask)
        box_mask = segmentation::mask_from_box(instance->bbox, depth, in.camera, in.box_mask).mask;
      const segmentation::Mask& mask = instance->mask ? *instance->mask : box_mask;
      if (mask.empty()) continue;
      const MaskViewCount c =
          count_inside_mask(clouds[ref->object], *pose, in.camera, depth, mask, options);
      ObjectMaskCheck& object = result.objects[ref->object];
      ++object.keyframes;
      object.visible += c.visible;
      object.inside += c.inside;
    }
  }

  // 3. The shares.
  for (ObjectMaskCheck& object : result.objects) {
    object.share = object.visible ? static_cast<double>(object.inside) / object.visible : 0.0;
    result.visible += object.visible;
    result.inside += object.inside;
  }
  result.share = result.visible ? static_cast<double>(result.inside) / result.visible : 0.0;
  return result;
}

}  // namespace objmap::pipeline
