// The scene step through `objmap fuse` (docs/scene.md): the up direction, the support
// surfaces and the objects' `on` relations against objmap synth's ground truth with the trajectory
// in the SLAM frame (the first camera's, as ORB-SLAM2 writes it), and the up direction on real TUM
// sequences whose trajectory is given in their first camera's frame.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "fuse_helpers.h"
#include "objmap/io/trajectory.h"
#include "objmap/segmentation/class_sizes.h"

namespace objmap::test {
namespace {

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

Eigen::Vector3d up_of(const fs::path& run) {
  const nlohmann::json doc = read_json(run / "objects.json");
  const auto& u = doc.at("up_in_world");
  return {u[0].get<double>(), u[1].get<double>(), u[2].get<double>()};
}

// `objmap fuse` of a dataset folder with `trajectory` and the segmentation folder `seg`, cached.
fs::path fuse_cached(const std::string& key, const fs::path& data, const fs::path& trajectory,
                     const fs::path& seg, RunResult* result) {
  return cached_output(key,
                       {"fuse", "--dataset", data.string(), "--trajectory", trajectory.string(),
                        "--segmentation", seg.string(), "--out", "{OUT}"},
                       result);
}

// The ground truth moved into its first camera's frame (T0⁻¹ · T_i), written to `out`; returns
// the rotation from the ground truth's world to that frame.
Eigen::Matrix3d first_camera_frame(const fs::path& groundtruth, const fs::path& out) {
  Trajectory t = io::read_trajectory(groundtruth);
  const Pose first_from_world = t.poses.front().world_from_cam.inverse();
  for (auto& p : t.poses) p.world_from_cam = first_from_world * p.world_from_cam;
  io::write_trajectory(out, t);
  return first_from_world.linear();
}

// A real sequence fused with its ground truth moved into its first camera's frame (cached as
// `key`): the run folder (absent when the fuse failed, `why` says why) and the true up in it.
struct FirstCameraRun {
  fs::path run;
  RunResult why;
  Eigen::Vector3d truth;  // the world's +z in the first camera's frame
  Eigen::Matrix3d first_from_world;
};
FirstCameraRun fuse_in_first_camera_frame(const std::string& key, const fs::path& data,
                                          const std::string& segmentation) {
  const fs::path trajectory = fs::path(::testing::TempDir()) / (key + ".txt");
  FirstCameraRun r;
  r.first_from_world = first_camera_frame(data / "groundtruth.txt", trajectory);
  r.truth = r.first_from_world * Eigen::Vector3d::UnitZ();
  r.run = fuse_cached(key, data, trajectory, data / segmentation, &r.why);
  return r;
}

// `trajectory` moved into another world frame (new = moved · old) and written to `out` with
// `decimals` decimals, as a SLAM system might write it.
void write_moved(const fs::path& trajectory, const fs::path& out, const Eigen::Isometry3d& moved,
                 int decimals) {
  const Trajectory t = io::read_trajectory(trajectory);
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  char line[256];
  for (const auto& p : t.poses) {
    const Eigen::Isometry3d m = moved * p.world_from_cam;
    const Eigen::Vector3d x = m.translation();
    const Eigen::Quaterniond q(m.linear());
    std::snprintf(line, sizeof line, "%.6f %.*f %.*f %.*f %.*f %.*f %.*f %.*f\n", p.timestamp,
                  decimals, x.x(), decimals, x.y(), decimals, x.z(), decimals, q.x(), decimals,
                  q.y(), decimals, q.z(), decimals, q.w());
    text += line;
  }
  write_text(out, text);
}

// The ups (brought back into the ground truth's frame) of `data` fused with its z-up ground truth
// as it is and moved by 5 random rigid motions, written with 5, 6, 7, 8 and 9 decimals.
std::vector<Eigen::Vector3d> ups_in_moved_frames(const fs::path& data, const fs::path& seg,
                                                 const std::vector<std::string>& extra) {
  TempDir tmp;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<Eigen::Vector3d> ups;
  for (int k = -1; k < 5; ++k) {
    Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
    fs::path trajectory = data / "groundtruth.txt";
    if (k >= 0) {
      const Eigen::Vector4d q(uniform(rng), uniform(rng), uniform(rng), uniform(rng));
      moved.linear() = Eigen::Quaterniond(q.normalized()).toRotationMatrix();
      moved.translation() = 5.0 * Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
      trajectory = tmp / ("moved" + std::to_string(k) + ".txt");
      write_moved(data / "groundtruth.txt", trajectory, moved, 5 + k);
    }
    const fs::path run = tmp / ("run" + std::to_string(k + 1));
    std::vector<std::string> args = {
        "fuse",           "--dataset",  data.string(), "--trajectory", trajectory.string(),
        "--segmentation", seg.string(), "--out",       run.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const RunResult r = run_objmap(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    if (r.exit_code != 0) return {};
    ups.push_back(moved.linear().transpose() * up_of(run));
  }
  return ups;
}

TEST(FuseScene, SyntheticScenesInTheSlamFrameUpSurfacesAndOnRelations) {
  // Seeds 1-3 fused with estimated_slam_frame.txt (the drifting estimate in the first camera's
  // frame: y down, z forward); eval scene brings the map into the ground truth's frame by the
  // trajectories. The bounds: up within 2 deg, floor and table found within 2 cm, `on` precision
  // and recall >= 0.9 over the seeds.
  int predicted = 0, relevant = 0, correct = 0;
  for (const char* seed : {"1", "2", "3"}) {
    RunResult why;
    const fs::path scene = cached_output(std::string("seed") + seed + "-motion-scene",
                                         {"synth", "--out", "{OUT}", "--seed", seed}, &why);
    ASSERT_TRUE(fs::exists(scene)) << why.err;
    const fs::path slam = scene / "estimated_slam_frame.txt";
    const fs::path run = fuse_cached(std::string("seed") + seed + "-slam-frame-fuse", scene, slam,
                                     scene / "segmentation", &why);
    ASSERT_TRUE(fs::exists(run)) << why.err;
    TempDir tmp;
    const RunResult eval = run_objmap({"eval", "scene", "--run", run.string(), "--gt",
                                       (scene / "objects_gt.json").string(), "--gt-trajectory",
                                       (scene / "groundtruth.txt").string(), "--trajectory",
                                       slam.string(), "--json", (tmp / "scene.json").string()});
    ASSERT_EQ(eval.exit_code, 0) << eval.err;
    const nlohmann::json e = read_json(tmp / "scene.json");
    EXPECT_LT(e["up_angle_deg"].get<double>(), 2.0) << "seed " << seed;
    EXPECT_EQ(e["surfaces"]["found"].get<int>(), 2) << "seed " << seed << ": floor and table";
    EXPECT_LE(e["surfaces"]["height_abs_error_m"]["max"].get<double>(), 0.02) << "seed " << seed;
    predicted += e["on"]["predicted"].get<int>();
    relevant += e["on"]["relevant"].get<int>();
    correct += e["on"]["correct"].get<int>();
  }
  ASSERT_GT(predicted, 0);
  EXPECT_GE(static_cast<double>(correct) / predicted, 0.9) << "on precision";
  EXPECT_GE(static_cast<double>(correct) / relevant, 0.9) << "on recall";
}

TEST(FuseScene, Fr3CabinetInItsFirstCameraFrameFindsUp) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr3_cabinet_58kf");
  const FirstCameraRun r =
      fuse_in_first_camera_frame("fr3-cabinet-first-camera", data, "boxes_yolov2");
  ASSERT_TRUE(fs::exists(r.run)) << r.why.err;
  EXPECT_LT(angle_deg(up_of(r.run), r.truth), 1.0);  // 0.07 deg measured
  // The hall's floor is the floor (26 m2, no table however few objects stand on it).
  const nlohmann::json doc = read_json(r.run / "objects.json");
  ASSERT_FALSE(doc["surfaces"].empty());
  EXPECT_EQ(doc["surfaces"][0]["label"], "floor");
  EXPECT_GT(doc["surfaces"][0]["area_m2"].get<double>(), 10.0);
}

TEST(FuseScene, Fr1RpyWithTheVisualOdometryEstimateFindsUp) {
  // vo_estimate_first100.txt is in its first camera's frame. The camera mostly turns in place, so
  // the SE(3) that aligns the estimate's positions to the ground truth's is ill-conditioned (it
  // puts the truth 27 deg away); the truth here is the ground truth's +z carried by the rotation
  // that aligns the two trajectories' orientations (the chordal mean of R_gt · R_estᵀ).
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_rpy_every4");
  const Trajectory gt = io::read_trajectory(data / "groundtruth.txt");
  const Trajectory est = io::read_trajectory(data / "vo_estimate_first100.txt");
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  int pairs = 0;
  for (const auto& e : est.poses) {
    const auto g = io::lookup_pose(gt, e.timestamp, {0.02});
    if (!g) continue;
    sum += g->linear() * e.world_from_cam.linear().transpose();
    ++pairs;
  }
  ASSERT_GT(pairs, 50);
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d gt_from_est = svd.matrixU() * svd.matrixV().transpose();
  const Eigen::Vector3d truth = gt_from_est.transpose() * Eigen::Vector3d::UnitZ();
  RunResult why;
  const fs::path run = fuse_cached("fr1-rpy-vo-first100", data, data / "vo_estimate_first100.txt",
                                   data / "detections_yolofastest", &why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  EXPECT_LT(angle_deg(up_of(run), truth), 1.5);  // 0.89 deg measured
}

TEST(FuseScene, Fr1RpyGroundTruthDeskIsATableWithTheKeyboardAndMiceOnIt) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_rpy_every4");
  const FirstCameraRun r =
      fuse_in_first_camera_frame("fr1-rpy-first-camera", data, "detections_yolofastest");
  ASSERT_TRUE(fs::exists(r.run)) << r.why.err;
  // fr1's depth planes themselves lie 2-7 deg from the ground truth's z frame by frame
  // (docs/scene.md); the levels' planes of the whole map: 0.94-0.99 deg in any frame.
  EXPECT_LT(angle_deg(up_of(r.run), r.truth), 3.0);
  const nlohmann::json doc = read_json(r.run / "objects.json");
  double table_height = -1e9, floor_height = 1e9;
  for (const auto& s : doc["surfaces"]) {
    if (s["label"] == "floor") floor_height = std::min(floor_height, s["height_m"].get<double>());
    if (s["label"] == "table" && s["area_m2"].get<double>() > 1.0)
      table_height = s["height_m"].get<double>();
  }
  EXPECT_NEAR(table_height - floor_height, 0.7, 0.15) << "a desk top of over 1 m2 above the floor";
  int keyboards = 0, mice = 0;
  for (const auto& o : doc["objects"]) {
    const auto& on = o["relations"]["on"];
    const bool on_table = !on.is_null() && on["label"] == "table";
    keyboards += o["class"] == "keyboard" && on_table;
    mice += o["class"] == "mouse" && on_table;
  }
  EXPECT_GE(keyboards, 1);
  EXPECT_GE(mice, 2);
}

TEST(FuseScene, Fr1Desk9UpIsNearItsFloorsOwnNormal) {
  // fr1_desk_9's depth and ground truth disagree by about 3 deg: its floor leans 3.1 +- 0.5 deg
  // toward -y in every frame (scripts/frame_planes.sh; normal (0, -0.053, 0.999) in the ground
  // truth's world). Up is judged against that floor: 1.75 deg measured (4.64 from +z; its desk
  // leans more).
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  const FirstCameraRun r =
      fuse_in_first_camera_frame("fr1-desk9-first-camera", data, "detections_yolofastest");
  ASSERT_TRUE(fs::exists(r.run)) << r.why.err;
  const Eigen::Vector3d floor = r.first_from_world * Eigen::Vector3d(0.0, -0.053, 0.999);
  EXPECT_LT(angle_deg(up_of(r.run), floor), 3.0);
}

TEST(FuseScene, Fr1RpyZUpGroundTruthHasKeyboardsMiceAndTheMonitorOnTheDeskTheChairOnTheFloor) {
  // Fused with groundtruth.txt as it is (z up): the desk is a table 0.7 m above the floor, with
  // the keyboards, the mice and the monitor on it. The monitor stands at the desk's back edge,
  // where it hides the desk: it is on it by a quarter of its footprint, not by its centre. The
  // chair is seen from above, its legs hidden (bottom 0.51 m above the floor): it stands on the
  // floor, its gap saying how much of it is hidden, not on its seat. (A second "chair", its bottom
  // 0.69 m up, was detected in 3 of the 74 keyframes that had its place in view: the detected
  // share leaves it out.) Whatever else is on the floor has its bottom near it, and nothing is on
  // an object of its own class.
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_rpy_every4");
  RunResult why;
  const fs::path run = fuse_cached("fr1-rpy-groundtruth", data, data / "groundtruth.txt",
                                   data / "detections_yolofastest", &why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  EXPECT_LT(angle_deg(up_of(run), Eigen::Vector3d::UnitZ()), 3.0);
  const nlohmann::json doc = read_json(run / "objects.json");
  std::map<int, std::string> class_of;
  for (const auto& o : doc["objects"]) class_of[o["id"].get<int>()] = o["class"];
  std::map<std::string, int> on_table, on_floor, count;
  for (const auto& o : doc["objects"]) {
    const auto& on = o["relations"]["on"];
    const std::string c = o["class"].get<std::string>();
    ++count[c];
    if (on.is_null()) continue;
    if (on["label"] == "table") ++on_table[c];
    if (on["label"] == "floor") {
      ++on_floor[c];
      EXPECT_LE(on["gap_m"].get<double>(), c == "chair" ? 0.6 : 0.15) << c << " " << o["id"];
    }
    if (on["kind"] == "object") {
      EXPECT_NE(class_of[on["id"].get<int>()], c) << o["id"] << " on its own class";
    }
  }
  EXPECT_GE(on_table["keyboard"], 2);
  EXPECT_GE(on_table["mouse"], 2);  // a third "mouse" was a monitor's foot: now its part
  EXPECT_GE(on_table["tv monitor"], 1);
  EXPECT_EQ(count["chair"], 1);
  EXPECT_EQ(on_floor["chair"], 1) << "a chair does not float: its legs are hidden";
  EXPECT_EQ(doc["surfaces"][0]["label"], "floor") << "the largest surface is the floor";
}

TEST(FuseScene, UpIsTheSameInAnyWorldFrameOnFr1Rpy) {
  // Every 4th of fr1_rpy_every4's frames (the camera rolls, pitches and turns over a desk) fused
  // with its ground truth as it is and moved into 5 random frames written with 5-9 decimals: the
  // grid is laid in the cameras' frame and up is the mode of the sample's normals, so the ups
  // agree within 0.3 deg (before: 1.7-5.6 deg from the truth by the rounding alone). fr1's depth
  // leans 2-7 deg from its ground truth's z (docs/scene.md): up within 3 deg of it.
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_rpy_every4");
  const std::vector<Eigen::Vector3d> ups = ups_in_moved_frames(
      data, data / "detections_yolofastest", {"--keyframes", "stride", "--stride", "4"});
  ASSERT_EQ(ups.size(), 6u);
  for (const auto& u : ups) {
    EXPECT_LT(angle_deg(u, ups.front()), 0.3) << u.transpose();
    EXPECT_LT(angle_deg(u, Eigen::Vector3d::UnitZ()), 3.0) << u.transpose();
  }
}

TEST(FuseScene, UpIsTheSameInAnyWorldFrameOnASyntheticScene) {
  RunResult why;
  const fs::path scene =
      cached_output("seed1-motion-scene", {"synth", "--out", "{OUT}", "--seed", "1"}, &why);
  ASSERT_TRUE(fs::exists(scene)) << why.err;
  const std::vector<Eigen::Vector3d> ups = ups_in_moved_frames(scene, scene / "segmentation", {});
  ASSERT_EQ(ups.size(), 6u);
  for (const auto& u : ups) {
    EXPECT_LT(angle_deg(u, ups.front()), 0.3) << u.transpose();
    EXPECT_LT(angle_deg(u, Eigen::Vector3d::UnitZ()), 1.0) << u.transpose();
  }
}

// The 7-Scenes kitchen clip detected with `model` (YOLOv8n-seg, every class) and fused with its
// own poses, both cached: the run folder (absent when a step failed; `why` says why).
fs::path seven_scenes_run(const fs::path& data, const fs::path& model, RunResult* why) {
  const fs::path seg = cached_output(
      "7scenes-yolov8n-seg",
      {"detect", "--dataset", data.string(), "--model", model.string(), "--out", "{OUT}"}, why);
  if (!fs::exists(seg)) return seg;
  return cached_output(
      "7scenes-yolov8n-fuse",
      {"fuse", "--dataset", data.string(), "--segmentation", seg.string(), "--out", "{OUT}"}, why);
}

TEST(FuseScene, SevenScenesChairsAtTheDiningTableAreNearIt) {
  // The 7-Scenes kitchen clip with YOLOv8n-seg's masks (YOLOv5n-seg finds no table there): a
  // dining table and two chairs pushed under it. By their box centres (the old rule, 0.5 m) one
  // chair was near it (0.46 m); by the gap between their boxes both are (0: under the table top).
  OBJMAP_DATA_OR_SKIP(data, "7scenes_redkitchen_3dmatch_50f");
  OBJMAP_DATA_OR_SKIP(model, "../models/yolov8n-seg_coco/yolov8n-seg_640x640.onnx");
  RunResult why;
  const fs::path run = seven_scenes_run(data, model, &why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  const RunResult q =
      run_objmap({"query", "--run", run.string(), "chair near dining table", "--json"});
  ASSERT_EQ(q.exit_code, 0) << q.err;
  const nlohmann::json answer = nlohmann::json::parse(q.out);
  const nlohmann::json doc = read_json(run / "objects.json");
  std::size_t chairs = 0;
  for (const auto& o : doc["objects"]) chairs += o["class"] == "chair";
  EXPECT_EQ(chairs, 2u);
  EXPECT_EQ(answer["matches"].size(), chairs) << q.out;
  for (const auto& m : answer["matches"]) EXPECT_LE(m["distance_m"].get<double>(), 0.05) << q.out;
}

// Every object's upright box (objects.json `obb`: its third axis is the up) no wider along either
// horizontal axis than its class's largest size × 1.15 (the oversize margin): the classes of
// those that are, one line each.
std::string wider_than_their_class(const fs::path& run) {
  const segmentation::ClassSizes sizes;
  std::string wide;
  const nlohmann::json doc = read_json(run / "objects.json");
  for (const auto& o : doc["objects"]) {
    const std::optional<segmentation::ClassSize> size = sizes.find(o["class"].get<std::string>());
    const auto& half = o["obb"]["half_extent"];
    const double width = 2.0 * std::max(half[0].get<double>(), half[1].get<double>());
    if (size && width > size->max_m * 1.15) wide += o["class"].get<std::string>() + "\n";
  }
  return wide;
}

TEST(FuseScene, NoObjectIsWiderThanItsClassOnFr1RpyOrTheKitchenClip) {
  // fr1_rpy_every4 with its ground truth and boxes: the 0.81 m keyboard and a mouse are trimmed of
  // the desk their box masks held, the 0.67 m "laptop" is the tv monitor it was also called, and
  // the monitor's 0.31 m foot, called mouse and cell phone, is part of the monitor above it. The
  // 7-Scenes clip with YOLOv8n-seg's masks: a cup's box trimmed of the table, 0.22 -> 0.15 m.
  OBJMAP_DATA_OR_SKIP(rpy, "tum/fr1_rpy_every4");
  RunResult why;
  const fs::path run = fuse_cached("fr1-rpy-groundtruth", rpy, rpy / "groundtruth.txt",
                                   rpy / "detections_yolofastest", &why);
  ASSERT_TRUE(fs::exists(run)) << why.err;
  EXPECT_EQ(wider_than_their_class(run), "") << "fr1_rpy_every4";
  OBJMAP_DATA_OR_SKIP(scenes, "7scenes_redkitchen_3dmatch_50f");
  OBJMAP_DATA_OR_SKIP(model, "../models/yolov8n-seg_coco/yolov8n-seg_640x640.onnx");
  const fs::path kitchen = seven_scenes_run(scenes, model, &why);
  ASSERT_TRUE(fs::exists(kitchen)) << why.err;
  EXPECT_EQ(wider_than_their_class(kitchen), "") << "7scenes_redkitchen_3dmatch_50f";
}

}  // namespace
}  // namespace objmap::test
