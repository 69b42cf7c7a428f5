// objmap query's grammar and answers on a scene written here.
#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "objmap/scene/query.h"
#include "support/test_support.h"

namespace objmap::scene {
namespace {

using objmap::test::TempDir;
using objmap::test::write_text;

// A desk (surface 1, table) on a floor (surface 2): a cup and a keyboard on the desk, a book on the
// desk with a cup on the book, a mouse near the keyboard, a chair on the floor whose seat is
// surface 3 with a book on it.
const char* kObjects = R"({
  "schema_version": 1, "generator": "test", "frame": "world", "units": "metres",
  "up_in_world": [0, 0, 1], "gravity_from_world": [1, 0, 0, 0, 1, 0, 0, 0, 1],
  "surfaces": [
    {"id": 1, "label": "table", "height_m": 0.75, "center": [1, 1, 0.75],
     "outline": [[0, 0, 0.75], [2, 0, 0.75], [2, 2, 0.75], [0, 2, 0.75]]},
    {"id": 2, "label": "floor", "height_m": 0.0, "center": [3, 3, 0],
     "outline": [[-1, -1, 0], [6, -1, 0], [6, 6, 0], [-1, 6, 0]]},
    {"id": 3, "label": "seat", "height_m": 0.45, "center": [4, 4, 0.45], "object": 6,
     "outline": [[3.8, 3.8, 0.45], [4.2, 3.8, 0.45], [4.2, 4.2, 0.45], [3.8, 4.2, 0.45]]}],
  "objects": [
    {"id": 1, "class": "cup", "position": [0.5, 0.5, 0.8],
     "relations": {"on": {"kind": "surface", "id": 1, "label": "table", "gap_m": 0.002},
                   "near": [], "above": [], "under": []}},
    {"id": 2, "class": "keyboard", "position": [1.0, 1.0, 0.76],
     "relations": {"on": {"kind": "surface", "id": 1, "label": "table", "gap_m": 0.004},
                   "near": [{"id": 3, "distance_m": 0.25}], "above": [], "under": []}},
    {"id": 3, "class": "mouse", "position": [1.25, 1.0, 0.76],
     "relations": {"on": {"kind": "surface", "id": 1, "label": "table", "gap_m": 0.001},
                   "near": [{"id": 2, "distance_m": 0.25}], "above": [], "under": []}},
    {"id": 4, "class": "book", "position": [1.5, 1.5, 0.77],
     "relations": {"on": {"kind": "surface", "id": 1, "label": "table", "gap_m": 0.0},
                   "near": [{"id": 5, "distance_m": 0.05}], "above": [],
                   "under": [{"id": 5, "gap_m": 0.01}]}},
    {"id": 5, "class": "cup", "position": [1.5, 1.5, 0.85],
     "relations": {"on": {"kind": "object", "id": 4, "label": "book", "gap_m": 0.01},
                   "near": [{"id": 4, "distance_m": 0.05}], "above": [{"id": 4, "gap_m": 0.01}],
                   "under": []}},
    {"id": 6, "class": "chair", "position": [4, 4, 0.45],
     "relations": {"on": {"kind": "surface", "id": 2, "label": "floor", "gap_m": 0.01},
                   "near": [], "above": [], "under": []}},
    {"id": 7, "class": "book", "position": [4, 4, 0.48],
     "relations": {"on": {"kind": "surface", "id": 3, "label": "seat", "gap_m": 0.0},
                   "near": [], "above": [], "under": []}}]})";

