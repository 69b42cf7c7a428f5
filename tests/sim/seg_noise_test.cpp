#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include <opencv2/imgproc.hpp>

#include "objmap/core/error.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/seg_noise.h"
#include "objmap/sim/synth.h"

namespace objmap::sim {
namespace {

namespace seg = objmap::segmentation;

// A tiny label image with four objects (ids 1..4) as rectangles, and a scene that names them.
struct Fixture {
  Scene scene;
  cv::Mat labels;
  Fixture() {
    const char* classes[] = {"teddy bear", "mouse", "cup", "book"};
    for (int i = 0; i < 4; ++i) {
      SceneObject o;
      o.id = i + 1;
      o.class_name = classes[i];
      scene.objects.push_back(o);
    }
    labels = cv::Mat(60, 80, CV_16UC1, cv::Scalar::all(0));
    labels(cv::Rect(5, 5, 20, 20)).setTo(1);
    labels(cv::Rect(40, 5, 15, 10)).setTo(2);
    labels(cv::Rect(5, 35, 12, 18)).setTo(3);
    labels(cv::Rect(40, 30, 30, 25)).setTo(4);
  }
};

double iou(const seg::Mask& a, const seg::Mask& b) {
  std::size_t inter = 0, uni = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    inter += a.data[i] && b.data[i];
    uni += a.data[i] || b.data[i];
  }
  return uni ? static_cast<double>(inter) / uni : 0.0;
}

TEST(SegNoise, ExactSegmentationHasOneInstancePerVisibleObject) {
  Fixture f;
  const auto exact = exact_segmentation(f.labels, f.scene, 12.5, 50);
  ASSERT_EQ(exact.instances.size(), 4u);
  EXPECT_EQ(exact.instances[0].class_name, "teddy bear");
  EXPECT_EQ(*exact.instances[1].track_id, 2);
  EXPECT_EQ(exact.instances[3].bbox.x, 40);
  EXPECT_EQ(exact.instances[3].bbox.w, 30);
  EXPECT_EQ(exact.instances[3].bbox.h, 25);
  std::size_t area = 0;
  for (auto b : exact.instances[2].mask->data) area += b;
  EXPECT_EQ(area, 12u * 18u);
  // A minimum area above the mouse's 150 pixels drops it.
  EXPECT_EQ(exact_segmentation(f.labels, f.scene, 12.5, 151).instances.size(), 3u);
}

TEST(SegNoise, ErrorsOccurAtTheConfiguredRates) {
  Fixture f;
  const auto exact = exact_segmentation(f.labels, f.scene, 0.0, 10);
  SegNoiseOptions o;
  o.miss_prob = 0.2;
  o.confusions = {{"teddy bear", "person", 0.5}, {"mouse", "cup", 0.25}};
  o.false_positives_per_frame = 0.0;  // separately below: a spurious ellipse may overlap an object
  o.id_switch_prob = 0.05;
  o.boundary_px = 1;
  SegmentationNoise noise(o, 11);
  const int frames = 600;
  int detected = 0, teddy = 0, teddy_person = 0, mouse = 0, mouse_cup = 0, spurious = 0;
  int switches = 0;
  std::map<int, int> last_track;  // object -> last track id seen
  std::map<int, std::set<int>> objects_of_track;
  for (int k = 0; k < frames; ++k) {
    const auto out = noise.apply(exact, f.labels.cols, f.labels.rows);
    for (const auto& inst : out.instances) {
      // Match to the truth by IoU.
      int object = 0;
      for (const auto& truth : exact.instances)
        if (iou(*truth.mask, *inst.mask) > 0.5) object = *truth.track_id;
      if (object == 0) {
        ++spurious;
        EXPECT_LE(inst.score, 0.6);
        continue;
      }
      ++detected;
      EXPECT_GE(inst.score, o.score_min);
      if (object == 1) {
        ++teddy;
        teddy_person += inst.class_name == "person";
      }
      if (object == 2) {
        ++mouse;
        mouse_cup += inst.class_name == "cup";
      }
      if (last_track.count(object) && last_track[object] != *inst.track_id) ++switches;
      last_track[object] = *inst.track_id;
      objects_of_track[*inst.track_id].insert(object);
    }
  }
  const double n = frames * 4.0;
  EXPECT_NEAR(1.0 - detected / n, 0.2, 0.03);  // sd 0.008
  EXPECT_NEAR(static_cast<double>(teddy_person) / teddy, 0.5, 0.07);
  EXPECT_NEAR(static_cast<double>(mouse_cup) / mouse, 0.25, 0.06);
  EXPECT_EQ(spurious, 0);
  // 2400 instance-frames at 5%: ~120 switches; the observed changes include those hidden by misses.
  EXPECT_NEAR(noise.stats().id_switches, 120, 40);
  EXPECT_GT(switches, 60);
  EXPECT_LE(switches, noise.stats().id_switches);
  // Re-used IDs: some track id was worn by two different objects over time.
  EXPECT_GT(noise.stats().id_reuses, 0);
  int shared = 0;
  for (const auto& [track, objects] : objects_of_track) shared += objects.size() > 1;
  EXPECT_GT(shared, 0);
  EXPECT_EQ(noise.stats().missed + detected, noise.stats().true_instances);
}

TEST(SegNoise, FalsePositivesAtTheConfiguredRate) {
  Fixture f;
  const auto exact = exact_segmentation(f.labels, f.scene, 0.0, 10);
  SegNoiseOptions o;
  o.miss_prob = 1.0;  // every true instance is missed: what remains is spurious
  o.false_positives_per_frame = 0.5;
  SegmentationNoise noise(o, 4);
  int spurious = 0;
  std::set<int> ids;
  const int frames = 1000;
  for (int k = 0; k < frames; ++k)
    for (const auto& inst : noise.apply(exact, f.labels.cols, f.labels.rows).instances) {
      ++spurious;
      EXPECT_LE(inst.score, 0.6);
      EXPECT_GT(inst.mask->data.size(), 0u);
      EXPECT_TRUE(ids.insert(*inst.track_id).second);  // a fresh ID each time
    }
  EXPECT_NEAR(spurious / static_cast<double>(frames), 0.5, 0.07);  // sd 0.022
  EXPECT_EQ(noise.stats().false_positives, spurious);
}

TEST(SegNoise, NoneGivesTheExactSegmentationWithStableIds) {
  Fixture f;
  const auto exact = exact_segmentation(f.labels, f.scene, 0.0, 10);
  SegmentationNoise noise(SegNoiseOptions::none(), 1);
  std::map<int, int> track_of_object;
  for (int k = 0; k < 20; ++k) {
    const auto out = noise.apply(exact, f.labels.cols, f.labels.rows);
    ASSERT_EQ(out.instances.size(), exact.instances.size());
    for (std::size_t i = 0; i < out.instances.size(); ++i) {
      EXPECT_EQ(out.instances[i].class_name, exact.instances[i].class_name);
      EXPECT_EQ(out.instances[i].mask->data, exact.instances[i].mask->data);
      const int object = *exact.instances[i].track_id;
      if (k == 0) track_of_object[object] = *out.instances[i].track_id;
      EXPECT_EQ(*out.instances[i].track_id, track_of_object[object]);
    }
  }
}

TEST(SegNoise, BoundaryNoiseErodesOrDilates) {
  Fixture f;
  const auto exact = exact_segmentation(f.labels, f.scene, 0.0, 10);
  SegNoiseOptions o = SegNoiseOptions::none();
  o.boundary_px = 2;
  SegmentationNoise noise(o, 5);
  int smaller = 0, larger = 0;
  for (int k = 0; k < 50; ++k) {
    const auto out = noise.apply(exact, f.labels.cols, f.labels.rows);
    const auto a = [](const seg::Mask& m) {
      std::size_t n = 0;
      for (auto b : m.data) n += b;
      return n;
    };
    for (std::size_t i = 0; i < out.instances.size(); ++i) {
      const std::size_t got = a(*out.instances[i].mask), want = a(*exact.instances[i].mask);
      smaller += got < want;
      larger += got > want;
      EXPECT_GT(iou(*out.instances[i].mask, *exact.instances[i].mask), 0.4);
    }
  }
  EXPECT_GT(smaller, 20);
  EXPECT_GT(larger, 20);
}

TEST(SegNoise, SmallSceneMakesMissesAndConfusions) {
  SynthOptions options;
  options.frames = 30;
  options.resolution_scale = 0.25;
  options.seg_noise.min_area_px = 10;
  options.seg_noise.boundary_px = 0;  // no masks eroded away: misses are the miss knob only
  options.seg_noise.false_positives_per_frame = 0.0;
  options.seg_noise.miss_prob = 0.25;
  options.seg_noise.confusions = {{"teddy bear", "person", 0.5}, {"mouse", "cup", 0.5}};
  const SynthSequence seq = synthesize(options);
  int truth = 0, reported_true = 0, person = 0, teddy = 0;
  for (const auto& f : seq.frames) {
    truth += static_cast<int>(f.segmentation_gt.instances.size());
    for (const auto& t : f.segmentation_gt.instances) teddy += t.class_name == "teddy bear";
    for (const auto& i : f.segmentation.instances) {
      reported_true += i.score >= options.seg_noise.score_min;
      person += i.class_name == "person" && i.score >= options.seg_noise.score_min;
    }
  }
  ASSERT_GT(truth, 200);
  EXPECT_NEAR(1.0 - static_cast<double>(reported_true) / truth, 0.25, 0.08);
  ASSERT_GT(teddy, 20);
  EXPECT_NEAR(static_cast<double>(person) / (teddy * 0.75), 0.5, 0.25);
}

// 80 x 60 px: an object (mask) at 1 m, an occluder at 0.5 m touching its left side, the table
// 2 cm behind it along its bottom, the wall at 3 m everywhere else.
struct BleedFixture {
  cv::Mat mask = cv::Mat(60, 80, CV_8UC1, cv::Scalar::all(0));
  cv::Mat depth_m = cv::Mat(60, 80, CV_32FC1, cv::Scalar::all(3.0));
  cv::Rect object{30, 20, 20, 20}, occluder{20, 15, 10, 30}, table{20, 40, 40, 20};
  BleedFixture() {
    mask(object).setTo(1);
    depth_m(object).setTo(1.0);
    depth_m(table).setTo(1.02);
    depth_m(occluder).setTo(0.5);
  }
};

TEST(SegNoise, BleedReachesThePixelsBehindTheObjectNeverAnOccluder) {
  const BleedFixture f;
  const int r = 2;
  const cv::Mat region = bleed_region(f.mask, f.depth_m, r);
  cv::Mat reach;
  cv::dilate(f.mask, reach, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}));
  int on_wall = 0, on_table = 0;
  for (int v = 0; v < region.rows; ++v)
    for (int u = 0; u < region.cols; ++u) {
      const bool in_ring = reach.at<std::uint8_t>(v, u) && !f.mask.at<std::uint8_t>(v, u);
      const bool on_occluder = f.occluder.contains({u, v});
      // Exactly the ring around the mask minus the occluder: wall and table (behind) are taken.
      EXPECT_EQ(region.at<std::uint8_t>(v, u) != 0, in_ring && !on_occluder) << u << "," << v;
      if (!region.at<std::uint8_t>(v, u)) continue;
      (f.table.contains({u, v}) ? on_table : on_wall) += 1;
    }
  EXPECT_GT(on_table, 2 * 20);  // two rows below the 20 px wide bottom edge
  EXPECT_GT(on_wall, 2 * 20);
  // Off, or an empty mask: nothing.
  EXPECT_EQ(cv::countNonZero(bleed_region(f.mask, f.depth_m, 0)), 0);
  EXPECT_EQ(cv::countNonZero(bleed_region(cv::Mat::zeros(60, 80, CV_8UC1), f.depth_m, r)), 0);
}

