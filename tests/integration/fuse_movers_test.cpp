// What moves is not the map (docs/fusion.md, "Sightings"): a synthetic scene whose teddy bear the
// segmentation calls a person, fused by objmap and by the paper's method.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "fuse_helpers.h"
#include "objmap/io/ply.h"
#include "support/schema_check.h"

namespace objmap::test {
namespace {

// The scene's segmentation with every "teddy bear" called "person".
void copy_with_person(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  for (const auto& entry : fs::directory_iterator(from)) {
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    std::string s = text.str();
    for (std::size_t at = s.find("teddy bear"); at != std::string::npos;
         at = s.find("teddy bear", at))
      s.replace(at, 10, "person");
    std::ofstream(to / entry.path().filename()) << s;
  }
}

std::size_t count_class(const nlohmann::json& list, const std::string& name) {
  std::size_t n = 0;
  for (const auto& o : list) n += o["class"] == name;
  return n;
}

TEST(FuseMovers, APersonIsASightingNotAMapObjectButAnObjectOfThePaper) {
  RunResult synth;
  const fs::path scene = cached_output("default-scene", {"synth", "--out", "{OUT}"}, &synth);
  ASSERT_TRUE(fs::exists(scene)) << synth.err;
  TempDir tmp;
  copy_with_person(scene / "segmentation", tmp / "seg");
  const auto fuse = [&](const std::string& out, const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"fuse",
                                     "--dataset",
                                     scene.string(),
                                     "--trajectory",
                                     (scene / "groundtruth.txt").string(),
                                     "--segmentation",
                                     (tmp / "seg").string(),
                                     "--out",
                                     (tmp / out).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_objmap(args);
  };
  const RunResult ours = fuse("ours", {});
  ASSERT_EQ(ours.exit_code, 0) << ours.err;
  const auto doc = read_json(tmp / "ours" / "objects.json");
  EXPECT_TRUE(validate_json(doc, load_schema("objects.schema.json")).empty());
  EXPECT_EQ(count_class(doc["objects"], "person"), 0u);
  ASSERT_EQ(count_class(doc["sightings"], "person"), 1u) << doc["sightings"].dump();
  const auto& person = doc["sightings"][0];
  EXPECT_LT(person["first_seen"].get<double>(), person["last_seen"].get<double>());
  EXPECT_GE(person["frames"].get<int>(), 3);
  for (const auto& o : doc["objects"])  // not in the relations
    for (const char* list : {"near", "above", "under"})
      for (const auto& n : o["relations"][list]) EXPECT_NE(n["id"], person["id"]) << o["id"];
  const auto run = read_json(tmp / "ours" / "run.json");
  EXPECT_EQ(run["counts"]["sightings"], 1);
  EXPECT_GT(run["points"]["dense_sightings"].get<int>(), 100) << "its voxels left the dense map";
  EXPECT_EQ(io::read_ply(tmp / "ours" / "map_semantic.ply").size(),
            run["points"]["dense_map"].get<std::size_t>());

  const RunResult paper = fuse("paper", {"--method", "paper"});
  ASSERT_EQ(paper.exit_code, 0) << paper.err;
  const auto paper_doc = read_json(tmp / "paper" / "objects.json");
  EXPECT_GE(count_class(paper_doc["objects"], "person"), 1u);
  EXPECT_TRUE(paper_doc["sightings"].empty());
}

}  // namespace
}  // namespace objmap::test
