// objmap query on a run fused here: the seed-3 synthetic scene fused with its ground-truth
// trajectory (the cached run of tests/integration, tests/report and tests/schemas). The expected
// answers are worked out from objects.json itself (its surfaces and relations), not through the
// library's reader.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

struct Fused {
  fs::path run;
  RunResult result;
};

const Fused& fused() {
  static Fused f = [] {
    Fused r;
    const fs::path scene =
        cached_output("seed3-orbit60-scene",
                      {"synth", "--out", "{OUT}", "--seed", "3", "--orbit-speed", "60"}, &r.result);
    if (!fs::exists(scene)) return r;
    r.run = cached_output(
        "seed3-orbit60-fuse",
        {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
         "--segmentation", (scene / "segmentation").string(), "--out", "{OUT}"},
        &r.result);
    return r;
  }();
  return f;
}

// objects.json of the run, read as JSON, with what the tests need of it.
struct Map {
  json doc;
  std::map<int, const json*> objects, surfaces;  // by id

  explicit Map(const fs::path& file) : doc(json::parse(read_text(file))) {
    for (const json& o : doc.at("objects")) objects[o.at("id").get<int>()] = &o;
    for (const json& s : doc.at("surfaces")) surfaces[s.at("id").get<int>()] = &s;
  }
  // The surface object `id` stands on, following relations.on through objects.
  std::optional<int> standing_surface(int id) const {
    for (int hop = 0; hop < 8 && objects.count(id); ++hop) {
      const json& on = objects.at(id)->at("relations").at("on");
      if (on.is_null()) return std::nullopt;
      if (on.at("kind") == "surface") return on.at("id").get<int>();
      id = on.at("id").get<int>();
    }
    return std::nullopt;
  }
  std::string label_of_surface(std::optional<int> id) const {
    return id && surfaces.count(*id) ? surfaces.at(*id)->at("label").get<std::string>() : "";
  }
  // The ids of the objects of `cls` (any class when empty) that stand on a surface `label`.
  std::set<int> standing_on(const std::string& cls, const std::string& label) const {
    std::set<int> out;
    for (const auto& [id, o] : objects)
      if ((cls.empty() || o->at("class") == cls) && label_of_surface(standing_surface(id)) == label)
        out.insert(id);
    return out;
  }
  std::set<std::string> classes() const {
    std::set<std::string> out;
    for (const auto& [id, o] : objects) out.insert(o->at("class").get<std::string>());
    return out;
  }
};

std::set<int> ids_of(const json& list) {
  std::set<int> out;
  for (const json& m : list) out.insert(m.at("id").get<int>());
  return out;
}

// The output line of object `id` (the lines of a match list start with "  <id> ").
std::string line_of(const std::string& out, int id) {
  std::istringstream in(out);
  const std::string start = "  " + std::to_string(id) + " ";
  for (std::string line; std::getline(in, line);)
    if (line.rfind(start, 0) == 0) return line;
  return "";
}

std::string fixed3(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

class QueryCli : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(fused().run)) << fused().result.err;
    map_ = std::make_unique<Map>(fused().run / "objects.json");
  }
  RunResult query(const std::string& text, bool as_json = false) {
    std::vector<std::string> args{"query", "--run", fused().run.string(), text};
    if (as_json) args.push_back("--json");
    return run_objmap(args);
  }
  json query_json(const std::string& text) {
    const RunResult r = query(text, true);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? json::parse(r.out) : json::object();
  }
  // A class of the map with at least one object on a table, and those objects.
  std::pair<std::string, std::set<int>> class_on_table() const {
    for (const std::string& cls : map_->classes())
      if (auto ids = map_->standing_on(cls, "table"); !ids.empty()) return {cls, ids};
    return {"", {}};
  }
  std::unique_ptr<Map> map_;
};

TEST_F(QueryCli, AMatchIsPrintedWithIdClassPositionAndSurface) {
  const auto [cls, expected] = class_on_table();
  ASSERT_FALSE(cls.empty()) << "the seed-3 run has no object on a table";
  const RunResult r = query(cls + " on the table");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(r.out.rfind(std::to_string(expected.size()) + " match", 0), 0u) << r.out;
  for (const int id : expected) {
    const std::string line = line_of(r.out, id);
    ASSERT_NE(line, "") << id << " missing in\n" << r.out;
    EXPECT_NE(line.find(" " + cls + " "), std::string::npos) << line;
    const json& p = map_->objects.at(id)->at("position");
    for (int k = 0; k < 3; ++k)
      EXPECT_NE(line.find(fixed3(p[k].get<double>())), std::string::npos) << line;
    const int surface = *map_->standing_surface(id);
    EXPECT_NE(line.find(" " + std::to_string(surface) + " table "), std::string::npos) << line;
  }
  // No other object of the map is listed.
  for (const auto& [id, o] : map_->objects) {
    if (!expected.count(id)) {
      EXPECT_EQ(line_of(r.out, id), "") << id << "\n" << r.out;
    }
  }
}

