// The dataset layouts (io/dataset.h): each read as it is, on the real 7-Scenes sample and on real
// TUM frames written out in the other layouts; bad input named by file, line or field.
#include "objmap/io/dataset.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "objmap/io/image.h"
#include "objmap/io/trajectory.h"
#include "objmap/io/tum_dataset.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::TempDir;
using test::write_text;

std::string matrix_text(const Pose& pose) {
  std::string out;
  const Eigen::Matrix4d m = pose.matrix();
  char cell[40];
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      std::snprintf(cell, sizeof cell, "%.17g ", m(r, c));
      out += cell;
    }
    out += "\n";
  }
  return out;
}

fs::path seven_scenes() { return test::data_dir() / "7scenes_redkitchen_3dmatch_50f"; }
fs::path desk() { return test::data_dir() / "tum/fr1_desk_9"; }

TEST(Dataset, SevenScenesIsReadAsItIsWithItsPosesAndCamera) {
  OBJMAP_DATA_OR_SKIP(sample, "7scenes_redkitchen_3dmatch_50f");
  EXPECT_EQ(detect_layout(seven_scenes()), "7scenes");
  const Dataset d = read_dataset(seven_scenes());
  EXPECT_EQ(d.layout, "7scenes");
  ASSERT_EQ(d.frames.size(), 50u);
  EXPECT_EQ(d.frames.front().rgb_file.filename(), "frame-000008.color.png");
  EXPECT_EQ(d.frames.front().depth_file.filename(), "frame-000008.depth.png");
  EXPECT_DOUBLE_EQ(d.frames.front().rgb_timestamp, 8.0 / 30.0);
  EXPECT_DOUBLE_EQ(d.frames.back().rgb_timestamp, 57.0 / 30.0);
  ASSERT_TRUE(d.camera);
  EXPECT_EQ(d.camera->fx, 585.0);
  EXPECT_EQ(d.camera->cx, 320.0);
  EXPECT_EQ(d.camera->width, 640);
  EXPECT_EQ(d.camera->height, 480);
  EXPECT_EQ(d.depth_factor, 1000.0);
  EXPECT_EQ(d.depth_invalid, 65535);
  ASSERT_EQ(d.poses.size(), 50u);
  // frame-000008.pose.txt: row 0 is 9.0709007e-001 2.7616704e-001 -3.1753206e-001 -3.4287909e-001;
  // its rotation is 4e-5 from orthonormal, and is read as the nearest rotation.
  const Pose& first = d.poses.poses.front().world_from_cam;
  EXPECT_NEAR(first.linear()(0, 0), 0.90709007, 1e-4);
  EXPECT_NEAR(first.linear()(0, 2), -0.31753206, 1e-4);
  EXPECT_DOUBLE_EQ(first.translation().x(), -0.34287909);
  EXPECT_NEAR((first.linear().transpose() * first.linear() - Eigen::Matrix3d::Identity()).norm(),
              0.0, 1e-12);
}

TEST(Dataset, SevenScenesDepthIsMillimetres) {
  OBJMAP_DATA_OR_SKIP(sample, "7scenes_redkitchen_3dmatch_50f");
  const Dataset d = read_dataset(seven_scenes());
  const cv::Mat depth = read_frame_depth(d, d.frames.front(), *d.camera);
  double lo = 0, hi = 0;
  cv::minMaxLoc(depth, &lo, &hi, nullptr, nullptr, depth > 0);
  EXPECT_GT(lo, 300);   // a kitchen seen from 0.3 m ...
  EXPECT_LT(hi, 8000);  // ... to 8 m, in millimetres (3DMatch's copy has 0 for no depth)
}

// fr1_desk_9's frames written as a 7-Scenes sequence in two seq-NN/ folders, with poses.
fs::path write_desk_as_seven_scenes(const fs::path& root, const Dataset& tum,
                                    const Trajectory& gt) {
  for (std::size_t i = 0; i < tum.frames.size(); ++i) {
    const fs::path seq = root / (i < 5 ? "seq-01" : "seq-02");
    fs::create_directories(seq);
    char name[32];
    std::snprintf(name, sizeof name, "frame-%06zu", i < 5 ? i : i - 5);
    fs::copy_file(tum.frames[i].rgb_file, seq / (std::string(name) + ".color.png"));
    fs::copy_file(tum.frames[i].depth_file, seq / (std::string(name) + ".depth.png"));
    const auto pose = lookup_pose(gt, tum.frames[i].rgb_timestamp, {});
    write_text(seq / (std::string(name) + ".pose.txt"), matrix_text(*pose));
  }
  return root;
}