TEST(SegNoise, BleedAddsPixelsAndChangesNothingElse) {
  // With every other error on, the bleed takes no random draws: misses, classes, scores, ids and
  // the boundary noise stay as they are; the masks only grow, by the bleed region.
  const BleedFixture f;
  Fixture labels;
  labels.labels.setTo(0);
  labels.labels.setTo(1, f.mask);
  const auto exact = exact_segmentation(labels.labels, labels.scene, 0.0, 10);
  ASSERT_EQ(exact.instances.size(), 1u);
  SegNoiseOptions o;
  o.miss_prob = 0.2;
  o.false_positives_per_frame = 0.5;
  o.id_switch_prob = 0.1;
  SegNoiseOptions bleeding = o;
  bleeding.bleed_px = 3;
  SegmentationNoise plain(o, 3), same_with_depth(o, 3), bled(bleeding, 3);
  const cv::Mat region = bleed_region(f.mask, f.depth_m, 3);
  int grown = 0;
  for (int k = 0; k < 100; ++k) {
    const auto a = plain.apply(exact, 80, 60);
    const auto b = same_with_depth.apply(exact, 80, 60, f.depth_m);
    const auto c = bled.apply(exact, 80, 60, f.depth_m);
    ASSERT_EQ(a.instances.size(), b.instances.size());
    ASSERT_EQ(a.instances.size(), c.instances.size());
    for (std::size_t i = 0; i < a.instances.size(); ++i) {
      EXPECT_EQ(a.instances[i].mask->data, b.instances[i].mask->data);  // bleed 0: as before
      EXPECT_EQ(a.instances[i].class_name, c.instances[i].class_name);
      EXPECT_EQ(a.instances[i].score, c.instances[i].score);
      EXPECT_EQ(a.instances[i].track_id, c.instances[i].track_id);
      cv::Mat expected = to_mat(*a.instances[i].mask);
      if (iou(*a.instances[i].mask, *exact.instances[0].mask) > 0.5) {  // not a spurious one
        cv::bitwise_or(expected, region, expected);
        grown += cv::countNonZero(expected) > cv::countNonZero(to_mat(*a.instances[i].mask));
      }
      EXPECT_EQ(to_mask(expected).data, c.instances[i].mask->data) << "frame " << k;
    }
  }
  EXPECT_GT(grown, 50);
  EXPECT_GT(bled.stats().bleed_pixels, 0);
  EXPECT_EQ(plain.stats().bleed_pixels, 0);
}

