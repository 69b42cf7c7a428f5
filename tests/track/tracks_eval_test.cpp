// CLEAR-MOT and IDF1 on a hand-made case whose values are computed by hand below.
#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "objmap/eval/tracks.h"

namespace objmap::eval {
namespace {

using segmentation::Box;
using segmentation::FrameSegmentation;
using segmentation::Instance;
using segmentation::Segmentation;

Instance inst(int id, Box box, std::string cls = "cup") {
  Instance i;
  i.class_name = std::move(cls);
  i.track_id = id;
  i.bbox = box;
  return i;
}

Segmentation frames(std::vector<std::vector<Instance>> per_frame) {
  Segmentation s;
  for (std::size_t f = 0; f < per_frame.size(); ++f) {
    FrameSegmentation fs;
    fs.timestamp = 100.0 + 0.1 * static_cast<double>(f);
    fs.instances = std::move(per_frame[f]);
    s.frames.push_back(std::move(fs));
  }
  return s;
}

const Box kA{0, 0, 10, 10}, kB{100, 0, 10, 10}, kC{200, 0, 10, 10};

// Ground truth: objects A (id 1), B (id 2) in frames 0-3, C (id 3) in frames 0-1: 10 detections.
// Estimate (hypothesis ids 11, 12, 13, 19):
//   f0: A->11 (box shifted 2 px: IoU 80/120 = 2/3), B->12, C->14
//   f1: A->11, B->12, C->14, false positive 19 far away, one instance without track id (ignored)
//   f2: A->11, B missed
//   f3: A->11, B->13 (B gets a new id after the miss: one ID switch, one fragmentation)
// CLEAR-MOT: matches 9, misses 1, false positives 1, ID switches 1 over 10 gt detections:
//   MOTA = 1 - (1 + 1 + 1) / 10 = 0.7; MOTP = (8 x 1 + 2/3) / 9 = 26/27.
//   MT (>= 80% matched): A (4/4), C (2/2); PT: B (3/4); ML: none. Fragmentations: 1 (B).
// IDF1: hypotheses 11: 4, 12: 2, 13: 1, 14: 2, 19: 1 -> 10 detections. Best trajectory matching
//   A-11 (4 frames), B-12 (2), C-14 (2): IDTP = 8, IDFN = 10 - 8 = 2, IDFP = 10 - 8 = 2,
//   IDF1 = 2 x 8 / (10 + 10) = 0.8, IDP = IDR = 0.8.
TEST(TracksEval, HandMadeCaseExactValues) {
  const Segmentation gt = frames({{inst(1, kA), inst(2, kB), inst(3, kC)},
                                  {inst(1, kA), inst(2, kB), inst(3, kC)},
                                  {inst(1, kA), inst(2, kB)},
                                  {inst(1, kA), inst(2, kB)}});
  Instance untracked = inst(0, kA);
  untracked.track_id.reset();
  const Segmentation est =
      frames({{inst(11, {2, 0, 10, 10}), inst(12, kB), inst(14, kC)},
              {inst(11, kA), inst(12, kB), inst(14, kC), inst(19, {300, 300, 10, 10}), untracked},
              {inst(11, kA)},
              {inst(11, kA), inst(13, kB)}});
  const TrackEvalResult r = evaluate_tracks(gt, est);
  EXPECT_EQ(r.frames, 4u);
  EXPECT_EQ(r.gt_instances, 10u);
  EXPECT_EQ(r.est_instances, 10u);
  EXPECT_EQ(r.est_untracked, 1u);
  EXPECT_EQ(r.matches, 9u);
  EXPECT_EQ(r.misses, 1u);
  EXPECT_EQ(r.false_positives, 1u);
  EXPECT_EQ(r.id_switches, 1u);
  EXPECT_EQ(r.fragmentations, 1u);
  EXPECT_DOUBLE_EQ(r.mota, 0.7);
  EXPECT_NEAR(r.motp, 26.0 / 27.0, 1e-12);
  EXPECT_EQ(r.gt_tracks, 3u);
  EXPECT_EQ(r.est_tracks, 5u);
  EXPECT_EQ(r.mostly_tracked, 2u);
  EXPECT_EQ(r.partially_tracked, 1u);
  EXPECT_EQ(r.mostly_lost, 0u);
  EXPECT_EQ(r.idtp, 8u);
  EXPECT_EQ(r.idfp, 2u);
  EXPECT_EQ(r.idfn, 2u);
  EXPECT_DOUBLE_EQ(r.idf1, 0.8);
  EXPECT_DOUBLE_EQ(r.idp, 0.8);
  EXPECT_DOUBLE_EQ(r.idr, 0.8);
}

// A perfect estimate with other id numbers: MOTA = MOTP = IDF1 = 1, no switch.
TEST(TracksEval, PerfectEstimateWithRenamedIds) {
  const Segmentation gt = frames({{inst(1, kA), inst(2, kB)}, {inst(1, kA), inst(2, kB)}});
  const Segmentation est = frames({{inst(7, kB), inst(5, kA)}, {inst(5, kA), inst(7, kB)}});
  const TrackEvalResult r = evaluate_tracks(gt, est);
  EXPECT_DOUBLE_EQ(r.mota, 1.0);
  EXPECT_DOUBLE_EQ(r.motp, 1.0);
  EXPECT_DOUBLE_EQ(r.idf1, 1.0);
  EXPECT_EQ(r.id_switches, 0u);
}

// CLEAR-MOT keeps last frame's correspondence while it stays admissible, even when another
// hypothesis fits better: no switch. The box IoU of the shifted kept box is 0.6 (>= 0.5).
TEST(TracksEval, KeepsPreviousCorrespondenceWhileAdmissible) {
  const Segmentation gt = frames({{inst(1, kA)}, {inst(1, kA)}});
  const Segmentation est = frames({{inst(5, kA)}, {inst(5, {2.5, 0, 10, 10}), inst(6, kA)}});
  const TrackEvalResult r = evaluate_tracks(gt, est);
  EXPECT_EQ(r.id_switches, 0u);
  EXPECT_EQ(r.false_positives, 1u);
  EXPECT_NEAR(r.motp, (1.0 + 0.6) / 2.0, 1e-12);
}

// Below the IoU threshold a pair is a miss and a false positive.
TEST(TracksEval, BelowMinIouIsMissAndFalsePositive) {
  const Segmentation gt = frames({{inst(1, kA)}});
  const Segmentation est = frames({{inst(5, {5, 0, 10, 10})}});  // IoU 50/150 = 1/3
  const TrackEvalResult r = evaluate_tracks(gt, est);
  EXPECT_EQ(r.matches, 0u);
  EXPECT_EQ(r.misses, 1u);
  EXPECT_EQ(r.false_positives, 1u);
  EXPECT_DOUBLE_EQ(r.mota, -1.0);
}

// Masks are compared pixel by pixel when both instances have one: boxes equal, masks half
// overlapping -> IoU 1/3.
TEST(TracksEval, MaskIouWhenBothHaveMasks) {
  Instance a = inst(1, {0, 0, 4, 2}), b = inst(2, {0, 0, 4, 2});
  segmentation::Mask ma{4, 2, std::vector<std::uint8_t>(8, 0)}, mb = ma;
  for (int u = 0; u < 2; ++u) ma.data[u] = ma.data[4 + u] = 1;  // columns 0-1
  for (int u = 1; u < 3; ++u) mb.data[u] = mb.data[4 + u] = 1;  // columns 1-2
  a.mask = ma;
  b.mask = mb;
  EXPECT_NEAR(instance_iou(a, b), 2.0 / 6.0, 1e-12);
  b.mask.reset();
  EXPECT_DOUBLE_EQ(instance_iou(a, b), 1.0);  // one without mask: boxes
}

TEST(TracksEval, GroundTruthWithoutTrackIdIsAnError) {
  Segmentation gt = frames({{inst(1, kA)}});
  gt.source = "gt_dir";
  gt.frames[0].instances[0].track_id.reset();
  gt.frames[0].source = "gt_dir/100.000000.json";
  try {
    evaluate_tracks(gt, frames({{}}));
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "gt_dir/100.000000.json");
    EXPECT_NE(e.reason().find("no track_id"), std::string::npos);
  }
}

}  // namespace
}  // namespace objmap::eval