TEST(Dataset, SevenScenesSequencesFollowOneAnother) {
  OBJMAP_DATA_OR_SKIP(sample, "tum/fr1_desk_9");
  TempDir tmp;
  const Dataset tum = read_tum_dataset(desk());
  const Trajectory gt = read_trajectory(desk() / "groundtruth.txt");
  write_desk_as_seven_scenes(tmp.path(), tum, gt);
  const Dataset d = read_dataset(tmp.path());
  EXPECT_EQ(d.layout, "7scenes");
  ASSERT_EQ(d.frames.size(), tum.frames.size());
  EXPECT_EQ(d.frames[4].rgb_file.parent_path().filename(), "seq-01");
  EXPECT_EQ(d.frames[5].rgb_file.parent_path().filename(), "seq-02");
  EXPECT_DOUBLE_EQ(d.frames[5].rgb_timestamp, 5.0 / 30.0);  // seq-02 starts after frame 4
  ASSERT_EQ(d.poses.size(), tum.frames.size());
  for (std::size_t i = 0; i < tum.frames.size(); ++i) {
    const Pose truth = *lookup_pose(gt, tum.frames[i].rgb_timestamp, {});
    EXPECT_LT((d.poses.poses[i].world_from_cam.matrix() - truth.matrix()).norm(), 1e-12) << i;
  }
}

TEST(Dataset, ReplicaReadsTrajAndCamParamsOneFolderUp) {
  OBJMAP_DATA_OR_SKIP(sample, "tum/fr1_desk_9");
  TempDir tmp;
  const Dataset tum = read_tum_dataset(desk());
  const Trajectory gt = read_trajectory(desk() / "groundtruth.txt");
  const fs::path scene = tmp / "office0";
  fs::create_directories(scene / "results");
  std::string traj;
  for (std::size_t i = 0; i < tum.frames.size(); ++i) {
    char n[32];
    std::snprintf(n, sizeof n, "%06zu", i);
    cv::imwrite((scene / "results" / ("frame" + std::string(n) + ".jpg")).string(),
                cv::imread(tum.frames[i].rgb_file.string()));
    fs::copy_file(tum.frames[i].depth_file,
                  scene / "results" / ("depth" + std::string(n) + ".png"));
    std::string row = matrix_text(*lookup_pose(gt, tum.frames[i].rgb_timestamp, {}));
    std::replace(row.begin(), row.end(), '\n', ' ');
    traj += row + "\n";
  }
  write_text(scene / "traj.txt", traj);
  write_text(tmp / "cam_params.json",
             R"({"camera": {"w": 640, "h": 480, "fx": 517.3, "fy": 516.5, "cx": 318.6,
                 "cy": 255.3, "scale": 5000.0}})");
  const Dataset d = read_dataset(scene);
  EXPECT_EQ(d.layout, "replica");
  ASSERT_EQ(d.frames.size(), 9u);
  EXPECT_EQ(d.depth_factor, 5000.0);
  EXPECT_EQ(d.camera->fx, 517.3);
  EXPECT_EQ(d.camera_source, (tmp / "cam_params.json").string());
  ASSERT_EQ(d.poses.size(), 9u);
  EXPECT_LT((d.poses.poses[8].world_from_cam.matrix() -
             lookup_pose(gt, tum.frames[8].rgb_timestamp, {})->matrix())
                .norm(),
            1e-12);
}