TEST(SegNoise, EdgeSceneMasksBleedFarBehindTheObjects) {
  // The "edge" preset, exact segmentation plus a 3 px bleed: every added pixel lies within 3 px of
  // the exact mask and behind each mask pixel within 3 px of it, and many of them lie far behind.
  SynthOptions options;
  options.preset = "edge";
  options.frames = 8;
  options.orbit_speed_deg_per_s = 60.0;  // 16 degrees of the orbit
  options.resolution_scale = 0.5;
  options.set_noise_free();
  options.seg_noise.min_area_px = 10;
  options.seg_noise.bleed_px = 3;
  const int r = options.seg_noise.bleed_px;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1});
  const SynthSequence seq = synthesize(options);
  long added = 0, far_behind = 0, on_objects = 0;
  for (const auto& f : seq.frames) {
    // No misses, no false positives: the noisy instances are the exact ones, in order.
    ASSERT_EQ(f.segmentation.instances.size(), f.segmentation_gt.instances.size());
    for (std::size_t i = 0; i < f.segmentation.instances.size(); ++i) {
      const cv::Mat exact = to_mat(*f.segmentation_gt.instances[i].mask);
      const cv::Mat noisy = to_mat(*f.segmentation.instances[i].mask);
      for (int v = 0; v < exact.rows; ++v)
        for (int u = 0; u < exact.cols; ++u) {
          if (exact.at<std::uint8_t>(v, u)) {
            EXPECT_TRUE(noisy.at<std::uint8_t>(v, u));  // the bleed only adds
            continue;
          }
          if (!noisy.at<std::uint8_t>(v, u)) continue;
          ++added;
          // The farthest mask pixel within r (the elliptic kernel of the boundary noise).
          float object_m = -1.0f;
          for (int dv = -r; dv <= r; ++dv)
            for (int du = -r; du <= r; ++du) {
              const int uu = u + du, vv = v + dv;
              if (!kernel.at<std::uint8_t>(dv + r, du + r) || uu < 0 || vv < 0 ||
                  uu >= exact.cols || vv >= exact.rows || !exact.at<std::uint8_t>(vv, uu))
                continue;
              object_m = std::max(object_m, f.depth_exact_m.at<float>(vv, uu));
            }
          const float pixel_m = f.depth_exact_m.at<float>(v, u);
          ASSERT_GT(object_m, 0.0f) << "added pixel farther than " << r << " px from the mask";
          EXPECT_GT(pixel_m, object_m) << "bled onto a pixel in front, frame " << f.index;
          far_behind += pixel_m >= object_m + 0.15f;
          on_objects += f.labels.at<std::uint16_t>(v, u) != 0;
        }
    }
  }
  // Measured (seed 1): 11571 added, 80% of them >= 0.15 m behind (median 2.3 m: the walls), 4%
  // on other objects.
  ASSERT_GT(added, 1000);
  EXPECT_GT(far_behind, added / 2) << added << " added";
  EXPECT_LT(on_objects, added / 10);  // mostly table, floor and walls
  EXPECT_EQ(seq.seg_stats.bleed_pixels, added);
}

