#include "objmap/pipeline/diff.h"

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "objmap/core/clock.h"
#include "objmap/core/error.h"
#include "objmap/core/json_vec.h"
#include "objmap/core/version.h"
#include "objmap/io/atomic.h"
#include "objmap/io/json_file.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/ply.h"
#include "objmap/io/run_path.h"
#include "objmap/io/scene_json.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/keyframes.h"
#include "objmap/pipeline/run_json.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

namespace {

// An object's points beyond this many are thinned evenly: the evidence tests a few dozen anyway.
constexpr std::size_t kMaxObjectPoints = 400;

// A diff folder: diff.json marks an earlier one (io::require_replaceable).
const io::OutputKind kDiffFolder{"diff", {"diff.json"}, false};

std::vector<Vec3f> thinned(const PointCloud& cloud) {
  if (cloud.size() <= kMaxObjectPoints) return cloud.points;
  std::vector<Vec3f> out;
  const double step = static_cast<double>(cloud.size()) / kMaxObjectPoints;
  for (std::size_t i = 0; i < kMaxObjectPoints; ++i)
    out.push_back(cloud.points[static_cast<std::size_t>(i * step)]);
  return out;
}

// The views of the run: the keyframes fuse would take (recording + trajectory of run.json).
std::vector<Pose> read_views(const fs::path& run, Camera& camera) {
  const fs::path file = run / "run.json";
  require(fs::exists(file), run.string(), "no run.json; expected a run folder of objmap fuse");
  const run_json::json doc = run_json::read_file(file);
  camera = run_json::camera(doc, file);
  const io::Dataset dataset = run_json::dataset(doc, file);
  const Trajectory trajectory = io::read_trajectory(run_json::input_path(doc, file, "trajectory"));
  const KeyframeSelection selection = select_keyframes(dataset, trajectory, KeyframeOptions{});
  std::vector<Pose> views;
  for (const Keyframe& k : selection.keyframes) views.push_back(k.world_from_cam);
  return views;
}

ordered_json matrix_json(const Pose& p) {
  ordered_json m = ordered_json::array();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.push_back(p.matrix()(r, c));
  return m;
}

ordered_json evidence_json(const std::optional<change::PlaceEvidence>& e) {
  if (!e) return nullptr;
  return {{"views", e->views},       {"sightlines", e->sightlines},
          {"surface", e->surface},   {"seen_through", e->seen_through},
          {"occluded", e->occluded}, {"surface_share", e->surface_share()}};
}

ordered_json side_json(const std::optional<int>& id, const std::string& cls,
                       const std::optional<Vec3>& position, const std::optional<Vec3>& in_before) {
  if (!id) return nullptr;
  ordered_json j = {{"id", *id}, {"class", cls}, {"position", vec3_json(*position)}};
  if (in_before) j["position_in_before"] = vec3_json(*in_before);
  return j;
}

ordered_json finite_or_null(double v) { return std::isfinite(v) ? ordered_json(v) : nullptr; }

ordered_json registration_json(const change::Registration& r) {
  return {{"source", r.source},
          {"before_from_after", matrix_json(r.before_from_after)},
          {"yaw_deg", r.yaw_deg},
          {"tilt_deg", r.tilt_deg},
          {"translation_m", vec3_json(r.before_from_after.translation())},
          {"common_objects", r.common_objects},
          {"coarse_rms_m", r.coarse_rms_m},
          {"hypotheses", r.hypotheses},
          {"fitness", r.fitness},
          {"fitness_both", r.fitness_both},
          {"rms_m", r.rms_m},
          {"icp_points", r.icp_points},
          {"sigma_translation_m", finite_or_null(r.sigma_translation_m)},
          {"sigma_yaw_deg", finite_or_null(r.sigma_yaw_deg)},
          {"uncertainty_at_objects_m", finite_or_null(r.uncertainty_at_objects_m)},
          {"uncertainty_yaw_deg", finite_or_null(r.uncertainty_yaw_deg)}};
}

}  // namespace

void DiffOptions::check() const {
  require(!before.empty(), "--before", "missing; expected a run folder of objmap fuse");
  require(!after.empty(), "--after", "missing; expected a run folder of objmap fuse");
  require(!out.empty(), "--out", "missing; expected a folder for diff.json");
  registration.check();
  classify.check();
}

change::Visit read_visit(const fs::path& run) {
  require(fs::is_directory(run), run.string(),
          "not a folder; expected a run folder of objmap fuse");
  change::Visit v;
  v.name = run.string();
  const fs::path objects_file = run / "objects.json";
  // Up and the gravity frame first: a run without them cannot be registered in 4 DoF.
  const io::SceneDescription scene = io::read_map_scene(objects_file);
  v.up_in_world = scene.up;
  v.gravity_from_world = scene.gravity_from_world;
  const std::vector<io::MappedObject> objects = io::read_objects_json(objects_file);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const io::MappedObject& m = objects[i];
    change::VisitObject o;
    o.id = m.id;
    o.class_name = m.class_name;
    o.position = m.position;
    o.half_extent = m.obb.half_extent;
    if (!m.ply.empty()) {
      const fs::path ply =
          io::path_in_run(run, m.ply, objects_file, "objects[" + std::to_string(i) + "].ply");
      if (fs::exists(ply)) {
        const PointCloud cloud = io::read_ply(ply);
        o.points = thinned(cloud);
        if (cloud.has_colors() && !cloud.empty()) {
          Vec3 sum = Vec3::Zero();
          for (const Rgb& c : cloud.colors) sum += Vec3(c.r, c.g, c.b);
          o.colour = sum / static_cast<double>(cloud.size());
        }
      }
    }
    v.objects.push_back(std::move(o));
  }
  const fs::path dense = run / "map_dense.ply";
  require(fs::exists(dense), dense.string(), "missing; expected the dense map objmap fuse writes");
  v.dense = io::read_ply(dense);
  v.world_from_cam = read_views(run, v.camera);
  return v;
}