TEST(Dataset, Open3dReadsItsLogAndColumnMajorIntrinsic) {
  OBJMAP_DATA_OR_SKIP(sample, "tum/fr1_desk_9");
  TempDir tmp;
  const Dataset tum = read_tum_dataset(desk());
  const Trajectory gt = read_trajectory(desk() / "groundtruth.txt");
  std::string log;
  for (std::size_t i = 0; i < tum.frames.size(); ++i) {
    char n[32];
    std::snprintf(n, sizeof n, "%06zu", i);
    fs::create_directories(tmp / "color");
    fs::create_directories(tmp / "depth");
    fs::copy_file(tum.frames[i].rgb_file, tmp / "color" / (std::string(n) + ".png"));
    fs::copy_file(tum.frames[i].depth_file, tmp / "depth" / (std::string(n) + ".png"));
    log += std::to_string(i) + " " + std::to_string(i) + " " + std::to_string(i + 1) + "\n" +
           matrix_text(*lookup_pose(gt, tum.frames[i].rgb_timestamp, {}));
  }
  write_text(tmp / "scene" / "trajectory.log", log);
  write_text(tmp / "intrinsic.json",
             R"({"width": 640, "height": 480,
                 "intrinsic_matrix": [517.3, 0, 0, 0, 516.5, 0, 318.6, 255.3, 1]})");
  const Dataset d = read_dataset(tmp.path());
  EXPECT_EQ(d.layout, "open3d");
  ASSERT_EQ(d.frames.size(), 9u);
  EXPECT_EQ(d.camera->fy, 516.5);
  EXPECT_EQ(d.camera->cx, 318.6);
  EXPECT_EQ(d.camera->cy, 255.3);
  EXPECT_EQ(d.depth_factor, 1000.0);
  ASSERT_EQ(d.poses.size(), 9u);
}

