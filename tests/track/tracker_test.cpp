// The DeepSORT life cycle, matching cascade and appearance, on hand-made detection streams.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "objmap/core/error.h"
#include "objmap/track/appearance.h"
#include "objmap/track/track_segmentation.h"
#include "objmap/track/tracker.h"

namespace objmap::track {
namespace {

Detection det(double x, double y, std::string cls = "cup") {
  Detection d;
  d.box = {x, y, 40, 80};
  d.class_name = std::move(cls);
  return d;
}

TrackerOptions motion_only() {
  TrackerOptions o;
  o.use_appearance = false;
  return o;
}

TEST(Tracker, ConfirmedAfterNInitHits) {
  Tracker tracker(motion_only());
  std::vector<Association> a;
  for (int k = 0; k < 3; ++k) {
    a = tracker.step({det(100 + 2 * k, 100)});
    ASSERT_EQ(a.size(), 1u);
    EXPECT_EQ(a[0].track_id, 1);
    EXPECT_EQ(a[0].hit, k + 1);
    EXPECT_EQ(a[0].confirmed, k == 2) << k;
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_EQ(tracker.tracks()[0].track_state, TrackState::kConfirmed);
}

TEST(Tracker, TentativeTrackDeletedOnAMiss) {
  Tracker tracker(motion_only());
  tracker.step({det(100, 100)});
  tracker.step({det(100, 100)});
  tracker.step({});  // miss while tentative: deleted
  EXPECT_TRUE(tracker.tracks().empty());
  EXPECT_EQ(tracker.step({det(100, 100)})[0].track_id, 2);
}

// A confirmed track is found again by the cascade after up to max_age - 1 missed frames (at the
// next frame its time since update is <= max_age, the cascade's depth), and deleted after more.
TEST(Tracker, ConfirmedTrackLivesMaxAgeMisses) {
  for (const int misses : {4, 5}) {
    TrackerOptions o = motion_only();
    o.max_age = 5;
    Tracker tracker(o);
    for (int k = 0; k < 5; ++k) tracker.step({det(100, 100)});
    for (int k = 0; k < misses; ++k) tracker.step({});
    const auto a = tracker.step({det(100, 100)});
    EXPECT_EQ(a[0].track_id, misses <= 4 ? 1 : 2) << misses;
    EXPECT_EQ(a[0].confirmed, misses <= 4) << misses;
  }
}

TEST(Tracker, SameClassOnlyUnlessAsked) {
  for (const bool same_class : {true, false}) {
    TrackerOptions o = motion_only();
    o.same_class_only = same_class;
    Tracker tracker(o);
    for (int k = 0; k < 4; ++k) tracker.step({det(100, 100, "cup")});
    const auto a = tracker.step({det(100, 100, "bowl")});
    EXPECT_EQ(a[0].track_id, same_class ? 2 : 1);
  }
}

TEST(Tracker, LowScoreIsNotTracked) {
  TrackerOptions o = motion_only();
  o.min_score = 0.5;
  Tracker tracker(o);
  Detection low = det(100, 100);
  low.score = 0.3;
  const auto a = tracker.step({det(300, 100), low});
  EXPECT_EQ(a[0].track_id, 1);
  EXPECT_EQ(a[1].track_id, 0);
}

// Two objects side by side are hidden for two frames and come back with their places swapped (10
// px apart, inside the Mahalanobis gate). Motion alone keeps the ids on the places; the appearance
// gallery makes them follow the objects.
TEST(Tracker, AppearanceFollowsObjectsThroughASwap) {
  Descriptor red = Descriptor::Zero(4), blue = Descriptor::Zero(4);
  red(0) = 1;
  blue(3) = 1;
  for (const bool appearance : {true, false}) {
    TrackerOptions o;
    o.use_appearance = appearance;
    Tracker tracker(o);
    const auto with = [](Detection d, const Descriptor& desc) {
      d.descriptor = desc;
      return d;
    };
    std::vector<Association> a;
    for (int k = 0; k < 5; ++k)
      a = tracker.step({with(det(100, 100), red), with(det(110, 100), blue)});
    const int red_id = a[0].track_id, blue_id = a[1].track_id;
    tracker.step({});
    tracker.step({});
    a = tracker.step({with(det(110, 100), red), with(det(100, 100), blue)});
    if (appearance) {
      EXPECT_EQ(a[0].track_id, red_id);
      EXPECT_EQ(a[1].track_id, blue_id);
    } else {
      EXPECT_EQ(a[0].track_id, blue_id);
      EXPECT_EQ(a[1].track_id, red_id);
    }
  }
}

TEST(Tracker, MissingDescriptorWithAppearanceIsAnError) {
  Tracker tracker;  // use_appearance by default
  EXPECT_THROW(tracker.step({det(0, 0)}), InputError);
}

// The colour descriptor of a red square is close to another red square's and far from a blue
// one's; a mask restricts it to the instance's own pixels.
TEST(Appearance, ColourDescriptorSeparatesColours) {
  cv::Mat image(60, 120, CV_8UC3, cv::Scalar(0, 0, 200));       // red (BGR)
  image(cv::Rect(60, 0, 60, 60)).setTo(cv::Scalar(200, 0, 0));  // right half blue
  segmentation::Instance left, right, both;
  left.bbox = {0, 0, 60, 60};
  right.bbox = {60, 0, 60, 60};
  both.bbox = {0, 0, 120, 60};
  const Descriptor dl = colour_descriptor(image, left), dr = colour_descriptor(image, right);
  EXPECT_NEAR(dl.norm(), 1.0, 1e-12);
  EXPECT_NEAR(cosine_distance(dl, dl), 0.0, 1e-12);
  EXPECT_GT(cosine_distance(dl, dr), 0.4);
  // The whole box but a mask of the left half only: the same descriptor as the left box.
  segmentation::Mask mask{120, 60, std::vector<std::uint8_t>(120 * 60, 0)};
  for (int v = 0; v < 60; ++v)
    for (int u = 0; u < 60; ++u) mask.data[v * 120 + u] = 1;
  both.mask = mask;
  EXPECT_NEAR(cosine_distance(colour_descriptor(image, both), dl), 0.0, 1e-12);
}

TEST(Tracker, BoxIou) {
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 10, 10}, {5, 0, 10, 10}), 50.0 / 150.0);
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 10, 10}, {20, 0, 10, 10}), 0.0);
}

}  // namespace
}  // namespace objmap::track

