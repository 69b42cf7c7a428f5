// objmap summary on run folders written here by hand (the files a workflow run leaves: run.json,
// objects.json, eval JSON, logs, benchmarks), so that every figure of the table is known.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "support/schema_check.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

// A complete recording: 3 objects (2 cup, 1 book), 1 duplicate pair, ATE/RPE and object errors,
// fuse timed by GNU time and by Snakemake's benchmark.
void write_ok_run(const fs::path& run) {
  fs::create_directories(run / "map");
  write_text(run / "map" / "objects.json",
             R"({"objects":[{"class":"cup"},{"class":"book"},{"class":"cup"}]})");
  write_text(run / "map" / "run.json", R"({"counts":{"keyframes":17},"duplicates":{"count":1}})");
  fs::create_directories(run / "track");
  write_text(run / "track" / "tracks.json", "{}");
  fs::create_directories(run / "eval");
  write_text(run / "eval" / "ate.json", R"({"pairs":30,"rmse":0.0123})");
  write_text(run / "eval" / "rpe.json",
             R"({"translational":{"rmse":0.0045},"rotational":{"rmse":0.25}})");
  write_text(run / "eval" / "objects.json",
             R"({"counts":[{"class":"cup","reference":2,"error":0.0},
                           {"class":"overall","reference":4,"mapped":3,"error":0.25}],
                 "centroid_error":[{"class":"overall","matched":3,
                                    "distance_m":{"mean":0.031,"rmse":0.042}}]})");
  fs::create_directories(run / "report");
  write_text(run / "report" / "report.html", "<html></html>");
  fs::create_directories(run / "logs");
  for (const char* stage : {"track", "fuse", "eval_ate", "eval_rpe", "eval_objects", "report"})
    write_text(run / "logs" / (std::string(stage) + ".log"), "fine\n");
  fs::create_directories(run / "benchmarks");
  write_text(run / "benchmarks" / "fuse.tsv",
             "s\th:m:s\tmax_rss\tmax_vms\n1.5\t0:00:01\t3.03\t4.0\n");
  write_text(run / "benchmarks" / "fuse.time", "1.48 204800\n");  // 200 MB
  write_text(run / "benchmarks" / "track.time", "0.25 51200\n");  // no .tsv: the time file's
}

// A recording whose fuse failed: its log's last line is the error; the later stages never ran.
void write_failed_run(const fs::path& run) {
  fs::create_directories(run / "track");
  write_text(run / "track" / "tracks.json", "{}");
  fs::create_directories(run / "logs");
  write_text(run / "logs" / "track.log", "fine\n");
  write_text(
      run / "logs" / "fuse.log",
      "reading\nobjmap: error: traj.txt:1: 4 fields; expected 8: timestamp tx ty tz qx qy qz "
      "qw\n\n");
}

