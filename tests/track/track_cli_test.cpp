// `objmap track` through the binary: the real YOLO stream of fr3_long_office_household (boxes, no
// images), the output files, and bad input (exit 2, one line).
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "objmap/segmentation/read.h"
#include "support/test_support.h"

namespace objmap::track {
namespace {

using test::run_objmap;
using test::fs::path;

// The real detection stream: 2585 frames of boxes. Measured: 242 confirmed tracks of 966 started,
// mean length 67.5 frames (docs/cli.md, "Tracking"); asserted with margin.
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
  EXPECT_EQ(
      r.err,
      "objmap: error: " + (tmp / "nope").string() +
          ": no such folder; expected a recording folder (TUM rgb.txt, or another layout) or a "
          "ROS 1 .bag\n");
  EXPECT_FALSE(test::fs::exists(tmp / "out"));
}

// A stream whose every frame is empty: nothing to track. The frames are streamed, so this is known
// after the pass over them (the progress lines come first); the error is the last line and no
// output is left.
TEST(TrackCli, EmptyDetectionStreamIsExit2) {
  test::TempDir tmp;
  test::write_text(tmp / "data" / "rgb.txt",
                   "1.000000 rgb/1.000000.png\n2.000000 rgb/2.000000.png\n");
  test::write_text(tmp / "seg" / "1.000000.json", "{\"instances\":[]}\n");
  test::write_text(tmp / "seg" / "2.000000.json", "{\"instances\":[]}\n");
  const auto r = run_objmap({"track", "--dataset", (tmp / "data").string(), "--segmentation",
                             (tmp / "seg").string(), "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  const std::string line = "objmap: error: " + (tmp / "seg").string() +
                           ": no instance in any of the 2 frames; expected detections to track\n";
  ASSERT_GE(r.err.size(), line.size()) << r.err;
  EXPECT_EQ(r.err.substr(r.err.size() - line.size()), line);
  EXPECT_EQ(r.err.find("objmap: error:"), r.err.size() - line.size()) << r.err;
  EXPECT_FALSE(test::fs::exists(tmp / "out"));
}

// The frames are read as they are tracked: a malformed frame after good ones is exit 2 naming its
// file and line, and leaves no output (the frames before it went to the temporary folder only).
TEST(TrackCli, MalformedLaterFrameLeavesNoOutput) {
  test::TempDir tmp;
  std::string listing;
  for (int f = 1; f <= 8; ++f) {
    const std::string stamp = std::to_string(f) + ".000000";
    listing += stamp + " rgb/" + stamp + ".png\n";
    test::write_text(tmp / "seg" / (stamp + ".json"),
                     f == 7 ? "{\"instances\":[{\"class\":\"cup\",,}]}\n"
                            : "{\"instances\":[{\"class\":\"cup\",\"score\":0.9,\"bbox\":[" +
                                  std::to_string(10 + f) + ",20,30,40]}]}\n");
  }
  test::write_text(tmp / "data" / "rgb.txt", listing);
  const auto r = run_objmap({"track", "--dataset", (tmp / "data").string(), "--segmentation",
                             (tmp / "seg").string(), "--out", (tmp / "out").string()});
  EXPECT_EQ(r.exit_code, 2);
  const std::string line =
      "objmap: error: " + (tmp / "seg" / "7.000000.json").string() + ":1: malformed JSON at column";
  EXPECT_NE(r.err.find(line), std::string::npos) << r.err;
  EXPECT_FALSE(test::fs::exists(tmp / "out"));
  for (const auto& entry : test::fs::directory_iterator(tmp.path()))
    EXPECT_TRUE(entry.path().filename() == "data" || entry.path().filename() == "seg")
        << entry.path();  // no temporary folder left either
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

namespace objmap::track {
namespace {

using test::run_objmap;
using test::fs::path;

// The 3D gate on real frames: fr1_rpy_every4's Yolo-Fastest boxes with the rgb images, the depth
// and groundtruth.txt. Measured (docs/benchmarks.md, "The tracker's 3D gate"): every frame has a
// pose, 520 of 521 boxes get a 3D position through box masks (one box gives no mask); 41 tracks
// confirmed of 226 started, 306 of 521 boxes tracked (without the gate: 46 of 190, 347). The gate
// splits tracks whose box centroid jumps between objects, so it starts more tracks and labels
// fewer boxes.
TEST(TrackCli, RealRpyWithDepthAndThe3dGate) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_rpy_every4");
  test::TempDir tmp;
  const auto r =
      run_objmap({"track", "--dataset", data.string(), "--segmentation",
                  (data / "detections_yolofastest").string(), "--out", (tmp / "out").string(),
                  "--trajectory", (data / "groundtruth.txt").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("camera preset fr1 from the folder name 'fr1_rpy_every4'"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("174 frames with a pose, 0 without"), std::string::npos) << r.out;
  const auto tracks = nlohmann::json::parse(test::read_text(tmp / "out" / "tracks.json"));
  EXPECT_EQ(tracks["frames"], 174);
  EXPECT_EQ(tracks["instances"], 521);
  EXPECT_EQ(tracks["appearance"], true);
  const auto& gate = tracks["gate_3d"];
  EXPECT_EQ(gate["frames_with_pose"], 174);
  EXPECT_EQ(gate["frames_without_pose"], 0);
  EXPECT_EQ(gate["instances_with_position"], 520);
  EXPECT_EQ(gate["instances_mask_from_box"], 520);
  EXPECT_EQ(gate["instances_no_mask_from_box"], 1);
  const std::size_t confirmed = tracks["tracks"].size();
  EXPECT_GE(confirmed, 36u);
  EXPECT_LE(confirmed, 46u);
  EXPECT_GE(tracks["instances_tracked"].get<double>() / 521.0, 0.54);
  EXPECT_GE(tracks["tracks_started"].get<int>(), 200);
}

// Frames without a pose are tracked without the gate, and the summary says how many: fr1_desk_9's
// detections with a trajectory that ends at the fifth frame.
TEST(TrackCli, FramesWithoutAPoseAreCounted) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  test::TempDir tmp;
  std::string kept;
  std::istringstream in(test::read_text(data / "groundtruth.txt"));
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#' && std::stod(line) <= 1305031453.491698 + 0.001)
      kept += line + "\n";
  test::write_text(tmp / "short.txt", kept);
  const auto r = run_objmap({"track", "--dataset", data.string(), "--segmentation",
                             (data / "detections_yolofastest").string(), "--out",
                             (tmp / "out").string(), "--trajectory", (tmp / "short.txt").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("5 frames with a pose, 4 without (tracked without the gate)"),
            std::string::npos)
      << r.out;
  const auto tracks = nlohmann::json::parse(test::read_text(tmp / "out" / "tracks.json"));
  EXPECT_EQ(tracks["gate_3d"]["frames_without_pose"], 4);

  // A trajectory that is not there: exit 2, one line naming it.
  const auto bad =
      run_objmap({"track", "--dataset", data.string(), "--segmentation",
                  (data / "detections_yolofastest").string(), "--out", (tmp / "out2").string(),
                  "--trajectory", (tmp / "nope.txt").string()});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.err, "objmap: error: " + (tmp / "nope.txt").string() + ": file not found\n");
  EXPECT_FALSE(test::fs::exists(tmp / "out2"));
}

}  // namespace
}  // namespace objmap::track
