// io::TrajectoryTail: a trajectory read again as it grows: the line being written waits, a
// malformed line is named once and skipped, a rewritten past is reported.
#include <gtest/gtest.h>

#include "objmap/io/trajectory.h"
#include "objmap/io/trajectory_tail.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

const char* const kTailHeader = "# timestamp tx ty tz qx qy qz qw\n";

TEST(TrajectoryTail, TheLineBeingWrittenWaitsForItsNewline) {
  TempDir tmp;
  io::TrajectoryTail tail(tmp / "t.txt");
  EXPECT_EQ(tail.poll().new_poses, 0u);  // not there yet: no pose, no error
  write_text(tmp / "t.txt", std::string(kTailHeader) + "1.0 0 0 0 0 0 0 1\n2.0 0.1 0 0 0 0");
  const auto first = tail.poll();
  EXPECT_EQ(first.new_poses, 1u);
  EXPECT_TRUE(first.malformed.empty());
  write_text(tmp / "t.txt", std::string(kTailHeader) + "1.0 0 0 0 0 0 0 1\n2.0 0.1 0 0 0 0 0 1\n");
  const auto second = tail.poll();
  EXPECT_EQ(second.new_poses, 1u);
  EXPECT_FALSE(second.rewritten);
  ASSERT_EQ(tail.trajectory().size(), 2u);
  EXPECT_DOUBLE_EQ(tail.trajectory().poses[1].world_from_cam.translation().x(), 0.1);
  EXPECT_EQ(tail.trajectory().poses[1].line, 3u);
}

TEST(TrajectoryTail, AMalformedLineIsNamedOnceSkippedAndCounted) {
  TempDir tmp;
  const fs::path file = tmp / "t.txt";
  io::TrajectoryTail tail(file);
  write_text(file, "1.0 0 0 0 0 0 0 1\n1.5 0 0 x 0 0 0 1\n2.0 0 0 0 0 0 0 1\n1.8 0 0 0 0 0 0 1\n");
  const auto first = tail.poll();
  ASSERT_EQ(first.malformed.size(), 2u);
  EXPECT_NE(first.malformed[0].find(file.string() + ":2: "), std::string::npos)
      << first.malformed[0];
  EXPECT_NE(first.malformed[1].find(file.string() + ":4: "), std::string::npos)
      << first.malformed[1];
  EXPECT_NE(first.malformed[1].find("skipped"), std::string::npos);
  EXPECT_EQ(tail.trajectory().size(), 2u);
  EXPECT_TRUE(tail.poll().malformed.empty());  // named once
  EXPECT_EQ(tail.malformed(), 2u);
  EXPECT_EQ(tail.lines(), 4u);
}

TEST(TrajectoryTail, ARewrittenPastIsReported) {
  TempDir tmp;
  const fs::path file = tmp / "t.txt";
  io::TrajectoryTail tail(file);
  write_text(file, "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n");
  EXPECT_FALSE(tail.poll().rewritten);
  write_text(file, "1.0 0.05 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n3.0 0 0 0 0 0 0 1\n");
  const auto poll = tail.poll();
  EXPECT_TRUE(poll.rewritten);
  EXPECT_EQ(poll.new_poses, 1u);
  EXPECT_EQ(tail.rewrites(), 1u);
}

// Found by fuzz_trajectory_tail: a line of separators only (",,,") and a comment after a vertical
// tab were named malformed, while read_trajectory, which fuse uses, skips them.
TEST(TrajectoryTail, SkipsTheLinesReadTrajectorySkips) {
  TempDir tmp;
  const fs::path file = tmp / "t.txt";
  write_text(file, "1.0 0 0 0 0 0 0 1\n,,,\n\v# comment\n \f\n\r \n2.0 0 0 0 0 0 0 1\n");
  io::TrajectoryTail tail(file);
  const auto poll = tail.poll();
  EXPECT_TRUE(poll.malformed.empty()) << poll.malformed.front();
  EXPECT_EQ(tail.malformed(), 0u);
  EXPECT_EQ(tail.lines(), 2u);
  ASSERT_EQ(tail.trajectory().size(), 2u);
  EXPECT_EQ(tail.trajectory().poses[1].line, 6u);
  EXPECT_EQ(io::read_trajectory(file).size(), 2u);
}

}  // namespace
}  // namespace objmap::test
