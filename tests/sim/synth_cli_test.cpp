#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "objmap/sim/presets.h"
#include "support/schema_check.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

int data_rows(const fs::path& file) {
  std::istringstream in(read_text(file));
  std::string line;
  int rows = 0;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#') ++rows;
  return rows;
}

int files_in(const fs::path& dir, const std::string& ext) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == ext;
  return n;
}

int lines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

TEST(SynthCli, WritesATumSequenceWithGroundTruth) {
  TempDir tmp;
  const fs::path out = tmp / "seq";
  const RunResult r = run_objmap({"synth", "--out", out.string(), "--frames", "4"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(data_rows(out / "rgb.txt"), 4);
  EXPECT_EQ(data_rows(out / "depth.txt"), 4);
  EXPECT_EQ(data_rows(out / "groundtruth.txt"), 4);
  EXPECT_EQ(data_rows(out / "estimated.txt"), 4);
  EXPECT_NE(read_text(out / "rgb.txt").find("# file: 'synthetic"), std::string::npos);
  EXPECT_EQ(files_in(out / "rgb", ".png"), 4);
  EXPECT_EQ(files_in(out / "depth", ".png"), 4);
  EXPECT_EQ(files_in(out / "segmentation", ".json"), 4);
  EXPECT_EQ(files_in(out / "segmentation_gt", ".json"), 4);
  EXPECT_TRUE(fs::exists(out / "rgb" / "1700000000.100000.png"));
  EXPECT_TRUE(fs::exists(out / "depth" / "1700000000.105000.png"));
  EXPECT_TRUE(fs::exists(out / "segmentation" / "1700000000.133333.json"));

  const auto camera = nlohmann::json::parse(read_text(out / "camera.json"));
  EXPECT_EQ(camera.at("width"), 640);
  EXPECT_DOUBLE_EQ(camera.at("fx").get<double>(), 517.3);
  EXPECT_DOUBLE_EQ(camera.at("depth_factor").get<double>(), 5000.0);

  const auto gt = nlohmann::json::parse(read_text(out / "objects_gt.json"));
  std::set<std::string> classes;
  for (const auto& o : gt.at("objects")) {
    classes.insert(o.at("class").get<std::string>());
    EXPECT_EQ(o.at("centroid").size(), 3u);
    EXPECT_EQ(o.at("obb").at("rotation").size(), 9u);
    EXPECT_EQ(o.at("obb").at("half_extent").size(), 3u);
  }
  EXPECT_GE(classes.size(), 8u);
  for (const auto& name : objmap::sim::paper_classes()) EXPECT_TRUE(classes.count(name)) << name;

  const auto seg =
      nlohmann::json::parse(read_text(out / "segmentation_gt" / "1700000000.100000.json"));
  EXPECT_GE(seg.at("instances").size(), 6u);
  EXPECT_EQ(seg.at("instances")[0].at("mask").at("size"), nlohmann::json::array({480, 640}));
}

TEST(SynthCli, SameSeedGivesByteIdenticalFilesWhateverTheThreads) {
  TempDir tmp;
  const std::vector<std::string> common{"--frames", "3", "--scale", "0.25", "--seed", "9"};
  auto args = [&](const std::string& out, const std::string& threads) {
    std::vector<std::string> a{"synth", "--out", (tmp / out).string(), "--threads", threads};
    a.insert(a.end(), common.begin(), common.end());
    return a;
  };
  ASSERT_EQ(run_objmap(args("a", "1")).exit_code, 0);
  ASSERT_EQ(run_objmap(args("b", "2")).exit_code, 0);
  int compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(tmp / "a")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), tmp / "a");
    EXPECT_EQ(read_text(e.path()), read_text(tmp / "b" / rel)) << rel;
    ++compared;
  }
  EXPECT_GT(compared, 15);
}

TEST(SynthCli, BadOptionsExitTwoWithOneLine) {
  TempDir tmp;
  RunResult r = run_objmap({"synth", "--out", (tmp / "x").string(), "--frames", "0"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--frames"), std::string::npos) << r.err;

  write_text(tmp / "file", "not a folder");
  r = run_objmap({"synth", "--out", (tmp / "file" / "seq").string(), "--frames", "2"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("objmap: error: "), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "file" / "seq"));

  r = run_objmap({"synth", "--out", (tmp / "y").string(), "--preset", "garden"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("garden"), std::string::npos) << r.err;

  r = run_objmap({"synth", "--out", (tmp / "z").string(), "--miss-rate", "1.5"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--miss-rate"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "z"));

  for (const char* bad : {"-1", "21"}) {
    r = run_objmap({"synth", "--out", (tmp / "b").string(), "--mask-bleed-px", bad});
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_EQ(r.err.rfind("objmap: error: --mask-bleed-px: must be in [0, 20] pixels", 0), 0u)
        << r.err;
    EXPECT_FALSE(fs::exists(tmp / "b"));
  }
}

TEST(SynthCli, MaskBleedGrowsTheNoisyMasksAndIsRecorded) {
  TempDir tmp;
  RunResult r = run_objmap({"synth", "--out", (tmp / "plain").string(), "--preset", "edge",
                            "--frames", "2", "--scale", "0.25", "--mask-bleed-px", "0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_objmap({"synth", "--out", (tmp / "bled").string(), "--preset", "edge", "--frames", "2",
                  "--scale", "0.25", "--mask-bleed-px", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("mask bleed"), std::string::npos) << r.out;
  const auto json = nlohmann::json::parse(read_text(tmp / "bled" / "synth.json"));
  EXPECT_EQ(json.at("preset"), "edge");
  EXPECT_EQ(json.at("segmentation_noise").at("bleed_px"), 2);
  EXPECT_GT(json.at("made").at("bleed_pixels").get<long>(), 0);
  const auto errors = validate_json(json, load_schema("synth.schema.json"));
  EXPECT_TRUE(errors.empty()) << errors.front();
  EXPECT_FALSE(nlohmann::json::parse(read_text(tmp / "plain" / "synth.json"))
                   .at("segmentation_noise")
                   .contains("bleed_px"));
  // Only the noisy masks differ: images, exact segmentation and trajectories are the same files.
  int same = 0, differ = 0;
  for (const auto& e : fs::recursive_directory_iterator(tmp / "plain")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), tmp / "plain");
    const bool equal = read_text(e.path()) == read_text(tmp / "bled" / rel);
    const bool noisy = rel.begin()->string() == "segmentation" || rel == "synth.json";
    EXPECT_EQ(equal, !noisy) << rel;
    (equal ? same : differ) += 1;
  }
  EXPECT_EQ(differ, 2 + 1);
  EXPECT_GT(same, 10);
}

}  // namespace
}  // namespace objmap::test
