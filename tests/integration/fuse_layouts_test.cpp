// objmap detect and fuse on recordings in their own layouts: the same frames read through two
// layouts give the same objects.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "fuse_helpers.h"
#include "objmap/io/dataset.h"
#include "objmap/io/image.h"
#include "objmap/io/trajectory.h"
#if OBJMAP_TEST_BAGS
#include "support/bag_writer.h"
#endif

namespace objmap::test {
namespace {

const char* const kSevenScenes = "7scenes_redkitchen_3dmatch_50f";
const char* const kYoloSeg = "../models/yolov5n-seg_coco/yolov5n-seg_480x640.onnx";

// Every number of two JSON values equal within `tol`, everything else exactly, paths apart
// (keys "ply", "mesh", "thumbnail" hold file names under each run).
::testing::AssertionResult same_json(const nlohmann::json& a, const nlohmann::json& b,
                                     const std::string& where, double tol) {
  if (a.is_number() && b.is_number()) {
    if (std::abs(a.get<double>() - b.get<double>()) <= tol) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << where << ": " << a << " vs " << b;
  }
  if (a.type() != b.type()) return ::testing::AssertionFailure() << where << ": types differ";
  if (a.is_object()) {
    if (a.size() != b.size()) return ::testing::AssertionFailure() << where << ": sizes differ";
    for (const auto& [key, value] : a.items()) {
      if (!b.contains(key))
        return ::testing::AssertionFailure() << where << "." << key << " missing";
      auto r = same_json(value, b[key], where + "." + key, tol);
      if (!r) return r;
    }
    return ::testing::AssertionSuccess();
  }
  if (a.is_array()) {
    if (a.size() != b.size())
      return ::testing::AssertionFailure() << where << ": " << a.size() << " vs " << b.size();
    for (std::size_t i = 0; i < a.size(); ++i) {
      auto r = same_json(a[i], b[i], where + "[" + std::to_string(i) + "]", tol);
      if (!r) return r;
    }
    return ::testing::AssertionSuccess();
  }
  if (a == b) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << where << ": " << a << " vs " << b;
}

// The 7-Scenes sample converted to a TUM folder as a user would: rgb.txt/depth.txt at the
// sequence's frame times (number / 30 s), depth copied with its "no depth" 65535 set to 0, the
// camera as camera.json (585, 320, 240, depth factor 1000) and the poses as groundtruth.txt.
void convert_seven_scenes_to_tum(const fs::path& src, const fs::path& dst) {
  const io::Dataset d = io::read_dataset(src);
  fs::create_directories(dst / "rgb");
  fs::create_directories(dst / "depth");
  std::ofstream rgb_list(dst / "rgb.txt"), depth_list(dst / "depth.txt");
  for (const io::FramePair& f : d.frames) {
    char t[40];
    std::snprintf(t, sizeof t, "%.17g", f.rgb_timestamp);
    const std::string stem = f.rgb_file.filename().string().substr(0, 12);
    fs::copy_file(f.rgb_file, dst / "rgb" / (stem + ".png"));
    cv::Mat depth = io::read_depth(f.depth_file, 640, 480);
    depth.setTo(0, depth == 65535);
    cv::imwrite((dst / "depth" / (stem + ".png")).string(), depth);
    rgb_list << t << " rgb/" << stem << ".png\n";
    depth_list << t << " depth/" << stem << ".png\n";
  }
  std::ofstream(dst / "camera.json") << R"({"fx": 585, "fy": 585, "cx": 320, "cy": 240,
      "width": 640, "height": 480, "depth_factor": 1000})";
  io::write_trajectory(dst / "groundtruth.txt", d.poses);
}

