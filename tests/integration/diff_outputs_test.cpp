// The outputs of a diff beyond diff.json, on the shared synthetic pair (tests/support/diff_pair.h,
// seed 11: 2 moved, 1 removed, 1 added): `objmap query --diff` answers what changes_gt.json says
// changed; `objmap report --diff` has a row per change with both thumbnails and a 3D view with
// both maps and an arrow per moved object; a damaged diff.json is exit 2, one line.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "support/diff_pair.h"
#include "support/schema_check.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

constexpr double kMatchM = 0.25;  // as objmap eval diff matches a found change to a true one

struct DiffFixture {
  SynthPair pair;
  fs::path diff;  // DIFF folder
  RunResult why;
};

DiffFixture diff_fixture() {
  DiffFixture f;
  f.pair = diff_synth_pair("11");
  if (!fs::exists(f.pair.run_a) || !fs::exists(f.pair.run_b)) {
    f.why = f.pair.why;
    return f;
  }
  f.diff = diff_synth_diff(f.pair, "11", &f.why);
  return f;
}

Vec3 vec(const json& v) { return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()}; }

// The true objects of a status in changes_gt.json.
std::vector<json> truth(const DiffFixture& f, const std::string& status) {
  std::vector<json> out;
  const json gt = json::parse(read_text(f.pair.second / "changes_gt.json"));  // outlives the loop
  for (const json& o : gt["objects"])
    if (o["status"] == status) out.push_back(o);
  return out;
}