// The option check() names, "" when it accepts the options.
std::string named_by_check(const SegNoiseOptions& o) {
  try {
    o.check();
  } catch (const InputError& e) {
    return e.where();
  }
  return "";
}

TEST(SegNoise, AnObjectOutOfViewLongerThanTheLimitComesBackWithANewTrackId) {
  Fixture f;
  const auto exact = exact_segmentation(f.labels, f.scene, 1.0, 1);
  // Object 4 leaves the view for frames 5..44 (40 frames); the others stay in view.
  cv::Mat without = f.labels.clone();
  without.setTo(0, f.labels == 4);
  const auto partial = exact_segmentation(without, f.scene, 1.0, 1);
  auto track_of = [](const seg::FrameSegmentation& s, const std::string& cls) {
    for (const auto& i : s.instances)
      if (i.class_name == cls) return *i.track_id;
    return -1;
  };
  for (const int limit : {0, 30, 60}) {
    SegNoiseOptions o = SegNoiseOptions::none();
    o.new_track_after_frames = limit;
    SegmentationNoise noise(o, 1);
    int before = -1, after = -1, cup_before = -1, cup_after = -1;
    for (int frame = 0; frame < 50; ++frame) {
      const auto out = noise.apply(frame >= 5 && frame < 45 ? partial : exact, 80, 60);
      if (frame == 4) before = track_of(out, "book"), cup_before = track_of(out, "cup");
      if (frame == 45) after = track_of(out, "book"), cup_after = track_of(out, "cup");
    }
    EXPECT_EQ(cup_after, cup_before) << "in view throughout: the same ID, limit " << limit;
    if (limit == 30) {
      EXPECT_NE(after, before) << "out of view 40 frames > 30: a new ID";
      EXPECT_EQ(noise.stats().revisit_ids, 1);
    } else {
      EXPECT_EQ(after, before) << "limit " << limit;
      EXPECT_EQ(noise.stats().revisit_ids, 0);
    }
  }
}

TEST(SegNoise, BadOptionsNameTheKnob) {
  SegNoiseOptions o;
  o.miss_prob = -0.1;
  EXPECT_EQ(named_by_check(o), "--miss-rate");
  o = SegNoiseOptions();
  o.bleed_px = -1;
  EXPECT_EQ(named_by_check(o), "--mask-bleed-px");
  o.bleed_px = 21;
  EXPECT_EQ(named_by_check(o), "--mask-bleed-px");
  // The bleed needs the frame's depth.
  o.bleed_px = 2;
  SegmentationNoise noise(o, 1);
  Fixture f;
  const auto exact = exact_segmentation(f.labels, f.scene, 0.0, 10);
  EXPECT_THROW(noise.apply(exact, f.labels.cols, f.labels.rows), InputError);
}

}  // namespace
}  // namespace objmap::sim
