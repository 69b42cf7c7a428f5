#include "objmap/eval/associate.h"

#include <gtest/gtest.h>

#include "eval_test_util.h"
#include "objmap/core/error.h"

namespace objmap::eval {
namespace {

using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;

Pairs pairs_of(const std::vector<StampMatch>& matches) {
  Pairs out;
  for (const StampMatch& m : matches) out.emplace_back(m.gt_index, m.est_index);
  return out;
}

TEST(Associate, ContestedStampGoesToTheCloserPartnerOneToOne) {
  // Candidates (< 0.02 s): g0-e0 0.006, g1-e0 0.004, g1-e1 0.010 (g0-e1 is 0.02, not < 0.02).
  // Greedy by difference: g1-e0 first; then g1 and e0 are taken, so g0 and e1 stay unmatched
  // although each had a partner within max_diff.
  const std::vector<double> gt = {1.000, 1.010};
  const std::vector<double> est = {1.006, 1.020};
  EXPECT_EQ(pairs_of(associate(gt, est, {})), (Pairs{{1, 0}}));
}

TEST(Associate, GreedyByDifferenceThenSortedByTime) {
  // e0 is 0.004 from g1 and 0.006 from g0; e1 is 0.002 from g1 -> e1 wins g1, e0 takes g0.
  const std::vector<double> gt = {2.000, 2.010, 5.0};
  const std::vector<double> est = {2.006, 2.012, 4.99, 9.0};
  EXPECT_EQ(pairs_of(associate(gt, est, {})), (Pairs{{0, 0}, {1, 1}, {2, 2}}));
}

TEST(Associate, OffsetIsAddedToTheEstimateStamps) {
  const std::vector<double> gt = {0.0, 0.1, 0.2, 0.3};
  const std::vector<double> est = {100.005, 100.104, 100.2, 100.5};
  AssociateOptions options;
  EXPECT_TRUE(associate(gt, est, options).empty());
  options.offset_s = -100.0;
  EXPECT_EQ(pairs_of(associate(gt, est, options)), (Pairs{{0, 0}, {1, 1}, {2, 2}}));
}

TEST(Associate, MaxDiffIsStrict) {
  // Binary fractions so that the differences are exact: 1/32 s apart.
  const std::vector<double> gt = {0.0, 1.0};
  const std::vector<double> est = {0.03125};
  AssociateOptions options;
  options.max_diff_s = 0.03125;
  EXPECT_TRUE(associate(gt, est, options).empty());
  options.max_diff_s = 0.0625;
  EXPECT_EQ(pairs_of(associate(gt, est, options)), (Pairs{{0, 0}}));
}

TEST(Associate, UnsortedStampsGiveTheSameMatches) {
  const std::vector<double> gt = {2.010, 5.0, 2.000};
  const std::vector<double> est = {9.0, 2.012, 4.99, 2.006};
  // sorted by gt time: (2.000, 2.006), (2.010, 2.012), (5.0, 4.99)
  EXPECT_EQ(pairs_of(associate(gt, est, {})), (Pairs{{2, 3}, {0, 1}, {1, 2}}));
}

TEST(Associate, BadOptionsAreRejected) {
  AssociateOptions options;
  options.max_diff_s = 0.0;
  EXPECT_THROW(options.check(), InputError);
  options.max_diff_s = 0.02;
  options.offset_s = std::nan("");
  EXPECT_THROW(options.check(), InputError);
}

TEST(Associate, RequirePairsNamesTheEstimateAndSaysWhatIsWrong) {
  using test::make_trajectory;
  const Trajectory gt = make_trajectory({0.0, 1.0}, {Pose::Identity(), Pose::Identity()}, "gt.txt");
  const Trajectory est =
      make_trajectory({50.0, 51.0}, {Pose::Identity(), Pose::Identity()}, "est.txt");
  const AssociateOptions options;
  try {
    require_pairs(associate(gt, est, options), 2, gt, est, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "est.txt");
    EXPECT_EQ(e.reason().rfind("no pose pairs within max_diff 0.02 s", 0), 0u) << e.what();
    EXPECT_NE(e.reason().find("gt.txt"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace objmap::eval
