// objmap fuse: bad input gives exit 2, one line naming the file and what is wrong, and no output.
#include <gtest/gtest.h>

#include "support/test_support.h"

namespace objmap::test {
namespace {

constexpr const char* kFirstFrame = "1305031453.359684";

class FuseBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = data_dir() / "tum/fr1_desk_9";
    if (!fs::exists(data_)) {
      if (data_required()) FAIL() << "real data missing: " << data_;
      GTEST_SKIP() << "real data missing: " << data_;
    }
    fs::create_directories(dir_ / "seg");
  }

  RunResult fuse(const fs::path& trajectory) {
    return run_objmap({"fuse", "--dataset", data_.string(), "--trajectory", trajectory.string(),
                       "--segmentation", (dir_ / "seg").string(), "--out",
                       (dir_ / "run").string()});
  }
  RunResult fuse() { return fuse(data_ / "groundtruth.txt"); }

  // Exit 2, one line on stderr containing `needle`, and nothing written.
  void expect_rejected(const RunResult& r, const std::string& needle) {
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "run"));
    for (const auto& e : fs::directory_iterator(dir_.path()))
      EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  }

  fs::path data_;
  TempDir dir_;
};

TEST_F(FuseBadInput, MaskOfAnotherSizeThanTheImage) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".json"),
             R"({"instances":[{"class":"cup","score":0.9,"bbox":[0,0,2,2],)"
             R"("mask":{"size":[10,10],"counts":"0d1"}}]})");
  expect_rejected(fuse(), "10");
}

TEST_F(FuseBadInput, InstanceOutsideTheImage) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".json"),
             R"({"instances":[{"class":"cup","score":0.9,"bbox":[700,10,50,50]}]})");
  expect_rejected(fuse(), kFirstFrame);
}

TEST_F(FuseBadInput, NoFrameWithAPose) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".json"),
             R"({"instances":[{"class":"cup","score":0.9,"bbox":[10,10,50,50]}]})");
  write_text(dir_ / "traj.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n");
  expect_rejected(fuse(dir_ / "traj.txt"), "traj.txt");
}

TEST_F(FuseBadInput, TrajectoryInNanosecondsIsNamedSo) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".json"),
             R"({"instances":[{"class":"cup","score":0.9,"bbox":[10,10,50,50]}]})");
  write_text(dir_ / "traj_ns.txt",
             "1305031453359684000 0 0 0 0 0 0 1\n1305031453659684000 0 0 0 0 0 0 1\n");
  expect_rejected(fuse(dir_ / "traj_ns.txt"),
                  "traj_ns.txt: no pose within 0.02 s of any of the 9 frames (poses 1.30503e+18 "
                  ".. 1.30503e+18, frames 1305031453.359684 .. 1305031453.627706); expected the "
                  "trajectory of this sequence, timestamps in seconds (these look like "
                  "nanoseconds)");
}

TEST_F(FuseBadInput, EmptySegmentation) { expect_rejected(fuse(), "seg"); }

TEST_F(FuseBadInput, BoxFilesWithoutABoxNameTheFormatFlag) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".txt"), "");
  expect_rejected(fuse(), "--seg-format");
}

// With the layout given, box files without a box are a segmentation with no instance: the run
// makes the dense map and says why there are no objects.
TEST_F(FuseBadInput, NoInstanceWithTheFormatGivenSaysWhyThereAreNoObjects) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".txt"), "");
  const auto r =
      run_objmap({"fuse", "--dataset", data_.string(), "--trajectory",
                  (data_ / "groundtruth.txt").string(), "--segmentation", (dir_ / "seg").string(),
                  "--seg-format", "boxes-named", "--out", (dir_ / "run").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("none in the keyframes' segmentation frames: no objects"), std::string::npos)
      << r.out;
  EXPECT_TRUE(fs::exists(dir_ / "run" / "map_dense.ply"));
}

TEST_F(FuseBadInput, EveryInstanceBelowTheMinScoreSaysWhyThereAreNoObjects) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".txt"),
             "66 keyboard 0.3 20 218 401 433\n62 tvmonitor 0.45 14 0 231 233\n");
  const auto r =
      run_objmap({"fuse", "--dataset", data_.string(), "--trajectory",
                  (data_ / "groundtruth.txt").string(), "--segmentation", (dir_ / "seg").string(),
                  "--min-score", "0.5", "--out", (dir_ / "run").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("all 2 below --min-score 0.5: no objects"), std::string::npos) << r.out;
}

