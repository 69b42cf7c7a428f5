#include "objmap/io/tum_dataset.h"

#include <gtest/gtest.h>

#include <cmath>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::copy_tree;
using test::read_text;
using test::TempDir;
using test::write_text;

// The reason of the InputError thrown by reading `dir` (fails the test when nothing is thrown).
std::string read_error(const fs::path& dir, std::string* where = nullptr) {
  return test::error_reason([&] { read_tum_dataset(dir); }, dir.string(), where);
}

TEST(ReadDataset, Fr1Desk9) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_desk_9");
  const Dataset d = read_tum_dataset(dir);
  EXPECT_EQ(d.rgb_rows, 9u);
  EXPECT_EQ(d.depth_rows, 9u);
  ASSERT_EQ(d.frames.size(), 9u);
  EXPECT_EQ(d.frames[0].rgb_timestamp, 1305031453.359684);
  EXPECT_EQ(d.frames[0].depth_timestamp, 1305031453.374112);
  EXPECT_EQ(d.frames[0].rgb_file, dir / "rgb/1305031453.359684.png");
  EXPECT_EQ(d.frames[8].depth_file, dir / "depth/1305031453.636951.png");
  EXPECT_EQ(d.recorded_from, "rgbd_dataset_freiburg1_desk.bag");
  EXPECT_EQ(d.root, dir);
}

TEST(ReadDataset, Fr1RpyEvery4) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_rpy_every4");
  const Dataset d = read_tum_dataset(dir);
  EXPECT_EQ(d.rgb_rows, 174u);
  ASSERT_EQ(d.frames.size(), 174u);
  EXPECT_EQ(d.frames.back().rgb_timestamp, 1305031253.56567);
  EXPECT_EQ(d.frames.back().depth_timestamp, 1305031253.557854);
  EXPECT_EQ(d.recorded_from, "");
  for (std::size_t i = 1; i < d.frames.size(); ++i)
    ASSERT_LT(d.frames[i - 1].rgb_timestamp, d.frames[i].rgb_timestamp);
}

TEST(ReadDataset, Fr3CabinetJpeg) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr3_cabinet_58kf");
  const Dataset d = read_tum_dataset(dir);
  ASSERT_EQ(d.frames.size(), 58u);
  EXPECT_EQ(d.frames[0].rgb_file.extension(), ".jpg");
  EXPECT_EQ(d.frames[0].rgb_timestamp, d.frames[0].depth_timestamp);
  EXPECT_EQ(d.recorded_from, "");
}

TEST(ReadDataset, Ycbv) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f");
  const Dataset d = read_tum_dataset(dir);
  ASSERT_EQ(d.frames.size(), 10u);
  EXPECT_EQ(d.frames[9].rgb_timestamp, 0.3);
}

TEST(AssociateStamps, MatchesAssociatePyOnContestedCase) {
  // Expected values from the TUM benchmark's associate.py (Python) on the same lists.
  using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;
  // 1.000 and 1.012 both want 1.009; 1.012 is closer and wins; 1.000 stays unmatched; 1.025 loses
  // to nobody but is too far from 1.040 compared with 1.045.
  EXPECT_EQ(associate_stamps({1.000, 1.012, 1.040, 1.100}, {1.009, 1.025, 1.045, 1.0999}, 0.02),
            (Pairs{{1, 0}, {2, 2}, {3, 3}}));
  // An exact tie in difference goes to the earlier rgb stamp (Python tuple order).
  EXPECT_EQ(associate_stamps({2.0, 2.5}, {2.25}, 0.5), (Pairs{{0, 0}}));
  // associate.py: [(1.0, 1.01), (1.03, 1.02)] (floating point decides the near-tie for 1.03).
  EXPECT_EQ(associate_stamps({1.0, 1.03}, {1.01, 1.02, 1.04}, 0.02), (Pairs{{0, 0}, {1, 1}}));
  // Strictly less than max_diff: 0.25 apart with max_diff 0.25 is not a pair.
  EXPECT_TRUE(associate_stamps({1.0}, {1.25}, 0.25).empty());
}

TEST(ReadDataset, ContestedCaseFromFiles) {
  TempDir dir;
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::string rgb = "# color images\n", depth = "# depth\n";
  for (const char* t : {"1.000", "1.012", "1.040", "1.100"}) {
    rgb += std::string(t) + " rgb/" + t + ".png\n";
    write_text(dir / "rgb" / (std::string(t) + ".png"), "x");
  }
  for (const char* t : {"1.009", "1.025", "1.045", "1.0999"}) {
    depth += std::string(t) + "\tdepth/" + t + ".png\n";
    write_text(dir / "depth" / (std::string(t) + ".png"), "x");
  }
  write_text(dir / "rgb.txt", rgb);
  write_text(dir / "depth.txt", depth);
  const Dataset d = read_tum_dataset(dir.path());
  ASSERT_EQ(d.frames.size(), 3u);
  EXPECT_EQ(d.frames[0].rgb_timestamp, 1.012);
  EXPECT_EQ(d.frames[0].depth_timestamp, 1.009);
  EXPECT_EQ(d.frames[2].depth_file, dir / "depth/1.0999.png");
  EXPECT_EQ(d.rgb_rows, 4u);
  EXPECT_EQ(d.depth_rows, 4u);
}