TEST_F(QueryCli, JsonMatchesAgreeWithTheRelationsOfObjectsJson) {
  const auto [cls, expected] = class_on_table();
  ASSERT_FALSE(cls.empty());
  const json doc = query_json(cls + "s on table");  // a plural
  ASSERT_TRUE(doc.contains("matches")) << doc.dump();
  EXPECT_EQ(doc.at("subject"), cls);
  EXPECT_EQ(doc.at("relation"), "on");
  EXPECT_EQ(doc.at("target"), "table");
  EXPECT_EQ(ids_of(doc.at("matches")), expected);
  EXPECT_TRUE(doc.at("candidates").empty());
  for (const json& m : doc.at("matches")) {
    const int id = m.at("id").get<int>();
    ASSERT_TRUE(map_->objects.count(id)) << id;
    const json& o = *map_->objects.at(id);
    EXPECT_EQ(m.at("class"), o.at("class"));
    for (int k = 0; k < 3; ++k)
      EXPECT_DOUBLE_EQ(m.at("position")[k].get<double>(), o.at("position")[k].get<double>());
    const int surface = *map_->standing_surface(id);
    EXPECT_EQ(m.at("surface").at("id"), surface);
    EXPECT_EQ(m.at("surface").at("label"), "table");
    EXPECT_DOUBLE_EQ(m.at("surface").at("height_m").get<double>(),
                     map_->surfaces.at(surface)->at("height_m").get<double>());
    // "on": the figure is the gap of the object's own `on`.
    EXPECT_DOUBLE_EQ(m.at("distance_m").get<double>(),
                     o.at("relations").at("on").at("gap_m").get<double>());
  }
}

TEST_F(QueryCli, NearGivesTheDistanceOfObjectsJson) {
  // The first object with a neighbour: "CLASS near NEIGHBOUR_CLASS".
  const json* subject = nullptr;
  for (const auto& [id, o] : map_->objects)
    if (!o->at("relations").at("near").empty()) {
      subject = o;
      break;
    }
  ASSERT_NE(subject, nullptr) << "no object of the seed-3 run has a neighbour";
  const std::string cls = subject->at("class"),
                    target = map_->objects
                                 .at(subject->at("relations").at("near")[0].at("id").get<int>())
                                 ->at("class");
  // Expected: each object of `cls` with a neighbour of `target`, at the first such distance.
  std::map<int, double> expected;
  for (const auto& [id, o] : map_->objects) {
    if (o->at("class") != cls) continue;
    for (const json& n : o->at("relations").at("near"))
      if (map_->objects.at(n.at("id").get<int>())->at("class") == target) {
        expected[id] = n.at("distance_m").get<double>();
        break;
      }
  }
  const json doc = query_json(cls + " near " + target);
  ASSERT_TRUE(doc.contains("matches")) << doc.dump();
  ASSERT_EQ(doc.at("matches").size(), expected.size()) << doc.dump(1);
  for (const json& m : doc.at("matches")) {
    const int id = m.at("id").get<int>();
    ASSERT_TRUE(expected.count(id)) << id;
    EXPECT_DOUBLE_EQ(m.at("distance_m").get<double>(), expected.at(id));
    const std::optional<int> surface = map_->standing_surface(id);
    if (surface) {
      EXPECT_EQ(m.at("surface").at("id"), *surface);
    } else {
      EXPECT_TRUE(m.at("surface").is_null());
    }
  }
}

TEST_F(QueryCli, NoMatchIsExitZeroWithTheNearestCandidates) {
  // A class of the map none of whose objects stands on the floor: its objects are the candidates.
  std::string cls;
  for (const std::string& c : map_->classes())
    if (map_->standing_on(c, "floor").empty()) cls = c;
  ASSERT_FALSE(cls.empty());
  std::set<int> of_class;
  for (const auto& [id, o] : map_->objects)
    if (o->at("class") == cls) of_class.insert(id);
  const RunResult r = query(cls + " on floor");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("no match for \"" + cls + " on floor\"", 0), 0u) << r.out;
  EXPECT_NE(r.out.find("nearest candidates:"), std::string::npos) << r.out;
  for (const int id : of_class) EXPECT_NE(line_of(r.out, id), "") << id << "\n" << r.out;
  const json doc = query_json(cls + " on floor");
  ASSERT_TRUE(doc.contains("matches")) << doc.dump();
  EXPECT_TRUE(doc.at("matches").empty());
  EXPECT_EQ(ids_of(doc.at("candidates")), of_class);

  // A class the map lacks: what stands on a table, whatever its class.
  const std::set<std::string> classes = map_->classes();
  ASSERT_EQ(classes.count("toothbrush"), 0u);
  const json other = query_json("toothbrush on table");
  ASSERT_TRUE(other.contains("candidates")) << other.dump();
  EXPECT_TRUE(other.at("matches").empty());
  EXPECT_EQ(ids_of(other.at("candidates")), map_->standing_on("", "table"));
  EXPECT_FALSE(other.at("candidates").empty());
}