TEST(Dataset, GenericLayoutOverTumFilesKeepsTheirTimestampsAndPoses) {
  OBJMAP_DATA_OR_SKIP(sample, "tum/fr1_desk_9");
  TempDir tmp;
  const fs::path layout = tmp / "objmap_layout.json";
  write_text(layout, R"({"color": "rgb/*.png", "depth": "depth/*.png", "depth_scale": 5000,
      "intrinsics": {"fx": 517.3, "fy": 516.5, "cx": 318.6, "cy": 255.3},
      "poses": "groundtruth.txt", "pose_format": "tum"})");
  DatasetOptions options;
  options.layout = layout.string();
  const Dataset d = read_dataset(desk(), options);
  const Dataset tum = read_tum_dataset(desk());
  EXPECT_EQ(d.layout, "generic");
  ASSERT_EQ(d.frames.size(), tum.frames.size());
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    EXPECT_DOUBLE_EQ(d.frames[i].rgb_timestamp, tum.frames[i].rgb_timestamp);
    EXPECT_EQ(d.frames[i].depth_file, tum.frames[i].depth_file);
  }
  EXPECT_EQ(d.poses.size(), read_trajectory(desk() / "groundtruth.txt").size());
  EXPECT_EQ(d.depth_factor, 5000.0);
}

TEST(Dataset, ScanNetDepthFromItsOwnCameraIsRegisteredIntoTheColourImage) {
  OBJMAP_DATA_OR_SKIP(sample, "tum/fr1_desk_9");
  TempDir tmp;
  const Dataset tum = read_tum_dataset(desk());
  // Colour at twice the depth camera's resolution (as ScanNet's 1296x968 against 640x480), depth
  // in millimetres, the same optical centre: a colour pixel (2u+0.5, 2v+0.5) sees depth pixel (u,
  // v).
  const cv::Mat rgb = cv::imread(tum.frames[0].rgb_file.string());
  cv::Mat big;
  cv::resize(rgb, big, {1280, 960});
  const cv::Mat depth5000 = read_depth(tum.frames[0].depth_file, 640, 480);
  cv::Mat depth_mm;
  depth5000.convertTo(depth_mm, CV_16U, 0.2);
  for (const char* sub : {"color", "depth", "pose", "intrinsic"}) fs::create_directories(tmp / sub);
  cv::imwrite((tmp / "color/0.jpg").string(), big);
  cv::imwrite((tmp / "depth/0.png").string(), depth_mm);
  write_text(tmp / "pose/0.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  write_text(tmp / "intrinsic/intrinsic_color.txt",
             "1000 0 639.5 0\n0 1000 479.5 0\n0 0 1 0\n0 0 0 1\n");
  write_text(tmp / "intrinsic/intrinsic_depth.txt",
             "500 0 319.25 0\n0 500 239.25 0\n0 0 1 0\n0 0 0 1\n");
  const Dataset d = read_dataset(tmp.path());
  EXPECT_EQ(d.layout, "scannet");
  ASSERT_TRUE(d.depth_camera);
  EXPECT_EQ(d.camera->width, 1280);
  const cv::Mat registered = read_frame_depth(d, d.frames[0], *d.camera);
  ASSERT_EQ(registered.cols, 1280);
  ASSERT_EQ(registered.rows, 960);
  int checked = 0, equal = 0;
  for (int v = 10; v < 470; v += 7)
    for (int u = 10; u < 630; u += 7) {
      const std::uint16_t z = depth_mm.at<std::uint16_t>(v, u);
      if (z == 0) continue;
      // Where the neighbourhood is flat, the colour pixels of the depth pixel carry its depth
      // (the nearest of the overlapping splats wins: within 2 mm).
      bool flat = true;
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du)
          flat = flat && std::abs(depth_mm.at<std::uint16_t>(v + dv, u + du) - z) <= 2;
      if (!flat) continue;
      ++checked;
      equal += std::abs(registered.at<std::uint16_t>(2 * v + 1, 2 * u + 1) - z) <= 2 &&
               std::abs(registered.at<std::uint16_t>(2 * v, 2 * u) - z) <= 2;
    }
  ASSERT_GT(checked, 1000);
  EXPECT_GT(equal, checked * 98 / 100) << equal << " of " << checked;
  // Coverage: the colour image has depth wherever the depth image had it.
  EXPECT_GT(cv::countNonZero(registered), 4 * cv::countNonZero(depth_mm) * 95 / 100);
}

TEST(Dataset, ScanNetLostPosesAreSkippedAndCounted) {
  TempDir tmp;
  for (const char* sub : {"color", "depth", "pose", "intrinsic"}) fs::create_directories(tmp / sub);
  const cv::Mat rgb(48, 64, CV_8UC3, cv::Scalar(10, 20, 30));
  const cv::Mat depth(48, 64, CV_16UC1, cv::Scalar(1000));
  for (int i = 0; i < 3; ++i) {
    cv::imwrite((tmp / "color" / (std::to_string(i) + ".jpg")).string(), rgb);
    cv::imwrite((tmp / "depth" / (std::to_string(i) + ".png")).string(), depth);
    write_text(tmp / "pose" / (std::to_string(i) + ".txt"),
               i == 1 ? "-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n"
                        "-inf -inf -inf -inf\n"
                      : "1 0 0 0\n0 1 0 0\n0 0 1 " + std::to_string(i) + "\n0 0 0 1\n");
  }
  for (const char* k : {"intrinsic_color.txt", "intrinsic_depth.txt"})
    write_text(tmp / "intrinsic" / k, "50 0 31.5 0\n0 50 23.5 0\n0 0 1 0\n0 0 0 1\n");
  const Dataset d = read_dataset(tmp.path());
  EXPECT_EQ(d.lost_poses, 1u);
  ASSERT_EQ(d.frames.size(), 2u);
  EXPECT_EQ(d.frames[1].rgb_file.filename(), "2.jpg");
  EXPECT_FALSE(d.depth_camera) << "same size, same intrinsics, identity extrinsic: registered";
}

// --- bad input: one line naming the file, line or field ---

// A tiny 7-Scenes folder of `n` frames, 64x48.
void write_tiny_seven_scenes(const fs::path& dir, int n, bool poses = true) {
  fs::create_directories(dir);
  for (int i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame-%06d", i);
    cv::imwrite((dir / (std::string(name) + ".color.png")).string(),
                cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
    cv::imwrite((dir / (std::string(name) + ".depth.png")).string(),
                cv::Mat(48, 64, CV_16UC1, cv::Scalar(1500)));
    if (poses)
      write_text(dir / (std::string(name) + ".pose.txt"), "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  }
}

TEST(Dataset, SevenScenesNoDepthValueBecomesZero) {
  TempDir tmp;
  write_tiny_seven_scenes(tmp.path(), 1);
  cv::Mat depth(48, 64, CV_16UC1, cv::Scalar(1500));
  depth(cv::Rect(0, 0, 10, 4)).setTo(65535);
  depth(cv::Rect(20, 20, 5, 5)).setTo(0);
  cv::imwrite((tmp / "frame-000000.depth.png").string(), depth);
  const Dataset d = read_dataset(tmp.path());
  const cv::Mat read = read_frame_depth(d, d.frames[0], *d.camera);
  EXPECT_EQ(cv::countNonZero(read == 65535), 0);
  EXPECT_EQ(cv::countNonZero(read == 0), 40 + 25);
  EXPECT_EQ(cv::countNonZero(read == 1500), 48 * 64 - 65);
}

TEST(DatasetErrors, AFolderOfNoLayoutNamesWhatWasLookedFor) {
  TempDir tmp;
  write_text(tmp / "notes.txt", "hello\n");
  std::string where;
  const std::string reason = test::error_reason([&] { read_dataset(tmp.path()); }, "empty", &where);
  EXPECT_EQ(where, tmp.path().string());
  EXPECT_NE(reason.find("rgb.txt + depth.txt (tum)"), std::string::npos) << reason;
  EXPECT_NE(reason.find("frame-XXXXXX.color.png (7scenes"), std::string::npos) << reason;
  EXPECT_NE(reason.find("objmap_layout.json"), std::string::npos) << reason;
}

TEST(DatasetErrors, AColourFrameWithoutDepthIsNamed) {
  TempDir tmp;
  write_tiny_seven_scenes(tmp.path(), 3);
  fs::remove(tmp / "frame-000001.depth.png");
  std::string where;
  const std::string reason =
      test::error_reason([&] { read_dataset(tmp.path()); }, "missing depth", &where);
  EXPECT_EQ(where, (tmp / "frame-000001.color.png").string());
  EXPECT_NE(reason.find("no depth image"), std::string::npos) << reason;
}

TEST(DatasetErrors, APoseWithFifteenNumbersIsNamed) {
  TempDir tmp;
  write_tiny_seven_scenes(tmp.path(), 2);
  write_text(tmp / "frame-000001.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0\n");
  std::string where;
  const std::string reason =
      test::error_reason([&] { read_dataset(tmp.path()); }, "15 numbers", &where);
  EXPECT_EQ(where, (tmp / "frame-000001.pose.txt").string());
  EXPECT_NE(reason.find("15 numbers; expected a 4x4 matrix"), std::string::npos) << reason;
}

TEST(DatasetErrors, APoseThatIsNotARotationIsNamed) {
  TempDir tmp;
  write_tiny_seven_scenes(tmp.path(), 1);
  write_text(tmp / "frame-000000.pose.txt", "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_NE(test::error_of([&] { read_dataset(tmp.path()); }).find("not a rotation"),
            std::string::npos);
}

TEST(DatasetErrors, SomeFramesWithoutPoseAreNamed) {
  TempDir tmp;
  write_tiny_seven_scenes(tmp.path(), 3);
  fs::remove(tmp / "frame-000002.pose.txt");
  std::string where;
  test::error_reason([&] { read_dataset(tmp.path()); }, "missing pose", &where);
  EXPECT_EQ(where, (tmp / "frame-000002.color.png").string());
}

TEST(DatasetErrors, GenericLayoutNamesTheField) {
  TempDir tmp;
  write_tiny_seven_scenes(tmp / "cap", 2, /*poses=*/false);
  const fs::path layout = tmp / "cap" / "objmap_layout.json";
  auto error_with = [&](const std::string& json) {
    write_text(layout, json);
    std::string where;
    const std::string reason = test::error_reason([&] { read_dataset(tmp / "cap"); }, json, &where);
    return where + " | " + reason;
  };
  const std::string base =
      R"("color": "frame-*.color.png", "depth": "frame-*.depth.png", "intrinsics": {"fx": 50, "fy": 50, "cx": 32, "cy": 24})";
  EXPECT_NE(error_with("{" + base + R"(, "depth_scale": 1000, "colour": 1})")
                .find("objmap_layout.json: colour | unknown field"),
            std::string::npos);
  EXPECT_NE(error_with("{" + base + R"(, "depth_scale": 1e400})")
                .find("objmap_layout.json: depth_scale | malformed JSON"),
            std::string::npos);
  EXPECT_NE(error_with("{" + base + R"(, "depth_scale": 1000, "intrinsics": {"fx": 1e999}})")
                .find("objmap_layout.json: intrinsics.fx | malformed JSON"),
            std::string::npos);
  EXPECT_NE(error_with("{" + base + R"(, "depth_scale": "mm"})")
                .find("objmap_layout.json: depth_scale | missing or not a number"),
            std::string::npos);
  EXPECT_NE(error_with(R"({"color": "img/*.jpg", "depth": "frame-*.depth.png", "depth_scale": 1000,
                           "intrinsics": {"fx": 50, "fy": 50, "cx": 32, "cy": 24}})")
                .find("matches no file"),
            std::string::npos);
  write_text(tmp / "cap" / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_NE(error_with(
                "{" + base +
                R"(, "depth_scale": 1000, "poses": "poses.txt", "pose_format": "matrix_per_line"})")
                .find("poses.txt:2 | 11 numbers; expected 12 or 16"),
            std::string::npos);
}

TEST(DatasetErrors, GenericCameraFromWorldPosesAreInverted) {
  TempDir tmp;
  write_tiny_seven_scenes(tmp.path(), 2, /*poses=*/false);
  write_text(tmp / "poses.txt", "1 0 0 1 0 1 0 2 0 0 1 3\n1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n");
  write_text(tmp / "objmap_layout.json",
             R"({"color": "frame-*.color.png", "depth": "frame-*.depth.png", "depth_scale": 1000,
                 "depth_invalid": 65535, "intrinsics": {"fx": 50, "fy": 50, "cx": 32, "cy": 24},
                 "poses": "poses.txt", "pose_format": "matrix_per_line",
                 "pose_convention": "camera_from_world", "fps": 10})");
  const Dataset d = read_dataset(tmp.path());
  EXPECT_EQ(d.layout, "generic");
  ASSERT_EQ(d.poses.size(), 2u);
  EXPECT_TRUE(d.poses.poses[0].world_from_cam.translation().isApprox(Vec3(-1, -2, -3)));
  EXPECT_DOUBLE_EQ(d.frames[1].rgb_timestamp, 0.1);
  EXPECT_EQ(d.depth_invalid, 65535);
}