TEST(FuseLayouts, SevenScenesFromItsOwnPosesEqualsItsTumConversion) {
  OBJMAP_DATA_OR_SKIP(scenes, kSevenScenes);
  OBJMAP_DATA_OR_SKIP(model, kYoloSeg);
  TempDir tmp;
  // detect reads the 7-Scenes folder as it is.
  const RunResult detect = run_objmap({"detect", "--dataset", scenes.string(), "--model",
                                       model.string(), "--out", (tmp / "seg").string()});
  ASSERT_EQ(detect.exit_code, 0) << detect.err;
  const RunResult a = run_objmap({"fuse", "--dataset", scenes.string(), "--segmentation",
                                  (tmp / "seg").string(), "--out", (tmp / "run7").string()});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  convert_seven_scenes_to_tum(scenes, tmp / "tum");
  const RunResult b = run_objmap({"fuse", "--dataset", (tmp / "tum").string(), "--trajectory",
                                  (tmp / "tum" / "groundtruth.txt").string(), "--segmentation",
                                  (tmp / "seg").string(), "--out", (tmp / "runtum").string()});
  ASSERT_EQ(b.exit_code, 0) << b.err;

  const nlohmann::json run7 = read_json(tmp / "run7" / "run.json");
  EXPECT_EQ(run7["inputs"]["dataset"]["layout"], "7scenes");
  EXPECT_EQ(run7["inputs"]["trajectory"]["from"], "dataset");
  EXPECT_EQ(run7["counts"]["frames"], 50);
  EXPECT_TRUE(fs::exists(tmp / "run7" / "dataset_trajectory.txt"));
  const nlohmann::json objects7 = read_json(tmp / "run7" / "objects.json");
  const nlohmann::json objects_tum = read_json(tmp / "runtum" / "objects.json");
  ASSERT_GE(objects7["objects"].size(), 2u) << "the kitchen's table, chairs or cup";
  EXPECT_TRUE(same_json(objects7["objects"], objects_tum["objects"], "objects", 1e-9));

  // Every frame (50 keyframes against the motion rule's few): the same objects within 10 %, and no
  // object stands on another of its own class (docs/fusion.md, per-density table).
  const RunResult every =
      run_objmap({"fuse", "--dataset", scenes.string(), "--segmentation", (tmp / "seg").string(),
                  "--keyframes", "all", "--out", (tmp / "run7all").string()});
  ASSERT_EQ(every.exit_code, 0) << every.err;
  const nlohmann::json objects_all = read_json(tmp / "run7all" / "objects.json");
  const double n_kf = static_cast<double>(objects7["objects"].size());
  const double n_all = static_cast<double>(objects_all["objects"].size());
  EXPECT_LE(std::abs(n_all - n_kf), 0.1 * n_kf) << every.out;
  for (const nlohmann::json* doc : {&objects7, &objects_all}) {
    std::map<int, std::string> class_of;
    for (const auto& o : (*doc)["objects"]) class_of[o["id"].get<int>()] = o["class"];
    for (const auto& o : (*doc)["objects"]) {
      const auto& on = o["relations"]["on"];
      if (!on.is_object() || on["kind"] != "object") continue;
      EXPECT_NE(class_of[on["id"].get<int>()], o["class"].get<std::string>()) << o["id"];
    }
  }
}

#if OBJMAP_TEST_BAGS
// fr1_desk_9 recorded as the TUM benchmark's own bags are (rgb8 colour, 32FC1 depth in metres,
// camera_info), in `compression`.
void write_tum_bag(const fs::path& desk, const fs::path& file, const std::string& compression) {
  const io::Dataset tum = io::read_dataset(desk);
  const Camera camera = camera_preset("fr1");
  BagWriter bag(file, compression);
  for (const io::FramePair& f : tum.frames) {
    bag.camera_info("/camera/rgb/camera_info", f.rgb_timestamp, camera,
                    "/openni_rgb_optical_frame");
    bag.image("/camera/rgb/image_color", f.rgb_timestamp, io::read_rgb(f.rgb_file, 0, 0), "rgb8");
    cv::Mat metres;
    io::read_depth(f.depth_file, 0, 0).convertTo(metres, CV_32F, 1.0 / 5000.0);
    bag.image("/camera/depth/image", f.depth_timestamp, metres, "32FC1");
  }
}