TEST_F(QueryCli, ABadQueryIsExitTwoNamingTheWord) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"cup beside table", "query: 'beside' is not a relation (on|near|above|under) after 'cup'"},
      {"cupp on table", "query: 'cupp' is not a class of COCO-80 or of this map"},
      {"cup on desks",
       "query: 'desks' is not a class of COCO-80 or of this map nor "
       "floor|table|seat|surface"},
      {"cup on table please", "query: 'please' after 'table' is not understood"},
      {"cup on table on floor", "query: 'on' after 'table' is not understood"},
      {"", "query: empty"},
      {"the", "query: empty"},
      {"cup on", "query: 'cup on' has no target"},
      {"on table", "query: 'on table' has no class"}};
  for (const auto& [text, message] : cases) {
    const RunResult r = query(text);
    EXPECT_EQ(r.exit_code, 2) << text;
    EXPECT_EQ(r.err.rfind("objmap: error: " + message, 0), 0u) << text << ": " << r.err;
    EXPECT_NE(r.err.find("expected CLASS [on|near|above|under CLASS|floor|table|seat|surface]"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.out, "") << text;
  }
}

TEST(QueryCliFiles, ARunWithoutObjectsJsonIsExitTwoNamingTheFile) {
  TempDir dir;
  const RunResult r = run_objmap({"query", "--run", dir.path().string(), "cup on table"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("objmap: error: " + (dir / "objects.json").string() + ": cannot open", 0),
            0u)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(QueryCliFiles, AnObjectsJsonWithoutTheSceneIsExitTwoNamingFileAndField) {
  ASSERT_TRUE(fs::exists(fused().run)) << fused().result.err;
  const json doc = json::parse(read_text(fused().run / "objects.json"));
  ASSERT_FALSE(doc.at("objects").empty());
  TempDir dir;
  const fs::path file = dir / "objects.json";
  // The message for objects.json with one field removed by `remove`.
  const auto error_without = [&](const std::function<void(json&)>& remove) {
    json copy = doc;
    remove(copy);
    write_text(file, copy.dump());
    const RunResult r = run_objmap({"query", "--run", dir.path().string(), "cup"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    return r.err;
  };
  const std::string start = "objmap: error: " + file.string() + ": ";
  EXPECT_EQ(error_without([](json& d) { d.erase("up_in_world"); })
                .rfind(start + "missing field 'up_in_world'; expected objects.json of an objmap "
                               "fuse that estimates the scene",
                       0),
            0u);
  EXPECT_EQ(error_without([](json& d) {
              d.erase("surfaces");
            }).rfind(start + "missing field 'surfaces'", 0),
            0u);
  EXPECT_EQ(error_without([](json& d) {
              d["objects"][0].erase("relations");
            }).rfind(start + "objects[0]: missing field 'relations'", 0),
            0u);
  EXPECT_EQ(error_without([](json& d) {
              d["objects"][0]["relations"].erase("near");
            }).rfind(start + "objects[0].relations: missing field 'near'", 0),
            0u);
  // The copy itself is answered: the messages above come from the removed fields.
  write_text(file, doc.dump());
  EXPECT_EQ(run_objmap({"query", "--run", dir.path().string(), "cup"}).exit_code, 0);
}

TEST(QueryCliHelp, ShowsTheGrammarAndExamplesAsDocsCliMdDoes) {
  const RunResult r = run_objmap({"query", "--help"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string grammar = "CLASS [on|near|above|under CLASS|floor|table|seat|surface]";
  EXPECT_NE(r.out.find(grammar), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--json"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--run"), std::string::npos) << r.out;
  // Every example of --help is in docs/cli.md's `objmap query` section, and the grammar too.
  const std::string docs = read_text(fs::path(OBJMAP_SOURCE_DIR_FOR_TESTS) / "docs" / "cli.md");
  const std::size_t section = docs.find("## `objmap query`");
  ASSERT_NE(section, std::string::npos);
  const std::string text = docs.substr(section, docs.find("\n## ", section + 1) - section);
  EXPECT_NE(text.find(grammar), std::string::npos);
  std::istringstream in(r.out);
  int examples = 0;
  for (std::string line; std::getline(in, line);) {
    const std::size_t at = line.find("objmap query --run RUN");
    if (at == std::string::npos) continue;
    ++examples;
    EXPECT_NE(text.find(line.substr(at)), std::string::npos) << line;
  }
  EXPECT_GE(examples, 3) << r.out;
}

}  // namespace
}  // namespace objmap::test