struct QueryTest : ::testing::Test {
  TempDir dir;
  MapScene scene;
  void SetUp() override {
    write_text(dir.path() / "objects.json", kObjects);
    scene = io::read_map_scene(dir.path() / "objects.json");
  }
  std::vector<int> ids(const std::string& text) {
    std::vector<int> out;
    for (const auto& m : run_query(parse_query(text, scene), scene).matches)
      out.push_back(m.object->id);
    std::sort(out.begin(), out.end());
    return out;
  }
  std::string error(const std::string& text) {
    try {
      parse_query(text, scene);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(QueryTest, CupOnTheTableIncludesTheCupOnTheBookOnTheTable) {
  EXPECT_EQ(ids("cup on table"), (std::vector<int>{1, 5}));
  EXPECT_EQ(ids("cups on the table"), (std::vector<int>{1, 5}));
  EXPECT_EQ(ids("Cup on table"), (std::vector<int>{1, 5}));
}

TEST_F(QueryTest, EachRelation) {
  EXPECT_EQ(ids("cup on book"), (std::vector<int>{5}));
  EXPECT_EQ(ids("mouse near keyboard"), (std::vector<int>{3}));
  EXPECT_EQ(ids("mice near keyboards"), (std::vector<int>{3}));
  EXPECT_EQ(ids("cup above book"), (std::vector<int>{5}));
  EXPECT_EQ(ids("book under cup"), (std::vector<int>{4}));
  EXPECT_EQ(ids("chair on floor"), (std::vector<int>{6}));
  EXPECT_EQ(ids("book on chair"), (std::vector<int>{7}));  // through the chair's seat
  EXPECT_EQ(ids("book on seat"), (std::vector<int>{7}));
  EXPECT_EQ(ids("book on surface"), (std::vector<int>{4, 7}));
  EXPECT_EQ(ids("books"), (std::vector<int>{4, 7}));
  EXPECT_TRUE(ids("keyboard on floor").empty());
}

TEST_F(QueryTest, NoMatchGivesTheNearestCandidates) {
  const QueryResult r = run_query(parse_query("keyboard on floor", scene), scene);
  EXPECT_TRUE(r.matches.empty());
  ASSERT_EQ(r.candidates.size(), 1u);
  EXPECT_EQ(r.candidates[0].object->id, 2);
  EXPECT_NE(r.candidates[0].why.find("on surface 1 (table)"), std::string::npos);
  // A class the map lacks: what is on the table instead.
  const QueryResult laptop = run_query(parse_query("laptop on table", scene), scene);
  EXPECT_TRUE(laptop.matches.empty());
  EXPECT_EQ(laptop.candidates.size(), 5u);
}

TEST_F(QueryTest, BadQueriesNameTheWord) {
  EXPECT_EQ(error("cupp on table"),
            "query: 'cupp' is not a class of COCO-80 or of this map; expected CLASS "
            "[on|near|above|under CLASS|floor|table|seat|surface], e.g. \"cup on table\"");
  EXPECT_NE(error("cup on desks")
                .find("'desks' is not a class of COCO-80 or of this map nor "
                      "floor|table|seat|surface"),
            std::string::npos);
  EXPECT_NE(error("cup on").find("has no target"), std::string::npos);
  EXPECT_NE(error("").find("query: empty"), std::string::npos);
  EXPECT_NE(error("on table").find("has no class"), std::string::npos);
  // A word after a known beginning is the one named.
  EXPECT_EQ(error("cup beside table")
                .rfind("query: 'beside' is not a relation (on|near|above|under) "
                       "after 'cup'; expected CLASS",
                       0),
            0u);
  EXPECT_EQ(error("tv monitors beside table").rfind("query: 'beside' is not a relation", 0), 0u);
  EXPECT_EQ(
      error("cup on table please")
          .rfind("query: 'please' after 'table' is not understood (one relation per query)", 0),
      0u);
  EXPECT_EQ(error("cup on dining table now").rfind("query: 'now' after 'dining table'", 0), 0u);
  EXPECT_EQ(error("cup near book on table").rfind("query: 'on' after 'book'", 0), 0u);
}

TEST_F(QueryTest, EveryMatchNamesTheSurfaceItStandsOn) {
  const auto surface_of = [&](const std::string& text) {
    std::vector<std::optional<int>> out;
    for (const auto& m : run_query(parse_query(text, scene), scene).matches)
      out.push_back(m.surface);
    return out;
  };
  EXPECT_EQ(surface_of("mouse near keyboard"), (std::vector<std::optional<int>>{1}));
  EXPECT_EQ(surface_of("cup above book"), (std::vector<std::optional<int>>{1}));  // via the book
  EXPECT_EQ(surface_of("book on chair"), (std::vector<std::optional<int>>{3}));   // the seat
  EXPECT_EQ(surface_of("chair"), (std::vector<std::optional<int>>{2}));
}

TEST(QueryRead, ARunWithoutTheSceneIsNamed) {
  TempDir dir;
  write_text(dir.path() / "objects.json",
             R"({"schema_version": 1, "frame": "world", "units": "metres", "objects": []})");
  try {
    io::read_map_scene(dir.path() / "objects.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("objects.json: missing field 'up_in_world'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace objmap::scene