TEST(DatasetErrors, GenericDepthInvalidZeroIsAccepted) {
  // 0 already means no depth: "depth_invalid": 0 says nothing more, and was refused ([1, 65535]).
  TempDir tmp;
  write_tiny_seven_scenes(tmp.path(), 2, /*poses=*/false);
  const std::string layout =
      R"({"color": "frame-*.color.png", "depth": "frame-*.depth.png", "depth_scale": 1000,
          "intrinsics": {"fx": 50, "fy": 50, "cx": 32, "cy": 24}, "depth_invalid": )";
  write_text(tmp / "objmap_layout.json", layout + "0}");
  EXPECT_EQ(read_dataset(tmp.path()).depth_invalid, 0);
  write_text(tmp / "objmap_layout.json", layout + "65536}");
  std::string where;
  const std::string reason = test::error_reason([&] { read_dataset(tmp.path()); }, "65536", &where);
  EXPECT_EQ(where, (tmp / "objmap_layout.json").string() + ": depth_invalid");
  EXPECT_EQ(reason, "is 65536; expected a number in [0.0, 65535.0]");
}

TEST(DatasetErrors, AnUnknownLayoutNameIsRefused) {
  TempDir tmp;
  DatasetOptions options;
  options.layout = "kitti";
  std::string where;
  test::error_reason([&] { read_dataset(tmp.path(), options); }, "kitti", &where);
  EXPECT_EQ(where, "--layout");
}

