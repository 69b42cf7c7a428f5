// `objmap track` through the binary: the real YOLO stream of fr3_long_office_household (boxes, no
// images), the output files, and bad input (exit 2, one line).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "objmap/segmentation/read.h"
#include "support/test_support.h"

namespace objmap::track {
namespace {

using test::run_objmap;
using test::fs::path;

// The real detection stream: 2585 frames of boxes. Measured: 242 confirmed tracks of 966 started,
// mean length 67.5 frames (docs/_parts/track.md); asserted with margin.
TEST(TrackCli, RealYoloStreamWithoutImages) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr3_long_office_household_annotations");
  test::TempDir tmp;
  const auto r = run_objmap({"track", "--dataset", data.string(), "--segmentation",
                             (data / "detections_yolo").string(), "--out", (tmp / "out").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("off (the dataset has no images)"), std::string::npos) << r.out;
  const auto tracks = nlohmann::json::parse(test::read_text(tmp / "out" / "tracks.json"));
  EXPECT_EQ(tracks["frames"], 2585);
  EXPECT_EQ(tracks["appearance"], false);
  const auto& list = tracks["tracks"];
  ASSERT_GT(list.size(), 100u);
  double total = 0;
  for (const auto& t : list) {
    EXPECT_GE(t["length"].get<int>(), 3);  // n_init detections at least
    EXPECT_LE(t["first_frame"].get<int>(), t["last_frame"].get<int>());
    total += t["length"].get<double>();
  }
  EXPECT_GT(total / static_cast<double>(list.size()), 30.0);
  // The written segmentation reads back with the same frames, and ids of tracks.json.
  const auto seg = segmentation::read_segmentation(tmp / "out");
  EXPECT_EQ(seg.format, "json");
  EXPECT_EQ(seg.frames.size(), 2585u);
  std::size_t with_id = 0;
  for (const auto& f : seg.frames)
    for (const auto& i : f.instances)
      if (i.track_id) {
        ++with_id;
        EXPECT_GE(*i.track_id, 1);
        EXPECT_LE(*i.track_id, static_cast<int>(list.size()));
      }
  EXPECT_EQ(static_cast<double>(with_id), total);
}

TEST(TrackCli, MissingDatasetFolderIsExit2) {
  test::TempDir tmp;
  test::fs::create_directories(tmp / "seg");
  const auto r = run_objmap({"track", "--dataset", (tmp / "nope").string(), "--segmentation",
                             (tmp / "seg").string(), "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "objmap: error: " + (tmp / "nope").string() +
                       ": no such folder; expected a TUM RGB-D folder with rgb.txt\n");
  EXPECT_FALSE(test::fs::exists(tmp / "out"));
}

// A stream whose every frame is empty: nothing to track.
TEST(TrackCli, EmptyDetectionStreamIsExit2) {
  test::TempDir tmp;
  test::write_text(tmp / "data" / "rgb.txt",
                   "1.000000 rgb/1.000000.png\n2.000000 rgb/2.000000.png\n");
  test::write_text(tmp / "seg" / "1.000000.json", "{\"instances\":[]}\n");
  test::write_text(tmp / "seg" / "2.000000.json", "{\"instances\":[]}\n");
  const auto r = run_objmap({"track", "--dataset", (tmp / "data").string(), "--segmentation",
                             (tmp / "seg").string(), "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "objmap: error: " + (tmp / "seg").string() +
                       ": no instance in any of the 2 frames; expected detections to track\n");
  EXPECT_FALSE(test::fs::exists(tmp / "out"));
}

// A segmentation frame of a dataset with images must have its rgb image (for the appearance).
TEST(TrackCli, FrameWithoutImageIsExit2) {
  test::TempDir tmp;
  test::write_text(tmp / "data" / "rgb.txt", "1.000000 rgb/1.000000.png\n");
  test::write_text(tmp / "data" / "rgb" / "1.000000.png", "not read");
  test::write_text(tmp / "seg" / "5.000000.json",
                   "{\"instances\":[{\"class\":\"cup\",\"score\":0.9,\"bbox\":[1,2,3,4]}]}\n");
  const auto r = run_objmap({"track", "--dataset", (tmp / "data").string(), "--segmentation",
                             (tmp / "seg").string(), "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((tmp / "seg" / "5.000000.json").string() + ": no rgb image of "),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace objmap::track

namespace objmap::track {
namespace {

// `objmap eval tracks` once the eval group registers it (setup_eval_tracks); skipped before.
TEST(EvalTracksCli, JsonOfAHandMadeCase) {
  if (run_objmap({"eval", "--help"}).out.find("\n  tracks ") == std::string::npos)
    GTEST_SKIP() << "objmap eval tracks is not registered in the eval group yet";
  test::TempDir tmp;
  // Object 1 in both frames; the estimate has it in frame 1 only, plus a false positive in frame 2.
  const std::string a = R"({"class":"cup","score":1,"track_id":1,"bbox":[0,0,10,10]})";
  const std::string fp = R"({"class":"cup","score":1,"track_id":8,"bbox":[50,50,10,10]})";
  test::write_text(tmp / "gt" / "1.000000.json", "{\"instances\":[" + a + "]}\n");
  test::write_text(tmp / "gt" / "2.000000.json", "{\"instances\":[" + a + "]}\n");
  test::write_text(tmp / "est" / "1.000000.json", "{\"instances\":[" + a + "]}\n");
  test::write_text(tmp / "est" / "2.000000.json", "{\"instances\":[" + fp + "]}\n");
  const auto r = run_objmap({"eval", "tracks", "--gt", (tmp / "gt").string(), "--est",
                             (tmp / "est").string(), "--json", (tmp / "m.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::read_text(tmp / "m.json"));
  EXPECT_DOUBLE_EQ(j["mota"].get<double>(), 0.0);  // 1 - (1 miss + 1 FP) / 2
  EXPECT_DOUBLE_EQ(j["idf1"].get<double>(), 0.5);  // 2 x 1 / (2 + 2)
  EXPECT_EQ(j["id_switches"], 0);
  const auto bad = run_objmap(
      {"eval", "tracks", "--gt", (tmp / "nope").string(), "--est", (tmp / "est").string()});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find((tmp / "nope").string()), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace objmap::track
