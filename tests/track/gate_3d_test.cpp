// The tracker's 3D gate on hand-made detection streams, and the robust 3D position of an instance
// from a depth image.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "objmap/core/error.h"
#include "objmap/geometry/backproject.h"
#include "objmap/track/position_3d.h"
#include "objmap/track/track_segmentation.h"
#include "objmap/track/tracker.h"

namespace objmap::track {
namespace {

Detection det3(double x, const Vec3& point_in_world) {
  Detection d;
  d.box = {x, 100, 40, 80};
  d.class_name = "chair";
  d.point_in_world = point_in_world;
  return d;
}

// Two chairs, one 1 m from the camera, one 3 m away, pass each other in the image while the
// camera pans right (the near one moves faster across the image) and then pans back. At the
// crossing the far chair is hidden behind the near one for a frame. After the turn, the constant
// velocity model predicts each box where the other one now is: on motion alone the ids swap; the
// 3D gate (the chairs are 2 m apart) keeps each id on its chair.
struct Crossing {
  std::vector<int> near_ids, far_ids;  // the id given to each chair's detections, frame by frame
};

Crossing run_crossing(bool gate_3d) {
  TrackerOptions o;
  o.use_appearance = false;  // two chairs of the same colour: nothing else to tell them apart
  o.use_gate_3d = gate_3d;
  Tracker tracker(o);
  const Vec3 near_chair(0.0, 0.0, 1.0), far_chair(0.2, 0.0, 3.0);
  Crossing out;
  const double speed_px = 4.0;
  for (int k = 0; k <= 20; ++k) {
    // Image x of the boxes: they meet at k = 10 (x = 140) and go back.
    const double s = k <= 10 ? k : 20 - k;
    const double near_x = 100 + speed_px * s, far_x = 180 - speed_px * s;
    std::vector<Detection> frame = {det3(near_x, near_chair)};
    if (k != 10) frame.push_back(det3(far_x, far_chair));  // hidden at the crossing
    const auto a = tracker.step(frame, 0.1 * k);
    out.near_ids.push_back(a[0].track_id);
    if (k != 10) out.far_ids.push_back(a[1].track_id);
  }
  return out;
}

TEST(Gate3d, StopsAnIdSwapBetweenSimilarBoxesAtDifferentDepths) {
  const Crossing without = run_crossing(false);
  // Motion alone: after the turn each chair carries the other's id.
  EXPECT_EQ(without.near_ids.front(), without.far_ids.back());
  EXPECT_EQ(without.far_ids.front(), without.near_ids.back());
  EXPECT_NE(without.near_ids.front(), without.near_ids.back());

  const Crossing with = run_crossing(true);
  for (int id : with.near_ids) EXPECT_EQ(id, with.near_ids.front());
  for (int id : with.far_ids) EXPECT_EQ(id, with.far_ids.front());
  EXPECT_NE(with.near_ids.front(), with.far_ids.front());
}

// The radius is max(gate_3d_m, gate_3d_speed_mps x seconds since the track's last 3D position); a
// detection or track without a 3D position is not gated.
TEST(Gate3d, RadiusGrowsWithTimeSinceTheLast3dPosition) {
  TrackerOptions o;
  o.use_appearance = false;
  o.use_gate_3d = true;
  o.gate_3d_m = 0.3;
  o.gate_3d_speed_mps = 0.5;
  const Vec3 p(1, 2, 3);
  struct Case {
    double dt_s, jump_m;
    bool same_id;
  };
  for (const Case c : {Case{0.1, 0.25, true}, Case{0.1, 0.35, false}, Case{2.0, 0.9, true},
                       Case{2.0, 1.1, false}}) {
    Tracker tracker(o);
    std::vector<Association> a;
    for (int k = 0; k < 4; ++k) a = tracker.step({det3(100, p)}, 0.1 * k);
    const int id = a[0].track_id;
    const double t = 0.3 + c.dt_s;
    a = tracker.step({det3(100, p + Vec3(c.jump_m, 0, 0))}, t);
    EXPECT_EQ(a[0].track_id == id, c.same_id) << c.dt_s << " s, " << c.jump_m << " m";
  }
  // Without a 3D position the detection joins on motion as before.
  Tracker tracker(o);
  for (int k = 0; k < 4; ++k) tracker.step({det3(100, p)}, 0.1 * k);
  Detection no_depth = det3(100, p);
  no_depth.point_in_world.reset();
  EXPECT_EQ(tracker.step({no_depth}, 0.4)[0].track_id, 1);
  // ... and the track keeps its last 3D position: a far detection later is still gated out.
  EXPECT_NE(tracker.step({det3(100, p + Vec3(0, 0, 2))}, 0.5)[0].track_id, 1);
}

// gate_3d_history: the detection may be near ANY of the track's last N positions. A track seen at
// A is lost for 2 s (radius 0.3 + 0.5 x 2 = 1.3 m) and found at B, 0.9 m away (the box mask took
// what stands behind the object); in the next frame the centroid is back at A. With the last
// position only (B) that is refused; with two positions (A, B) it is accepted.
TEST(Gate3d, HistoryAcceptsAReturnToAnEarlierPosition) {
  for (const int history : {1, 2}) {
    TrackerOptions o;
    o.use_appearance = false;
    o.use_gate_3d = true;
    o.gate_3d_history = history;
    Tracker tracker(o);
    const Vec3 a(0, 0, 1), b(0.9, 0, 1);
    for (int k = 0; k < 4; ++k) tracker.step({det3(100, a)}, 0.1 * k);
    EXPECT_EQ(tracker.step({det3(100, b)}, 2.3)[0].track_id, 1);
    EXPECT_EQ(tracker.step({det3(100, a)}, 2.4)[0].track_id == 1, history == 2) << history;
  }
}

TEST(Gate3d, BadOptionsNameTheField) {
  TrackerOptions o;
  o.gate_3d_m = 0;
  try {
    o.check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "TrackerOptions.gate_3d_m: must be > 0 metres, got 0.000000");
  }
  o = TrackerOptions();
  o.gate_3d_speed_mps = -1;
  EXPECT_THROW(o.check(), InputError);
  o = TrackerOptions();
  o.gate_3d_history = 0;
  EXPECT_THROW(o.check(), InputError);
}

TEST(Gate3d, NoPositionSourceIsAnError) {
  segmentation::Segmentation s;
  s.source = "seg";
  s.frames.resize(1);
  s.frames[0].instances.resize(1);
  s.frames[0].instances[0].bbox = {0, 0, 10, 10};
  TrackOptions o;
  o.tracker.use_appearance = false;
  o.tracker.use_gate_3d = true;
  try {
    track_segmentation(s, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "track_segmentation: the 3D gate is on but no position source was given; expected "
              "depth and a trajectory or use_gate_3d = false");
  }
}

// The robust centroid is the median of the mask's depth pixels: a mask that bleeds onto the wall
// behind the object (a third of its pixels) keeps the object's depth, where the mean would move
// 0.67 m back. The pose moves it into the world.
TEST(Position3d, MedianIgnoresMaskBleed) {
  Camera camera;  // 640x480, f 525, no distortion
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(static_cast<std::uint16_t>(3.0 * 5000)));
  depth(cv::Rect(300, 200, 40, 60)).setTo(static_cast<std::uint16_t>(1.0 * 5000));  // the object
  segmentation::Instance inst;
  inst.class_name = "cup";
  inst.bbox = {300, 200, 60, 60};
  segmentation::Mask mask{640, 480, std::vector<std::uint8_t>(640 * 480, 0)};
  for (int v = 200; v < 260; ++v)
    for (int u = 300; u < 360; ++u) mask.data[v * 640 + u] = 1;  // 40 columns object, 20 wall
  inst.mask = mask;
  Pose world_from_cam = Pose::Identity();
  world_from_cam.translation() = Vec3(1, 2, 3);
  const geometry::RayTable rays = geometry::make_ray_table(camera);
  const InstancePosition p =
      instance_position(inst, depth, camera, rays, world_from_cam, Position3dOptions());
  ASSERT_TRUE(p.point_in_world.has_value());
  EXPECT_EQ(p.status, PositionStatus::kOk);
  EXPECT_FALSE(p.mask_from_box);
  EXPECT_EQ(p.pixels, 60u * 60u);
  EXPECT_NEAR(p.point_in_world->z(), 3.0 + 1.0, 1e-6);  // the object's depth + the pose
  // x: the median pixel column is 330 (in the object), ray (330 - 319.5) / 525 at 1 m.
  EXPECT_NEAR(p.point_in_world->x(), 1.0 + (330 - 319.5) / 525.0, 1e-6);

  // Only a box: the mask is made from the box and the depth (the object's surface, not the wall).
  inst.mask.reset();
  const InstancePosition q =
      instance_position(inst, depth, camera, rays, world_from_cam, Position3dOptions());
  ASSERT_TRUE(q.point_in_world.has_value());
  EXPECT_TRUE(q.mask_from_box);
  EXPECT_NEAR(q.point_in_world->z(), 4.0, 0.01);

  // No depth in the box: no position, and why.
  depth.setTo(0);
  const InstancePosition r =
      instance_position(inst, depth, camera, rays, world_from_cam, Position3dOptions());
  EXPECT_FALSE(r.point_in_world.has_value());
  EXPECT_EQ(r.status, PositionStatus::kNoMaskFromBox);
}

}  // namespace
}  // namespace objmap::track