TEST(FuseLayouts, ATumBagInEitherCompressionGivesTheObjectsOfItsFolder) {
  OBJMAP_DATA_OR_SKIP(desk, "tum/fr1_desk_9");
  TempDir tmp;
  const std::string gt = (desk / "groundtruth.txt").string();
  const std::string boxes = (desk / "detections_yolofastest").string();
  const RunResult folder =
      run_objmap({"fuse", "--dataset", desk.string(), "--trajectory", gt, "--segmentation", boxes,
                  "--camera", "fr1", "--out", (tmp / "folder").string()});
  ASSERT_EQ(folder.exit_code, 0) << folder.err;
  const nlohmann::json expected = read_json(tmp / "folder" / "objects.json");
  ASSERT_GE(expected["objects"].size(), 1u) << folder.out;
  for (const std::string compression : {"bz2", "lz4"}) {
    const fs::path bag = tmp / ("desk_" + compression + ".bag");
    write_tum_bag(desk, bag, compression);
    const fs::path out = tmp / ("run_" + compression);
    const RunResult r = run_objmap({"fuse", "--dataset", bag.string(), "--trajectory", gt,
                                    "--segmentation", boxes, "--out", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json run = read_json(out / "run.json");
    EXPECT_EQ(run["inputs"]["dataset"]["layout"], "rosbag");
    EXPECT_EQ(run["inputs"]["dataset"]["topics"], "/camera/rgb/image_color,/camera/depth/image");
    EXPECT_TRUE(same_json(read_json(out / "objects.json")["objects"], expected["objects"],
                          compression, 1e-9));
  }
}

TEST(ObjmapRun, ABagGoesThroughDetectTrackFuseAndReport) {
  OBJMAP_DATA_OR_SKIP(desk, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(model, kYoloSeg);
  TempDir tmp;
  write_tum_bag(desk, tmp / "desk.bag", "lz4");
  const RunResult r = run_objmap(
      {"run", "--dataset", (tmp / "desk.bag").string(), "--model", model.string(), "--trajectory",
       (desk / "groundtruth.txt").string(), "--out", (tmp / "run").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  // Every frame was read from the bag by detect and track, and fuse read the bag.
  int frame_files = 0;
  for (const auto& e : fs::directory_iterator(tmp / "run" / "track"))
    frame_files += e.path().filename().string().rfind("1305031", 0) == 0;
  EXPECT_EQ(frame_files, 9);
  EXPECT_EQ(read_json(tmp / "run" / "map" / "run.json")["inputs"]["dataset"]["layout"], "rosbag");
  const nlohmann::json objects = read_json(tmp / "run" / "map" / "objects.json");
  bool monitor = false;
  for (const auto& o : objects["objects"]) monitor |= o["class"] == "tv monitor";
  EXPECT_TRUE(monitor) << r.out;
  EXPECT_TRUE(fs::exists(tmp / "run" / "report" / "report.html"));
}
#endif

TEST(FuseLayouts, ARecordingWithoutPosesNeedsATrajectory) {
  OBJMAP_DATA_OR_SKIP(desk, "tum/fr1_desk_9");
  TempDir tmp;
  const RunResult r =
      run_objmap({"fuse", "--dataset", desk.string(), "--segmentation",
                  (desk / "detections_yolofastest").string(), "--out", (tmp / "run").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--trajectory: missing, and the tum recording"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "run"));
}

// Lines of `text` that contain `what`.
int lines_with(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(ObjmapRun, RerunReusesEveryStageAndAChangedOptionRerunsOnlyTheStagesAfterIt) {
  OBJMAP_DATA_OR_SKIP(desk, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(model, kYoloSeg);
  TempDir tmp;
  const fs::path out = tmp / "run";
  std::vector<std::string> args = {"run",
                                   "--dataset",
                                   desk.string(),
                                   "--model",
                                   model.string(),
                                   "--trajectory",
                                   (desk / "groundtruth.txt").string(),
                                   "--out",
                                   out.string()};
  const RunResult first = run_objmap(args);
  ASSERT_EQ(first.exit_code, 0) << first.err << first.out;
  EXPECT_EQ(lines_with(first.out, "running ... done"), 4) << first.out;
  EXPECT_NE(first.out.find("map         "), std::string::npos);
  EXPECT_NE(first.out.find((out / "report" / "report.html").string()), std::string::npos);
  for (const char* f : {"detect", "track/tracks.json", "map/objects.json", "report/report.html"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  // The query works on its output.
  const RunResult query = run_objmap({"query", "--run", (out / "map").string(), "tv"});
  EXPECT_EQ(query.exit_code, 0) << query.err;

  const RunResult second = run_objmap(args);
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(lines_with(second.out, " reused "), 4) << second.out;
  EXPECT_EQ(lines_with(second.out, "running"), 0) << second.out;

  // A fuse option changed: detect and track are reused, fuse and report run again.
  std::ofstream(tmp / "fuse.json") << R"({"map": {"voxel_m": 0.02}})";
  args.insert(args.end(), {"--fuse-config", (tmp / "fuse.json").string()});
  const RunResult third = run_objmap(args);
  ASSERT_EQ(third.exit_code, 0) << third.err;
  EXPECT_NE(third.out.find("detect   reused"), std::string::npos) << third.out;
  EXPECT_NE(third.out.find("track    reused"), std::string::npos) << third.out;
  EXPECT_NE(third.out.find("fuse     running ... done"), std::string::npos) << third.out;
  EXPECT_NE(third.out.find("report   running ... done"), std::string::npos) << third.out;
  EXPECT_EQ(read_json(out / "map" / "run.json")["options"]["map"]["voxel_m"], 0.02);
}

TEST(ObjmapRun, AFailingStageIsNamedWithItsError) {
  OBJMAP_DATA_OR_SKIP(desk, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(model, kYoloSeg);
  TempDir tmp;
  std::ofstream(tmp / "broken.txt") << "1305031453.3595 1 2 3\n";
  const RunResult r =
      run_objmap({"run", "--dataset", desk.string(), "--model", model.string(), "--trajectory",
                  (tmp / "broken.txt").string(), "--out", (tmp / "run").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("objmap run: stage fuse:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("broken.txt:1"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "run" / "map"));
}

}  // namespace
}  // namespace objmap::test