namespace objmap::track {
namespace {

segmentation::Segmentation one_object_and_a_flicker() {
  segmentation::Segmentation s;
  s.source = "seg";
  for (int f = 0; f < 4; ++f) {
    segmentation::FrameSegmentation frame;
    frame.timestamp = 10.0 + f;
    segmentation::Instance cup;
    cup.class_name = "cup";
    cup.bbox = {100.0 + f, 100, 40, 80};
    cup.track_id = 99;  // input ids are ignored
    frame.instances.push_back(cup);
    if (f == 1) {  // a one-frame false positive: never confirmed, no id
      segmentation::Instance ghost = cup;
      ghost.bbox = {400, 300, 30, 30};
      frame.instances.push_back(ghost);
    }
    s.frames.push_back(frame);
  }
  return s;
}

TEST(TrackSegmentation, ConfirmedTracksOnlyWithTentativeHistory) {
  for (const bool history : {true, false}) {
    TrackOptions o;
    o.tracker.use_appearance = false;
    o.label_tentative_history = history;
    const TrackResult r = track_segmentation(one_object_and_a_flicker(), o);
    ASSERT_EQ(r.tracks.size(), 1u);
    EXPECT_EQ(r.tracks_started, 2u);
    EXPECT_EQ(r.tracks[0].id, 1);
    EXPECT_EQ(r.tracks[0].class_name, "cup");
    EXPECT_EQ(r.tracks[0].first_frame, history ? 0u : 2u);
    EXPECT_EQ(r.tracks[0].last_frame, 3u);
    EXPECT_EQ(r.tracks[0].length, history ? 4u : 2u);
    EXPECT_EQ(r.instances, 5u);
    EXPECT_EQ(r.instances_tracked, history ? 4u : 2u);
    EXPECT_FALSE(r.tracked.frames[1].instances[1].track_id.has_value());  // the flicker
    EXPECT_EQ(r.tracked.frames[0].instances[0].track_id.has_value(), history);
    EXPECT_EQ(r.tracked.frames[3].instances[0].track_id, std::optional<int>(1));
  }
}

TEST(TrackSegmentation, NoInstanceIsAnError) {
  segmentation::Segmentation s;
  s.source = "seg";
  s.frames.resize(3);
  TrackOptions o;
  o.tracker.use_appearance = false;
  try {
    track_segmentation(s, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "seg: no instance in any of the 3 frames; expected detections to track");
  }
}

}  // namespace
}  // namespace objmap::track