TEST(SummaryCli, TheTableCarriesEachRunsOwnFiguresAndNamesTheFailure) {
  TempDir tmp;
  write_ok_run(tmp / "good");
  write_failed_run(tmp / "bad");
  const RunResult r = run_objmap({"summary", (tmp / "good").string(), (tmp / "bad").string(),
                                  "--out", (tmp / "sum").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(tmp / "sum" / "summary.json");
  const json doc = json::parse(in);
  EXPECT_TRUE(validate_json(doc, load_schema("summary.schema.json")).empty());
  const json& good = doc["recordings"][0];
  EXPECT_EQ(good["name"], "good");
  EXPECT_EQ(good["status"], "ok");
  EXPECT_EQ(good["objects"], 3);
  EXPECT_EQ(good["objects_per_class"], json::parse(R"({"book":1,"cup":2})"));
  EXPECT_EQ(good["keyframes"], 17);
  EXPECT_EQ(good["duplicates"], 1);
  EXPECT_DOUBLE_EQ(good["ate_rmse_m"].get<double>(), 0.0123);
  EXPECT_DOUBLE_EQ(good["rpe_translational_rmse_m"].get<double>(), 0.0045);
  EXPECT_DOUBLE_EQ(good["rpe_rotational_rmse_deg"].get<double>(), 0.25);
  EXPECT_EQ(good["gt_objects"], 4);
  EXPECT_EQ(good["matched_objects"], 3);
  EXPECT_DOUBLE_EQ(good["count_error"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(good["centroid_error_mean_m"].get<double>(), 0.031);
  EXPECT_TRUE(good["ate_corrected_rmse_m"].is_null());
  // fuse: seconds from the benchmark, memory from GNU time (exact); track: both from GNU time.
  EXPECT_EQ(good["stages"], json::parse(R"([{"stage":"track","seconds":0.25,"max_rss_mb":50.0},
                                            {"stage":"fuse","seconds":1.5,"max_rss_mb":200.0}])"));
  EXPECT_DOUBLE_EQ(good["seconds"].get<double>(), 1.75);
  const json& bad = doc["recordings"][1];
  EXPECT_EQ(bad["status"], "failed");
  EXPECT_EQ(bad["failed_stage"], "fuse");
  EXPECT_EQ(bad["error"],
            "objmap: error: traj.txt:1: 4 fields; expected 8: timestamp tx ty tz qx qy qz qw");
  EXPECT_TRUE(bad["objects"].is_null());
  EXPECT_EQ(doc["totals"], json::parse(R"({"recordings":2,"ok":1,"failed":1,"incomplete":0,
                                           "objects":3,"seconds":1.75})"));
  const std::string md = read_text(tmp / "sum" / "summary.md");
  EXPECT_NE(md.find("| good | ok | 17 | 3 | 1 | 0.0123 | 0.0045 | 0.250 | - | 4 | 3 | 0.0310 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("- bad: stage fuse: `objmap: error: traj.txt:1: 4 fields"), std::string::npos);
  std::istringstream csv(read_text(tmp / "sum" / "summary.csv"));
  std::string head, first, second;
  std::getline(csv, head);
  std::getline(csv, first);
  std::getline(csv, second);
  EXPECT_EQ(first.substr(0, 40), "good,ok,,,map,17,3,1,0.0123,0.0045,0.25,");
  EXPECT_EQ(second.substr(0, 22), "bad,failed,fuse,objmap");
  EXPECT_NE(head.find(",objects_book,objects_cup"), std::string::npos) << head;
  for (const char* svg : {"objects.svg", "errors.svg"})
    EXPECT_EQ(read_text(tmp / "sum" / svg).rfind("<svg", 0), 0u) << svg;
}

TEST(SummaryCli, AnObjmapRunFolderGivesItsStageTimesFromStagesJson) {
  TempDir tmp;
  const fs::path run = tmp / "run";
  fs::create_directories(run / "map");
  fs::create_directories(run / "report");
  write_text(run / "map" / "objects.json", R"({"objects":[{"class":"chair"}]})");
  write_text(run / "map" / "run.json", R"({"counts":{"keyframes":4},"duplicates":{"count":0}})");
  write_text(run / "report" / "report.html", "<html></html>");
  write_text(run / "stages.json", R"({"detect":{"seconds":1.25},"fuse":{"seconds":0.5}})");
  const RunResult r = run_objmap({"summary", run.string(), "--out", (tmp / "sum").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(tmp / "sum" / "summary.json");
  const json doc = json::parse(in);
  const json& rec = doc["recordings"][0];
  EXPECT_EQ(rec["status"], "ok");
  EXPECT_EQ(rec["objects_per_class"], json::parse(R"({"chair":1})"));
  EXPECT_EQ(rec["stages"], json::parse(R"([{"stage":"detect","seconds":1.25,"max_rss_mb":null},
                                           {"stage":"fuse","seconds":0.5,"max_rss_mb":null}])"));
  EXPECT_TRUE(rec["max_rss_mb"].is_null());
}

TEST(SummaryCli, AFolderThatIsNotARunIsExitTwoNamingIt) {
  TempDir tmp;
  fs::create_directories(tmp / "empty");
  RunResult r = run_objmap({"summary", (tmp / "empty").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("empty: not a run folder: it holds neither logs/ nor map/"),
            std::string::npos)
      << r.err;
  r = run_objmap({"summary", (tmp / "missing").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing: no such folder"), std::string::npos) << r.err;
}

TEST(SummaryCli, AMalformedEvalFileIsExitTwoNamingFileAndField) {
  TempDir tmp;
  write_ok_run(tmp / "good");
  write_text(tmp / "good" / "eval" / "ate.json", R"({"rmse":"small"})");
  RunResult r = run_objmap({"summary", (tmp / "good").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("ate.json: /rmse: not a number"), std::string::npos) << r.err;
  write_text(tmp / "good" / "eval" / "ate.json", "{");
  r = run_objmap({"summary", (tmp / "good").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("ate.json: malformed JSON"), std::string::npos) << r.err;
}

TEST(SummaryCli, AnOutFolderThatHoldsSomethingElseIsRefused) {
  TempDir tmp;
  write_ok_run(tmp / "good");
  fs::create_directories(tmp / "other");
  write_text(tmp / "other" / "keep.txt", "mine");
  const RunResult r =
      run_objmap({"summary", (tmp / "good").string(), "--out", (tmp / "other").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(read_text(tmp / "other" / "keep.txt"), "mine");
}

}  // namespace
}  // namespace objmap::test
