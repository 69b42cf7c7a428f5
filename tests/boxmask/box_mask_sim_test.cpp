// mask_from_box on the synthetic "tabletop" scene of objmap::sim: each object's exact visible mask
// gives its bounding box, mask_from_box turns the box back into a mask, and the mean IoU per class
// is reported (and asserted) against the exact masks.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/segmentation/box_mask.h"
#include "objmap/sim/camera_path.h"
#include "objmap/sim/depth_noise.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/random.h"
#include "objmap/sim/render.h"

namespace objmap::segmentation {
namespace {

struct ClassScore {
  double iou_sum = 0, precision_sum = 0;
  int n = 0;
};

struct SimScores {
  std::map<std::string, ClassScore> per_class;
  double mean_iou = 0, mean_precision = 0;
  int n = 0;
};

// Renders `frames` frames of the tabletop orbit; returns IoU/precision per class over every object
// with at least `min_pixels` visible pixels.
SimScores run_tabletop(int frames, bool noisy, int min_pixels = 400) {
  const sim::Scene scene = sim::make_scene("tabletop", 1);
  Camera cam = camera_preset("fr3");  // no distortion, as the renderer requires
  std::vector<double> stamps;
  for (int i = 0; i < frames; ++i) stamps.push_back(i * 2.0);
  const Trajectory path = sim::make_camera_path(sim::preset_camera_path("tabletop"), stamps, 1);
  SimScores s;
  for (std::size_t f = 0; f < path.poses.size(); ++f) {
    const sim::RenderedFrame frame = sim::render_frame(scene, cam, path.poses[f].world_from_cam);
    cv::Mat depth_m = frame.depth_m;
    if (noisy) {
      sim::Rng rng(sim::derive_seed(1, f));
      depth_m = sim::apply_depth_noise(frame.depth_m, cam, sim::DepthNoiseOptions{}, rng);
    }
    const cv::Mat depth = sim::depth_to_u16(depth_m, cam.depth_factor);
    for (const auto& object : scene.objects) {
      const cv::Mat truth = frame.labels == object.id;
      if (cv::countNonZero(truth) < min_pixels) continue;
      const cv::Rect r = cv::boundingRect(truth);
      const Box box{double(r.x), double(r.y), double(r.width), double(r.height)};
      const BoxMaskResult result = mask_from_box(box, depth, cam, {});
      std::size_t inter = 0, uni = 0;
      for (int v = r.y; v < r.y + r.height; ++v) {
        for (int u = r.x; u < r.x + r.width; ++u) {
          const bool t = truth.at<std::uint8_t>(v, u) != 0;
          const bool m = result.mask.at(u, v) != 0;
          inter += t && m;
          uni += t || m;
        }
      }
      const double iou = uni ? double(inter) / uni : 0.0;
      const double precision = result.pixels ? double(inter) / result.pixels : 0.0;
      ClassScore& c = s.per_class[object.class_name];
      c.iou_sum += iou;
      c.precision_sum += precision;
      ++c.n;
      s.mean_iou += iou;
      s.mean_precision += precision;
      ++s.n;
    }
  }
  if (s.n) {
    s.mean_iou /= s.n;
    s.mean_precision /= s.n;
  }
  return s;
}

void print(const char* title, const SimScores& s) {
  std::printf("[ measured ] %s: %d boxes, mean IoU %.3f, mean precision %.3f\n", title, s.n,
              s.mean_iou, s.mean_precision);
  for (const auto& [name, c] : s.per_class) {
    std::printf("[ measured ]   %-12s n %2d  IoU %.3f  precision %.3f\n", name.c_str(), c.n,
                c.iou_sum / c.n, c.precision_sum / c.n);
  }
}

// Measured (4 frames, 45 boxes): mean IoU 0.804, precision 0.874. Objects standing free on the
// table reach 0.90–0.98; the failures are occlusion (a book under another book, a bottle beside
// the teddy bear): see docs/fusion.md, "Masks from boxes". The per-class figures are printed;
// only the means are asserted, the scene may still change.
TEST(BoxMaskSim, TabletopNoiseFree) {
  const SimScores s = run_tabletop(4, false);
  print("tabletop, noise-free", s);
  ASSERT_GT(s.n, 30);
  EXPECT_GT(s.mean_iou, 0.75);
  EXPECT_GT(s.mean_precision, 0.82);
}

// Measured: mean IoU 0.717, precision 0.846 (the noise model also drops pixels at depth edges,
// which the exact masks keep).
TEST(BoxMaskSim, TabletopKinectNoise) {
  const SimScores s = run_tabletop(4, true);
  print("tabletop, Kinect-like depth noise", s);
  ASSERT_GT(s.n, 30);
  EXPECT_GT(s.mean_iou, 0.67);
  EXPECT_GT(s.mean_precision, 0.8);
}

}  // namespace
}  // namespace objmap::segmentation
