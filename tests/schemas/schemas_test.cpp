// Every JSON that objmap writes validates against its schema in schemas/.
#include <gtest/gtest.h>

#include <fstream>

#include "support/schema_check.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

nlohmann::json load(const fs::path& file) {
  std::ifstream in(file);
  return nlohmann::json::parse(in);
}

void expect_valid(const fs::path& file, const std::string& schema) {
  ASSERT_TRUE(fs::exists(file)) << file;
  const auto errors = validate_json(load(file), load_schema(schema));
  EXPECT_TRUE(errors.empty()) << file << " vs " << schema << ": " << errors.front();
}

fs::path scene() {
  RunResult r;
  const fs::path dir = cached_output(
      "seed3-orbit60-scene", {"synth", "--out", "{OUT}", "--seed", "3", "--orbit-speed", "60"}, &r);
  EXPECT_TRUE(fs::exists(dir)) << r.err;
  return dir;
}

// The scene fused with its groundtruth.txt (the cached run of tests/integration); `r`: how fuse
// failed when it is absent.
fs::path fused_run(RunResult* r) {
  const fs::path s = scene();
  return cached_output(
      "seed3-orbit60-fuse",
      {"fuse", "--dataset", s.string(), "--trajectory", (s / "groundtruth.txt").string(),
       "--segmentation", (s / "segmentation").string(), "--out", "{OUT}"},
      r);
}

TEST(Schemas, TheValidatorRejectsWhatItShould) {
  const auto schema = load_schema("camera.schema.json");
  EXPECT_FALSE(validate_json(nlohmann::json::parse(R"({"fx":1})"), schema).empty());
  EXPECT_FALSE(validate_json(nlohmann::json::parse(R"([1,2])"), schema).empty());
}

TEST(Schemas, SynthOutputs) {
  const fs::path s = scene();
  expect_valid(s / "objects_gt.json", "objects_gt.schema.json");
  expect_valid(s / "camera.json", "camera.schema.json");
  expect_valid(s / "synth.json", "synth.schema.json");
  int checked = 0;
  for (const auto& e : fs::directory_iterator(s / "segmentation")) {
    if (checked == 3) break;
    expect_valid(e.path(), "segmentation.schema.json");
    ++checked;
  }
  EXPECT_EQ(checked, 3);
}

TEST(Schemas, FuseOutputsAndConfig) {
  RunResult r;
  const fs::path run = fused_run(&r);
  ASSERT_TRUE(fs::exists(run)) << r.err;
  expect_valid(run / "objects.json", "objects.schema.json");
  expect_valid(run / "run.json", "run.schema.json");
  const auto options = load(run / "run.json")["options"];
  const auto errors = validate_json(options, load_schema("fuse_config.schema.json"));
  EXPECT_TRUE(errors.empty()) << errors.front();
  expect_valid(fs::path(OBJMAP_SOURCE_DIR_FOR_TESTS) / "examples" / "fuse_config.json",
               "fuse_config.schema.json");
}

TEST(Schemas, QueryOutput) {
  RunResult r;
  const fs::path run = fused_run(&r);
  ASSERT_TRUE(fs::exists(run)) << r.err;
  const auto schema = load_schema("query.schema.json");
  // Matches (with a surface), no match (candidates), a relation to an object, a bare class.
  std::size_t matches = 0, candidates = 0, surfaces = 0;
  for (const char* text : {"book on table", "books on floor", "book near book", "book"}) {
    r = run_objmap({"query", "--run", run.string(), text, "--json"});
    ASSERT_EQ(r.exit_code, 0) << text << ": " << r.err;
    const auto doc = nlohmann::json::parse(r.out);
    const auto errors = validate_json(doc, schema);
    EXPECT_TRUE(errors.empty()) << text << ": " << errors.front();
    matches += doc["matches"].size();
    candidates += doc["candidates"].size();
    for (const auto& m : doc["matches"]) surfaces += m["surface"].is_object();
  }
  EXPECT_GT(matches, 0u);
  EXPECT_GT(candidates, 0u);
  EXPECT_GT(surfaces, 0u);
  // The schema rejects what the output must not be.
  EXPECT_FALSE(validate_json(nlohmann::json::parse(
                                 R"({"query":"x","subject":"x","relation":"beside","target":"",)"
                                 R"("matches":[],"candidates":[]})"),
                             schema)
                   .empty());
}

TEST(Schemas, EvalOutputs) {
  const fs::path s = scene();
  TempDir dir;
  auto r = run_objmap({"eval", "ate", "--gt", (s / "groundtruth.txt").string(), "--est",
                       (s / "estimated.txt").string(), "--json", (dir / "ate.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_valid(dir / "ate.json", "eval_ate.schema.json");
  r = run_objmap({"eval", "rpe", "--gt", (s / "groundtruth.txt").string(), "--est",
                  (s / "estimated.txt").string(), "--json", (dir / "rpe.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_valid(dir / "rpe.json", "eval_rpe.schema.json");
}

TEST(Schemas, TrackOutputs) {
  RunResult r;
  const fs::path s =
      cached_output("track-synth60", {"synth", "--out", "{OUT}", "--frames", "60"}, &r);
  ASSERT_TRUE(fs::exists(s)) << r.err;
  const fs::path tracked = cached_output("track-synth60-app",
                                         {"track", "--dataset", s.string(), "--segmentation",
                                          (s / "segmentation").string(), "--out", "{OUT}"},
                                         &r);
  ASSERT_TRUE(fs::exists(tracked)) << r.err;
  expect_valid(tracked / "tracks.json", "tracks.schema.json");
  TempDir dir;
  r = run_objmap({"eval", "tracks", "--gt", (s / "segmentation_gt").string(), "--est",
                  tracked.string(), "--json", (dir / "t.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_valid(dir / "t.json", "eval_tracks.schema.json");
}

TEST(Schemas, RealCameraFile) {
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f/camera.json");
  expect_valid(data, "camera.schema.json");
}

}  // namespace
}  // namespace objmap::test