// --out naming a folder that is not an earlier run (here the dataset itself, copied): exit 2 before
// any work, the folder as it was; an earlier run is replaced.
TEST_F(FuseBadInput, OutThatIsNotAnEarlierRunIsNeverReplaced) {
  write_text(dir_ / "seg" / (std::string(kFirstFrame) + ".json"),
             R"({"instances":[{"class":"cup","score":0.9,"bbox":[10,10,50,50]}]})");
  const fs::path data = dir_ / "data";
  fs::copy(data_, data, fs::copy_options::recursive);
  auto fuse_into = [&](const fs::path& out) {
    return run_objmap({"fuse", "--dataset", data.string(), "--trajectory",
                       (data / "groundtruth.txt").string(), "--segmentation",
                       (dir_ / "seg").string(), "--out", out.string()});
  };
  // The dataset itself is an input: refused as such.
  const RunResult input = fuse_into(data);
  EXPECT_EQ(input.exit_code, 2) << input.err;
  EXPECT_NE(input.err.find("--out: " + data.string() + " is the input of --dataset"),
            std::string::npos)
      << input.err;
  // Another folder that holds data: refused as not an earlier run.
  const fs::path other = dir_ / "other";
  fs::copy(data_, other, fs::copy_options::recursive);
  const RunResult r = fuse_into(other);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(other.string() +
                       ": exists and is not an earlier objmap fuse run (it holds depth, depth.txt, "
                       "detections_yolofastest and 3 more; no run.json), so it is not replaced"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const fs::path& folder : {data, other}) {
    EXPECT_TRUE(fs::exists(folder / "rgb.txt"));
    EXPECT_FALSE(fs::exists(folder / "run.json"));
  }
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_.path())) ++entries;
  EXPECT_EQ(entries, 3u);  // seg, data, other: no temporary folder

  // An earlier run is replaced: its extra file goes.
  const fs::path run = dir_ / "run";
  ASSERT_EQ(fuse_into(run).exit_code, 0);
  write_text(run / "extra.txt", "x");
  const RunResult again = fuse_into(run);
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(fs::exists(run / "run.json"));
  EXPECT_FALSE(fs::exists(run / "extra.txt"));
}

TEST(FuseCli, MissingRequiredFlagIsAUsageError) {
  const auto r = run_objmap({"fuse", "--dataset", "x"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--segmentation"), std::string::npos) << r.err;
}

TEST(FuseCli, UnknownConfigKeyIsNamed) {
  TempDir dir;
  write_text(dir / "c.json", R"({"objects":{"weight_idd":0.3}})");
  const auto r = run_objmap({"fuse", "--dataset", "x", "--trajectory", "t", "--segmentation", "s",
                             "--out", (dir / "o").string(), "--config", (dir / "c.json").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("objects.weight_idd"), std::string::npos) << r.err;
}

TEST(FuseCli, ThreadCountOutOfRangeIsNamed) {
  TempDir dir;
  const auto r = run_objmap({"fuse", "--dataset", "x", "--trajectory", "t", "--segmentation", "s",
                             "--out", (dir / "o").string(), "--threads", "65"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("threads (--threads): must be in [0, 64] (0: the cores, at most 8), got 65"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "o"));
}

// Meshes asked for without the OpenVDB module (OBJMAP_VDB_MODULE names the only file tried): exit 2
// before any work, one line naming what was tried and how to get it, nothing written.
TEST(FuseCli, MeshesWithoutTheOpenVdbModuleAreRefusedBeforeAnyWork) {
  TempDir dir;
  setenv("OBJMAP_VDB_MODULE", "/nonexistent/libobjmap_vdb.so", 1);
  const auto r = run_objmap({"fuse", "--dataset", "x", "--trajectory", "t", "--segmentation", "s",
                             "--out", (dir / "o").string(), "--mesh", "objects"});
  unsetenv("OBJMAP_VDB_MODULE");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("objmap: error: meshes: the OpenVDB module libobjmap_vdb.so is not found "
                        "(/nonexistent/libobjmap_vdb.so: cannot open shared object file",
                        0),
            0u)
      << r.err;
  EXPECT_NE(r.err.find("OBJMAP_VDB_MODULE"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "o"));
}

// An option of a part of fuse (the object map, the depth range) is named as the user wrote it: its
// config key and flag, not the library struct's member.
TEST(FuseCli, BadOptionNamesItsKeyAndFlag) {
  TempDir dir;
  const auto fuse_with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args{"fuse",           "--dataset", "x",     "--trajectory",      "t",
                                  "--segmentation", "s",         "--out", (dir / "o").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_objmap(args);
  };
  auto r = fuse_with({"--weight-id", "-1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("objmap: error: objects.weight_id (--weight-id): must be >= 0", 0), 0u)
      << r.err;
  r = fuse_with({"--min-depth", "5", "--max-depth", "1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("objmap: error: depth.max_m (--max-depth): must be finite and > ", 0), 0u)
      << r.err;
  write_text(dir / "c.json", R"({"outlier":{"neighbours":0}})");
  r = fuse_with({"--config", (dir / "c.json").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("objmap: error: outlier.neighbours (--outlier-k): must be >= 1", 0), 0u)
      << r.err;
}

}  // namespace
}  // namespace objmap::test
