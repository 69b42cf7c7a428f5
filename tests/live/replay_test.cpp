// objmap replay: the recording written again as it was (listings, trajectory, per-frame files), the
// loop closure's rewrite ending on the source's poses, and the folders it refuses.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "live_scene.h"

namespace objmap::test {
namespace {

TEST(Replay, WritesTheRecordingAsItWasAndDoneAtTheEnd) {
  const fs::path scene = live_scene(30);
  ASSERT_FALSE(scene.empty());
  TempDir tmp;
  const auto r = run_objmap({"replay", "--dataset", scene.string(), "--out", (tmp / "r").string(),
                             "--trajectory", (scene / "estimated.txt").string(), "--speed", "10"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const std::string f : {"rgb.txt", "depth.txt", "estimated.txt", "camera.json"})
    EXPECT_EQ(read_text(tmp / "r" / f), read_text(scene / f)) << f;
  std::size_t seg = 0;
  for (const auto& e : fs::directory_iterator(scene / "segmentation")) {
    EXPECT_EQ(read_text(tmp / "r/segmentation" / e.path().filename()), read_text(e.path()));
    ++seg;
  }
  EXPECT_EQ(seg, 30u);
  EXPECT_TRUE(fs::exists(tmp / "r/done"));
  EXPECT_NE(r.out.find("replayed      30 frames"), std::string::npos) << r.out;
  // No temporary file is left behind.
  for (const auto& e : fs::recursive_directory_iterator(tmp / "r"))
    EXPECT_EQ(e.path().filename().string().find(".replay-tmp"), std::string::npos) << e.path();
}

// A follower may watch the folder from before the replay starts: the folder itself is kept (its
// removal ends objmap follow), an earlier replay's files in it are replaced.
TEST(Replay, KeepsTheFolderItWritesIntoAndReplacesAnEarlierReplay) {
  const fs::path scene = live_scene(30);
  ASSERT_FALSE(scene.empty());
  TempDir tmp;
  fs::create_directories(tmp / "r");
  // An open handle on the folder: a removed folder shows no link left.
  const int fd = ::open((tmp / "r").c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  const std::vector<std::string> args{
      "replay", "--dataset", scene.string(), "--out", (tmp / "r").string(), "--speed", "20"};
  ASSERT_EQ(run_objmap(args).exit_code, 0);
  write_text(tmp / "r/rgb/stale.png", "an earlier replay's leftover");
  const auto again = run_objmap(args);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  struct stat after {};
  ASSERT_EQ(::fstat(fd, &after), 0);
  ::close(fd);
  EXPECT_GT(after.st_nlink, 0u) << "the folder was removed and made again";
  EXPECT_FALSE(fs::exists(tmp / "r/rgb/stale.png"));
  EXPECT_EQ(read_text(tmp / "r/rgb.txt"), read_text(scene / "rgb.txt"));
}

TEST(Replay, TheLoopClosureRewriteEndsOnTheSourcesPoses) {
  const fs::path scene = live_scene(30);
  ASSERT_FALSE(scene.empty());
  TempDir tmp;
  const auto r = run_objmap({"replay", "--dataset", scene.string(), "--out", (tmp / "r").string(),
                             "--trajectory", (scene / "estimated.txt").string(), "--speed", "10",
                             "--rewrite-at", "0.5"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_text(tmp / "r/estimated.txt"), read_text(scene / "estimated.txt"));
  const auto doc = nlohmann::json::parse(read_text(tmp / "r/replay.json"));
  EXPECT_EQ(doc.at("rewrite_at").get<double>(), 0.5);
  EXPECT_GT(doc.at("rewrite_time").get<double>(), 0.0);
}

TEST(Replay, RefusesAnOutputInsideTheRecordingOrThatIsNotAReplay) {
  const fs::path scene = live_scene(30);
  ASSERT_FALSE(scene.empty());
  TempDir tmp;
  const auto inside =
      run_objmap({"replay", "--dataset", scene.string(), "--out", (scene / "x").string()});
  EXPECT_EQ(inside.exit_code, 2);
  EXPECT_NE(inside.err.find("lies inside the recording"), std::string::npos) << inside.err;
  EXPECT_FALSE(fs::exists(scene / "x"));
  write_text(tmp / "other/notes.txt", "mine");
  const auto other =
      run_objmap({"replay", "--dataset", scene.string(), "--out", (tmp / "other").string()});
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_EQ(read_text(tmp / "other/notes.txt"), "mine");
  const auto missing =
      run_objmap({"replay", "--dataset", (tmp / "nope").string(), "--out", (tmp / "r").string()});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
}

}  // namespace
}  // namespace objmap::test