// --- depth from another camera: how much of each real mask lands on its object ---

// The share of `mask` pixels whose depth is within `band_mm` of the object's median true depth.
double share_on_object(const cv::Mat& depth_mm, const cv::Mat& mask, double median_mm,
                       double band_mm) {
  int in = 0, all = 0;
  for (int v = 0; v < mask.rows; ++v)
    for (int u = 0; u < mask.cols; ++u) {
      if (!mask.at<std::uint8_t>(v, u)) continue;
      ++all;
      const int z = depth_mm.at<std::uint16_t>(v, u);
      in += z > 0 && std::abs(z - median_mm) <= band_mm;
    }
  return all ? static_cast<double>(in) / all : 0.0;
}

// ycbv_0000_10f's real frame 0 written as a ScanNet export whose depth camera sits 2.5 cm beside
// the colour camera at half its resolution (a Kinect-like rig): its depth image is the frame's
// real depth seen from there. Registered back, each object's mask pixels find their object's depth
// again; taken as if registered (resized, no extrinsic: what a reader that ignores the depth
// camera does), part of each mask lands on the background. Prints the figures of docs/formats.md.
TEST(Dataset, RegisteredDepthPutsRealMasksBackOnTheirObjects) {
  OBJMAP_DATA_OR_SKIP(ycb, "ycbv_0000_10f");
  const Dataset src = read_dataset(ycb);
  TempDir tmp;
  Camera c;  // camera.json of the clip
  c.fx = 1066.778, c.fy = 1067.487, c.cx = 312.9869, c.cy = 241.3109, c.depth_factor = 10000;
  const cv::Mat depth = read_depth(src.frames[0].depth_file, 640, 480);
  const cv::Mat labels =
      cv::imread((ycb / "masks" / "0.000000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(labels.empty());
  // The depth camera: half resolution, 2.5 cm to the colour camera's right.
  Camera dc = c;
  dc.fx /= 2, dc.fy /= 2, dc.cx = (c.cx + 0.5) / 2 - 0.5, dc.cy = (c.cy + 0.5) / 2 - 0.5;
  dc.width = 320, dc.height = 240;
  Pose color_from_depth = Pose::Identity();
  color_from_depth.translation() = Vec3(0.025, 0, 0);
  cv::Mat seen(240, 320, CV_16UC1, cv::Scalar(0));
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      const int raw = depth.at<std::uint16_t>(v, u);
      if (raw == 0) continue;
      const Vec3 p = color_from_depth.inverse() * c.unproject(u, v, raw / 10000.0);
      const Eigen::Vector2d px = dc.project(p);
      const int du = static_cast<int>(std::lround(px.x())),
                dv = static_cast<int>(std::lround(px.y()));
      if (du < 0 || dv < 0 || du >= 320 || dv >= 240) continue;
      const auto mm = static_cast<std::uint16_t>(std::lround(p.z() * 1000));
      auto& cell = seen.at<std::uint16_t>(dv, du);
      if (cell == 0 || mm < cell) cell = mm;
    }
  for (const char* sub : {"color", "depth", "pose", "intrinsic"}) fs::create_directories(tmp / sub);
  fs::copy_file(src.frames[0].rgb_file, tmp / "color" / "0.png");
  cv::imwrite((tmp / "depth" / "0.png").string(), seen);
  write_text(tmp / "pose" / "0.txt", matrix_text(Pose::Identity()));
  char k[200];
  std::snprintf(k, sizeof k, "%.17g 0 %.17g 0\n0 %.17g %.17g 0\n0 0 1 0\n0 0 0 1\n", c.fx, c.cx,
                c.fy, c.cy);
  write_text(tmp / "intrinsic" / "intrinsic_color.txt", k);
  std::snprintf(k, sizeof k, "%.17g 0 %.17g 0\n0 %.17g %.17g 0\n0 0 1 0\n0 0 0 1\n", dc.fx, dc.cx,
                dc.fy, dc.cy);
  write_text(tmp / "intrinsic" / "intrinsic_depth.txt", k);
  write_text(tmp / "intrinsic" / "extrinsic_color.txt", matrix_text(Pose::Identity()));
  write_text(tmp / "intrinsic" / "extrinsic_depth.txt", matrix_text(color_from_depth));
  const Dataset scan = read_dataset(tmp.path());
  ASSERT_TRUE(scan.depth_camera);
  const cv::Mat registered = read_frame_depth(scan, scan.frames[0], *scan.camera);
  cv::Mat naive;
  cv::resize(seen, naive, {640, 480}, 0, 0, cv::INTER_NEAREST);
  cv::Mat truth_mm;
  depth.convertTo(truth_mm, CV_16U, 0.1);
  for (int label : {8, 14, 21}) {
    const cv::Mat mask = labels == label;
    std::vector<std::uint16_t> zs;
    for (int v = 0; v < 480; ++v)
      for (int u = 0; u < 640; ++u)
        if (mask.at<std::uint8_t>(v, u) && truth_mm.at<std::uint16_t>(v, u))
          zs.push_back(truth_mm.at<std::uint16_t>(v, u));
    ASSERT_GT(zs.size(), 500u) << label;
    std::nth_element(zs.begin(), zs.begin() + zs.size() / 2, zs.end());
    const double median = zs[zs.size() / 2];
    const double before = share_on_object(naive, mask, median, 30.0);
    const double after = share_on_object(registered, mask, median, 30.0);
    const double truth = share_on_object(truth_mm, mask, median, 30.0);
    std::printf(
        "label %2d: mask pixels within 3 cm of the object's depth: true depth %.3f, "
        "unregistered %.3f, registered %.3f\n",
        label, truth, before, after);
    EXPECT_GT(after, before + 0.05) << label;
    EXPECT_GT(after, truth - 0.05) << label;
  }
}

}  // namespace
}  // namespace objmap::io