Pose read_align_file(const fs::path& file) {
  const nlohmann::json doc = io::read_json_file(file, "cannot open; expected a JSON file");
  const bool in_diff = doc.is_object() && doc.contains("registration");
  const nlohmann::json& node = in_diff ? doc["registration"] : doc;
  const std::string field = in_diff ? "registration.before_from_after" : "before_from_after";
  require(node.is_object() && node.contains("before_from_after") &&
              node["before_from_after"].is_array() && node["before_from_after"].size() == 16,
          file.string() + ": " + field,
          "missing or not 16 numbers; expected a row-major 4x4 matrix");
  Eigen::Matrix4d m;
  for (int k = 0; k < 16; ++k) {
    const nlohmann::json& x = node["before_from_after"][k];
    require(x.is_number(), file.string() + ": " + field, "has a non-number; expected 16 numbers");
    m(k / 4, k % 4) = x.get<double>();
  }
  const Eigen::Matrix3d r = m.block<3, 3>(0, 0);
  require((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-4 &&
              std::abs(r.determinant() - 1.0) < 1e-4 &&
              m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)),
          file.string() + ": " + field,
          "is not a rigid transform; expected a rotation and a translation");
  Pose p = Pose::Identity();
  p.matrix() = m;
  return p;
}

std::string diff_json(const DiffOptions& options, const DiffResult& result) {
  ordered_json doc;
  doc["schema_version"] = 1;
  doc["generator"] = std::string("objmap ") + objmap::version();
  doc["before"] = options.before.string();
  doc["after"] = options.after.string();
  doc["frame"] = "before world; after positions also as given in the after world";
  doc["registration"] = registration_json(result.registration);
  ordered_json counts;
  for (change::Status s :
       {change::Status::kUnchanged, change::Status::kMoved, change::Status::kRemoved,
        change::Status::kAdded, change::Status::kChangedClass, change::Status::kNotSeenAgain,
        change::Status::kNotSeenBefore})
    counts[change::status_name(s)] = result.changes.count(s);
  doc["counts"] = counts;
  ordered_json left_out = ordered_json::array();
  for (const auto& [cls, n] : result.changes.left_out)
    left_out.push_back({{"class", cls}, {"count", n}});
  doc["left_out"] = left_out;
  ordered_json objects = ordered_json::array();
  for (const change::ObjectChange& c : result.changes.objects) {
    const bool pair = c.before_id && c.after_id;
    objects.push_back(
        {{"status", change::status_name(c.status)},
         {"before", side_json(c.before_id, c.before_class, c.before_position, std::nullopt)},
         {"after",
          side_json(c.after_id, c.after_class, c.after_position, c.after_position_in_before)},
         {"distance_m", pair ? ordered_json(c.distance_m) : ordered_json(nullptr)},
         {"displacement_m",
          c.status == change::Status::kMoved ? vec3_json(c.displacement) : ordered_json(nullptr)},
         {"evidence",
          {{"after_visit", evidence_json(c.evidence_after)},
           {"before_visit", evidence_json(c.evidence_before)}}},
         {"why", c.why}});
  }
  doc["objects"] = objects;
  return doc.dump(2) + "\n";
}

DiffResult run_diff(const DiffOptions& options) {
  options.check();
  io::require_not_an_input(
      {"--out", options.out},
      {{"--before", options.before}, {"--after", options.after}, {"--align", options.align}});
  io::require_replaceable(options.out, kDiffFolder);
  DiffResult result;
  // 1. Read both visits: objects, up, dense map, views.
  auto t0 = Clock::now();
  const change::Visit before = read_visit(options.before);
  const change::Visit after = read_visit(options.after);
  result.before_objects = before.objects.size();
  result.after_objects = after.objects.size();
  result.before_dense_points = before.dense.size();
  result.after_dense_points = after.dense.size();
  result.before_views = before.world_from_cam.size();
  result.after_views = after.world_from_cam.size();
  result.seconds_read = seconds_since(t0);
  // 2. Register the after world to the before world (or take the given transform).
  t0 = Clock::now();
  result.registration =
      options.align.empty()
          ? change::register_visits(before, after, options.registration)
          : change::score_registration(before, after, read_align_file(options.align),
                                       options.registration);
  result.seconds_register = seconds_since(t0);
  if (!result.registration.credible)
    throw InputError(options.before.string() + " and " + options.after.string(),
                     "no credible registration: " + result.registration.why +
                         "; expected two visits of the same place (or give --align FILE)");
  // 3. Classify every object of both maps.
  t0 = Clock::now();
  result.changes = change::classify_changes(before, after, result.registration.before_from_after,
                                            options.classify);
  result.seconds_classify = seconds_since(t0);
  // 4. DIFF/diff.json, written atomically.
  io::create_output_folders(options.out);
  io::write_file_atomic(options.out / "diff.json", diff_json(options, result));
  return result;
}

}  // namespace objmap::pipeline