json query_json(const DiffFixture& f, const std::string& text) {
  const RunResult r = run_objmap({"query", "--diff", f.diff.string(), text, "--json"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? json::parse(r.out) : json::object();
}

// Each true change matched by exactly one answer at its place (before end for moved and removed,
// after end, in B's world, for added; moved also at the after end), and no answer left over.
void expect_answers_are_the_truth(const json& answers, const std::vector<json>& truth,
                                  const std::string& status) {
  ASSERT_EQ(answers["matches"].size(), truth.size()) << answers.dump(1);
  std::vector<bool> used(truth.size(), false);
  for (const json& m : answers["matches"]) {
    EXPECT_EQ(m["status"], status);
    bool found = false;
    for (std::size_t k = 0; k < truth.size() && !found; ++k) {
      const json& t = truth[k];
      bool near = true;
      if (!t["before_position"].is_null())
        near = near && (vec(m["before"]["position"]) - vec(t["before_position"])).norm() < kMatchM;
      if (!t["after_position"].is_null())
        near = near && (vec(m["after"]["position"]) - vec(t["after_position"])).norm() < kMatchM;
      if (near && !used[k]) used[k] = found = true;
    }
    EXPECT_TRUE(found) << m.dump();
  }
}

TEST(DiffOutputs, QueryAnswersAreTheTrueChanges) {
  const DiffFixture f = diff_fixture();
  ASSERT_TRUE(fs::exists(f.diff / "diff.json")) << f.why.err;
  for (const std::string status : {"moved", "added", "removed"}) {
    SCOPED_TRACE(status);
    const json answers = query_json(f, "what " + status);
    EXPECT_TRUE(validate_json(answers, load_schema("query_diff.schema.json")).empty());
    expect_answers_are_the_truth(answers, truth(f, status), status);
  }
  // Moved: the displacement is after − before in A's frame.
  const json which = query_json(f, "which objects moved?");  // outlives the loop
  for (const json& m : which["matches"]) {
    const Vec3 d = vec(m["after"]["position_in_before"]) - vec(m["before"]["position"]);
    EXPECT_LT((vec(m["displacement_m"]) - d).norm(), 1e-6) << m.dump();
  }
  // A class narrows it: "moved CLASS" is the moved objects of that class.
  const json moved = query_json(f, "what moved");
  ASSERT_FALSE(moved["matches"].empty());
  const std::string cls = moved["matches"][0]["before"]["class"];
  const json of_class = query_json(f, "moved " + cls);
  for (const json& m : of_class["matches"]) EXPECT_EQ(m["before"]["class"], cls);
  // The text answer names each moved object with its displacement.
  const RunResult text = run_objmap({"query", "--diff", f.diff.string(), "what moved"});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("moved"), std::string::npos) << text.out;
}

TEST(DiffOutputs, QueryBadInputIsExit2OneLine) {
  const DiffFixture f = diff_fixture();
  ASSERT_TRUE(fs::exists(f.diff / "diff.json")) << f.why.err;
  TempDir tmp;
  json doc = json::parse(read_text(f.diff / "diff.json"));
  doc["objects"][0]["before"] = "x";
  doc["objects"][0]["status"] = "removed";
  write_text(tmp / "diff.json", doc.dump(1));
  const std::vector<std::vector<std::string>> bad = {
      {"query", "--diff", (tmp / "diff.json").string(), "what moved"},  // damaged
      {"query", "--diff", f.diff.string(), "what flew"},                // not understood
      {"query", "--diff", (tmp / "none").string(), "what moved"},       // no file
      {"query", "what moved"},                                          // no input
      {"query", "--diff", f.diff.string(), "--run", f.pair.run_a.string(), "cup"}};  // both
  for (const auto& args : bad) {
    const RunResult r = run_objmap(args);
    EXPECT_EQ(r.exit_code, 2) << args[args.size() - 1] << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  const RunResult damaged = run_objmap(bad[0]);
  EXPECT_NE(damaged.err.find((tmp / "diff.json").string() + ": objects[0].before"),
            std::string::npos)
      << damaged.err;
}

// The JSON of the page's 3D view (<script type="application/json" id="view3d-data">).
json view3d_data(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"view3d-data\">";
  const std::size_t start = html.find(open);
  if (start == std::string::npos) return json();
  const std::size_t end = html.find("</script>", start);
  return json::parse(html.substr(start + open.size(), end - start - open.size()));
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(DiffOutputs, ReportHasARowPerChangeBothThumbnailsAndBothMaps) {
  const DiffFixture f = diff_fixture();
  ASSERT_TRUE(fs::exists(f.diff / "diff.json")) << f.why.err;
  TempDir tmp;
  const fs::path out = tmp / "report";
  const RunResult r = run_objmap({"report", "--diff", f.diff.string(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = read_text(out / "report.html");
  const json diff = json::parse(read_text(f.diff / "diff.json"));
  int changes = 0, moved = 0;
  for (const json& o : diff["objects"]) {
    changes += o["status"] != "unchanged";
    moved += o["status"] == "moved";
  }
  ASSERT_GE(changes, 4);
  EXPECT_EQ(occurrences(html, "<tr data-status="), static_cast<std::size_t>(changes));
  EXPECT_EQ(occurrences(html, "<tr data-status=\"moved\""), static_cast<std::size_t>(moved));
  // Both thumbnails per row, embedded, and as files beside report.md.
  EXPECT_EQ(occurrences(html, "<img class=\"thumb\""), static_cast<std::size_t>(2 * changes));
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(out / "thumbnails"))
    files += e.path().extension() == ".png";
  EXPECT_EQ(files, static_cast<std::size_t>(2 * changes));
  // A side without an object says why (removed: not in B; added: not in A).
  EXPECT_NE(html.find("not in B: B saw its place empty"), std::string::npos);
  EXPECT_NE(html.find("not in A: A saw its place empty"), std::string::npos);
  // The registration: transform, fitness, uncertainty.
  for (const char* row : {"transform (rows 1-3)", "fitness", "σ translation"})
    EXPECT_NE(html.find(row), std::string::npos) << row;
  // The 3D view: both maps, one arrow per moved object from its old to its new place.
  const json data = view3d_data(html);
  ASSERT_TRUE(data.is_object());
  EXPECT_GT(data["map"]["count"].get<int>(), 1000);
  ASSERT_TRUE(data.contains("second_map"));
  EXPECT_GT(data["second_map"]["count"].get<int>(), 1000);
  ASSERT_TRUE(data.contains("arrows"));
  EXPECT_EQ(data["arrows"].size(), static_cast<std::size_t>(moved));
  for (const json& a : data["arrows"])
    EXPECT_GT((vec(a["to"]) - vec(a["from"])).norm(), 0.2) << a.dump();
  EXPECT_NE(html.find("data-layer=\"second_map\""), std::string::npos);
  EXPECT_NE(html.find("data-layer=\"arrows\""), std::string::npos);
  // Exactly one of --run and --diff.
  const RunResult both = run_objmap({"report", "--diff", f.diff.string(), "--run",
                                     f.pair.run_a.string(), "--out", (tmp / "r2").string()});
  EXPECT_EQ(both.exit_code, 2) << both.err;
  const RunResult none = run_objmap({"report", "--out", (tmp / "r3").string()});
  EXPECT_EQ(none.exit_code, 2) << none.err;
  EXPECT_EQ(std::count(none.err.begin(), none.err.end(), '\n'), 1) << none.err;
}

}  // namespace
}  // namespace objmap::test