TEST(ReadDataset, EmptyFolderMissingListsAndFolder) {
  TempDir dir;
  std::string where;
  EXPECT_EQ(read_error(dir.path(), &where),
            "empty folder; expected a TUM RGB-D folder with rgb.txt, depth.txt, rgb/ and depth/");
  EXPECT_EQ(read_error(dir / "nope"), "folder not found");
  write_text(dir / "depth.txt", "1 depth/1.png\n");
  EXPECT_EQ(read_error(dir.path(), &where),
            "file not found; expected a TUM RGB-D folder with rgb.txt and depth.txt (lines "
            "'timestamp filename')");
  EXPECT_EQ(where, (dir / "rgb.txt").string());
}

TEST(ReadDataset, MalformedCopiesOfFr1Desk9) {
  OBJMAP_DATA_OR_SKIP(src, "tum/fr1_desk_9");
  TempDir tmp;
  const fs::path dir = tmp / "fr1_desk_9";
  copy_tree(src, dir);
  const std::string rgb = read_text(src / "rgb.txt");
  const std::string depth = read_text(src / "depth.txt");
  std::string where;

  fs::remove(dir / "depth.txt");
  EXPECT_NE(read_error(dir, &where).find("file not found"), std::string::npos);
  EXPECT_EQ(where, (dir / "depth.txt").string());
  write_text(dir / "depth.txt", depth);

  // A listed image that does not exist (line 5: the 2nd data line).
  fs::remove(dir / "rgb/1305031453.391690.png");
  EXPECT_EQ(read_error(dir, &where),
            "listed image " + (dir / "rgb/1305031453.391690.png").string() + " does not exist");
  EXPECT_EQ(where, (dir / "rgb.txt").string() + ":5");
  copy_tree(src / "rgb", dir / "rgb");

  // A data line with one field, and with text as a timestamp.
  write_text(dir / "rgb.txt", rgb + "1305031454.0\n");
  EXPECT_EQ(read_error(dir, &where), "1 fields; expected 2: timestamp filename");
  EXPECT_EQ(where, (dir / "rgb.txt").string() + ":13");
  write_text(dir / "rgb.txt", rgb + "later rgb/x.png\n");
  EXPECT_EQ(read_error(dir), "timestamp is 'later'; expected a finite number");
  write_text(dir / "rgb.txt", rgb + "nan rgb/x.png\n");
  EXPECT_EQ(read_error(dir), "timestamp is 'nan'; expected a finite number");
  write_text(dir / "rgb.txt", rgb);

  // Out of order and duplicated stamps.
  write_text(dir / "depth.txt", depth + "1305031453.0 depth/1305031453.374112.png\n");
  EXPECT_EQ(read_error(dir, &where),
            "timestamp 1305031453.0 is before that of line 12; expected strictly increasing "
            "timestamps");
  EXPECT_EQ(where, (dir / "depth.txt").string() + ":13");
  write_text(dir / "depth.txt", depth + "1305031453.636951 depth/1305031453.636951.png\n");
  EXPECT_EQ(read_error(dir),
            "timestamp 1305031453.636951 duplicates line 12; expected strictly increasing "
            "timestamps");

  // Only comments.
  write_text(dir / "depth.txt", "# depth maps\n");
  EXPECT_EQ(read_error(dir), "lists no image; expected lines 'timestamp filename'");
}

TEST(ReadDataset, NoPairWithinMaxDiff) {
  OBJMAP_DATA_OR_SKIP(src, "tum/fr1_desk_9");
  TumOptions tight;
  tight.max_diff_s = 1e-6;
  EXPECT_THROW(read_tum_dataset(src, tight), InputError);
  TumOptions loose;
  loose.max_diff_s = 0.01;  // fewer pairs, each closer than 10 ms
  for (const FramePair& f : read_tum_dataset(src, loose).frames)
    EXPECT_LT(std::abs(f.rgb_timestamp - f.depth_timestamp), 0.01);
}

TEST(TumOptions, MaxDiffOutOfRange) {
  for (double bad : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    TumOptions o;
    o.max_diff_s = bad;
    try {
      o.check();
      FAIL() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "TumOptions.max_diff_s");
    }
  }
  TempDir dir;
  TumOptions o;
  o.max_diff_s = -1;
  EXPECT_THROW(read_tum_dataset(dir.path(), o), InputError);
}

TEST(RecordedFromHeader, ReadsTheFileComment) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_desk_9");
  EXPECT_EQ(recorded_from_header(dir / "rgb.txt"), "rgbd_dataset_freiburg1_desk.bag");
  EXPECT_EQ(recorded_from_header(dir / "groundtruth.txt"), "rgbd_dataset_freiburg1_desk.bag");
  EXPECT_EQ(recorded_from_header(dir / "nope.txt"), "");
}

}  // namespace
}  // namespace objmap::io
