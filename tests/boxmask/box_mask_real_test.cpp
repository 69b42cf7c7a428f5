// mask_from_box on real data: YCB-Video frames with real per-pixel masks and real (Asus Xtion)
// depth. Each object's exact bounding box (from its mask) goes in; the mask that comes out is
// compared with the real one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/segmentation/box_mask.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

namespace fs = std::filesystem;

struct Score {
  double iou_sum = 0, iou_valid_sum = 0, precision_sum = 0;
  int n = 0;
};

const std::map<int, std::string> kNames = {{8, "gelatin_box"}, {14, "mug"}, {21, "foam_brick"}};

// Mean scores per YCB id over the 10 frames, boxes grown by `margin` of their size on each side.
std::map<int, Score> run_ycbv(const fs::path& dir, double margin) {
  std::ifstream camera_file(dir / "camera.json");
  const auto j = nlohmann::json::parse(camera_file);
  Camera cam;
  cam.name = "ycbv";
  cam.fx = j.at("fx");
  cam.fy = j.at("fy");
  cam.cx = j.at("cx");
  cam.cy = j.at("cy");
  cam.depth_factor = j.at("depth_factor");

  const auto& names = kNames;
  std::map<int, Score> scores;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir / "masks")) {
    if (e.path().extension() == ".png") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files.size(), 10u);
  for (const auto& mask_file : files) {
    const cv::Mat labels = cv::imread(mask_file.string(), cv::IMREAD_UNCHANGED);
    const cv::Mat depth =
        cv::imread((dir / "depth" / mask_file.filename()).string(), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(labels.type(), CV_8UC1);
    EXPECT_EQ(depth.type(), CV_16UC1);
    if (labels.type() != CV_8UC1 || depth.type() != CV_16UC1) continue;
    for (const auto& [id, name] : names) {
      int u0 = labels.cols, v0 = labels.rows, u1 = -1, v1 = -1;
      for (int v = 0; v < labels.rows; ++v) {
        for (int u = 0; u < labels.cols; ++u) {
          if (labels.at<std::uint8_t>(v, u) != id) continue;
          u0 = std::min(u0, u);
          v0 = std::min(v0, v);
          u1 = std::max(u1, u);
          v1 = std::max(v1, v);
        }
      }
      EXPECT_GE(u1, 0) << name << " missing in " << mask_file;
      if (u1 < 0) continue;
      const double w = u1 - u0 + 1, h = v1 - v0 + 1;
      const Box box{u0 - margin * w, v0 - margin * h, w * (1 + 2 * margin), h * (1 + 2 * margin)};
      const BoxMaskResult r = mask_from_box(box, depth, cam, {});
      EXPECT_EQ(r.status, BoxMaskStatus::kOk) << name << " " << mask_file.filename();
      std::size_t inter = 0, uni = 0, inter_valid = 0, uni_valid = 0, found = 0;
      int mu0 = labels.cols, mv0 = labels.rows, mu1 = -1, mv1 = -1;  // the mask's bounds
      for (int v = 0; v < labels.rows; ++v) {
        for (int u = 0; u < labels.cols; ++u) {
          const bool t = labels.at<std::uint8_t>(v, u) == id;
          const bool m = r.mask.at(u, v);
          if (m) {
            mu0 = std::min(mu0, u);
            mv0 = std::min(mv0, v);
            mu1 = std::max(mu1, u);
            mv1 = std::max(mv1, v);
          }
          const bool valid = depth.at<std::uint16_t>(v, u) > 0;
          inter += t && m;
          uni += t || m;
          found += m;
          inter_valid += valid && t && m;
          uni_valid += valid && (t || m);
        }
      }
      // The result's bounds are those of its mask's pixels (fuse passes them on, unscanned).
      if (r.status == BoxMaskStatus::kOk) {
        EXPECT_EQ(r.bounds, cv::Rect(mu0, mv0, mu1 - mu0 + 1, mv1 - mv0 + 1)) << name;
      } else {
        EXPECT_TRUE(r.bounds.empty());
      }
      Score& s = scores[id];
      s.iou_sum += uni ? double(inter) / uni : 0;
      s.iou_valid_sum += uni_valid ? double(inter_valid) / uni_valid : 0;
      s.precision_sum += found ? double(inter) / found : 0;
      ++s.n;
    }
  }
  for (const auto& [id, s] : scores) {
    std::printf(
        "[ measured ] margin %.2f %-12s mean IoU %.3f (valid-depth pixels %.3f), "
        "precision %.3f, %d frames\n",
        margin, names.at(id).c_str(), s.iou_sum / s.n, s.iou_valid_sum / s.n, s.precision_sum / s.n,
        s.n);
  }
  return scores;
}

double mean_iou(std::map<int, Score>& scores, int id) {
  return scores[id].n ? scores[id].iou_sum / scores[id].n : 0.0;
}

double mean_precision(std::map<int, Score>& scores, int id) {
  return scores[id].n ? scores[id].precision_sum / scores[id].n : 0.0;
}

// Measured (tight boxes): IoU gelatin box 0.939, foam brick 0.908, mug 0.400; precision 0.97, 0.99,
// 0.96. The mug, seen from above with the brick standing against it, loses its inside and rim,
// which lie behind a depth step from its front.
TEST(BoxMaskReal, YcbVideoObjectsOnATableTightBoxes) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f");
  auto scores = run_ycbv(dir, 0.0);
  EXPECT_GT(mean_iou(scores, 8), 0.9);
  EXPECT_GT(mean_iou(scores, 21), 0.87);
  EXPECT_GT(mean_iou(scores, 14), 0.35);
  // What is found is the object: fusion suffers from wrong points more than from missing ones.
  for (const auto& [id, name] : kNames) EXPECT_GT(mean_precision(scores, id), 0.9) << name;
}

// Detection boxes are looser than mask boxes: 10 % margin on each side (the box area grows by 44
// %). Measured: IoU 0.937, 0.918, 0.377; precision 0.97, 0.98, 0.91.
TEST(BoxMaskReal, YcbVideoObjectsOnATableLooseBoxes) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f");
  auto scores = run_ycbv(dir, 0.1);
  EXPECT_GT(mean_iou(scores, 8), 0.9);
  EXPECT_GT(mean_iou(scores, 21), 0.87);
  EXPECT_GT(mean_iou(scores, 14), 0.35);
  for (const auto& [id, name] : kNames) EXPECT_GT(mean_precision(scores, id), 0.85) << name;
}

}  // namespace
}  // namespace objmap::segmentation
