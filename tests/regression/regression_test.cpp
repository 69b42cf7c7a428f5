// CI regression gate: the whole pipeline on a synthetic scene and on fr3_cabinet_58kf, with the
// paper's Table 3/4/5 style errors compared to the thresholds of tests/regression/thresholds.json
// (each the measured value plus a small margin, the measurement recorded beside it). A change that
// makes any of them worse than its threshold fails `make test`. Each check prints
// "metric: measured X, threshold <= Y (recorded Z on DATE)".
//
// The runs are shared through cached_output with tests/integration (same keys, same arguments):
// "seed3-orbit60-scene" (objmap synth --seed 3 --orbit-speed 60), "seed3-orbit60-fuse" (fuse with
// groundtruth.txt), plus "seed3-orbit60-fuse-estimated" (fuse with the drifting estimated.txt) and
// "fr3cabinet-fuse" (fr3_cabinet_58kf with groundtruth.txt and boxes_yolov2).
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

fs::path thresholds_file() {
  return fs::path(OBJMAP_SOURCE_DIR_FOR_TESTS) / "tests" / "regression" / "thresholds.json";
}

const json& thresholds() {
  static const json doc = [] {
    std::ifstream in(thresholds_file());
    return json::parse(in, nullptr, /*allow_exceptions=*/false);
  }();
  return doc;
}

// Compares `value` with the metric's "max" (or "min") threshold and prints both.
void check(const std::string& metric, double value) {
  SCOPED_TRACE(metric);
  const json& all = thresholds();
  ASSERT_TRUE(all.is_object() && all.contains("metrics")) << thresholds_file();
  ASSERT_TRUE(all["metrics"].contains(metric))
      << "no threshold for " << metric << " in " << thresholds_file() << " (measured " << value
      << ")";
  const json& t = all["metrics"][metric];
  const std::string recorded = " (recorded " + t.value("measured", json()).dump() + " on " +
                               t.value("date", std::string("?")) + ")";
  if (t.contains("max")) {
    const double max = t["max"].get<double>();
    std::cout << "[ regression ] " << metric << ": measured " << value << ", threshold <= " << max
              << recorded << std::endl;
    EXPECT_LE(value, max) << metric << " regressed beyond its threshold" << recorded;
  }
  if (t.contains("min")) {
    const double min = t["min"].get<double>();
    std::cout << "[ regression ] " << metric << ": measured " << value << ", threshold >= " << min
              << recorded << std::endl;
    EXPECT_GE(value, min) << metric << " regressed beyond its threshold" << recorded;
  }
}

// `objmap eval objects <args> --json F`, parsed; null on failure (with the reason in `why`).
json eval_objects(const std::vector<std::string>& args, std::string* why) {
  TempDir dir;
  std::vector<std::string> a{"eval", "objects"};
  a.insert(a.end(), args.begin(), args.end());
  a.insert(a.end(), {"--json", (dir / "eval.json").string()});
  const RunResult r = run_objmap(a);
  if (r.exit_code != 0) {
    *why = "exit " + std::to_string(r.exit_code) + ": " + r.err;
    return json();
  }
  std::ifstream in(dir / "eval.json");
  return json::parse(in, nullptr, false);
}

const json& overall(const json& rows) {
  for (const auto& r : rows)
    if (r.at("class") == "overall") return r;
  static const json none;
  return none;
}

struct SyntheticRuns {
  fs::path scene, gt_run, est_run;
  RunResult synth, gt_fuse, est_fuse;
};

const SyntheticRuns& synthetic() {
  static const SyntheticRuns runs = [] {
    SyntheticRuns s;
    s.scene =
        cached_output("seed3-orbit60-scene",
                      {"synth", "--out", "{OUT}", "--seed", "3", "--orbit-speed", "60"}, &s.synth);
    if (!fs::exists(s.scene)) return s;
    auto fuse = [&](const std::string& key, const std::string& trajectory, RunResult* result) {
      return cached_output(
          key,
          {"fuse", "--dataset", s.scene.string(), "--trajectory", (s.scene / trajectory).string(),
           "--segmentation", (s.scene / "segmentation").string(), "--out", "{OUT}"},
          result);
    };
    s.gt_run = fuse("seed3-orbit60-fuse", "groundtruth.txt", &s.gt_fuse);
    s.est_run = fuse("seed3-orbit60-fuse-estimated", "estimated.txt", &s.est_fuse);
    return s;
  }();
  return runs;
}

TEST(Regression, ThresholdsFileIsComplete) {
  const json& all = thresholds();
  ASSERT_TRUE(all.is_object() && all.contains("metrics")) << thresholds_file();
  ASSERT_GE(all["metrics"].size(), 8u);
  for (const auto& [name, t] : all["metrics"].items()) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(t.contains("max") || t.contains("min"));
    ASSERT_TRUE(t.contains("measured") && t["measured"].is_number());
    EXPECT_TRUE(t.contains("date") && t["date"].is_string());
    EXPECT_TRUE(t.contains("command") && t["command"].is_string());
    // A threshold is the measurement plus a margin: the recorded measurement passes it.
    const double measured = t["measured"].get<double>();
    if (t.contains("max")) {
      EXPECT_LE(measured, t["max"].get<double>());
    }
    if (t.contains("min")) {
      EXPECT_GE(measured, t["min"].get<double>());
    }
  }
}

TEST(Regression, GateFailsBeyondAThreshold) {
  EXPECT_NONFATAL_FAILURE(check("fr3_cabinet.centroid_error_m", 1.0),
                          "regressed beyond its threshold");
  EXPECT_NONFATAL_FAILURE(check("fr3_cabinet.obb_iou", 0.0), "regressed beyond its threshold");
}

// Table 3 and the centroid error of the map fused with the ground-truth trajectory, against the
// scene's exact objects (objects_gt.json, volume centroids).
TEST(Regression, SyntheticSeed3MapVsTrueObjects) {
  const SyntheticRuns& s = synthetic();
  ASSERT_TRUE(fs::exists(s.scene)) << s.synth.err;
  ASSERT_TRUE(fs::exists(s.gt_run)) << s.gt_fuse.err;
  std::string why;
  const json e = eval_objects({"--map", (s.gt_run / "objects.json").string(), "--gt-objects",
                               (s.scene / "objects_gt.json").string()},
                              &why);
  ASSERT_TRUE(e.is_object()) << why;
  const json& counts = overall(e.at("counts"));
  const json& centroid = overall(e.at("centroid_error"));
  ASSERT_TRUE(counts.is_object() && centroid.is_object());
  check("synthetic_seed3.gt_map.count_error", counts.at("error").get<double>());
  check(
      "synthetic_seed3.gt_map.unmatched_true_objects",
      static_cast<double>(centroid.at("reference").get<int>() - centroid.at("matched").get<int>()));
  check("synthetic_seed3.gt_map.mean_centroid_error_m", centroid["distance_m"]["mean"]);
  check("synthetic_seed3.gt_map.max_centroid_error_m", centroid["distance_m"]["max"]);
  check("synthetic_seed3.gt_map.mean_obb_iou", centroid["iou"]["mean"]);
}

// Tables 4-5 (the paper's protocol): the map fused with the drifting estimated.txt against the
// map fused with groundtruth.txt, and against the true objects.
TEST(Regression, SyntheticSeed3EstimateMapVsGroundTruthMap) {
  const SyntheticRuns& s = synthetic();
  ASSERT_TRUE(fs::exists(s.gt_run)) << s.gt_fuse.err;
  ASSERT_TRUE(fs::exists(s.est_run)) << s.est_fuse.err;
  std::string why;
  const json e = eval_objects({"--map", (s.est_run / "objects.json").string(), "--reference",
                               (s.gt_run / "objects.json").string()},
                              &why);
  ASSERT_TRUE(e.is_object()) << why;
  const json& counts = overall(e.at("counts"));
  const json& centroid = overall(e.at("centroid_error"));
  ASSERT_TRUE(counts.is_object() && centroid.is_object());
  check("synthetic_seed3.est_map_vs_gt_map.count_error", counts.at("error").get<double>());
  check("synthetic_seed3.est_map_vs_gt_map.mean_centroid_error_m", centroid["distance_m"]["mean"]);

  const json t = eval_objects({"--map", (s.est_run / "objects.json").string(), "--gt-objects",
                               (s.scene / "objects_gt.json").string()},
                              &why);
  ASSERT_TRUE(t.is_object()) << why;
  check("synthetic_seed3.est_map.mean_centroid_error_m",
        overall(t.at("centroid_error"))["distance_m"]["mean"]);
}

// fr3_cabinet_58kf: one cabinet, YOLOv2 boxes without class or track id, ground-truth trajectory;
// the ground truth is a cuboid (objects_gt.txt).
TEST(Regression, Fr3CabinetObjectVsCuboid) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr3_cabinet_58kf");
  RunResult fuse;
  const fs::path run = cached_output(
      "fr3cabinet-fuse",
      {"fuse", "--dataset", data.string(), "--trajectory", (data / "groundtruth.txt").string(),
       "--segmentation", (data / "boxes_yolov2").string(), "--out", "{OUT}"},
      &fuse);
  ASSERT_TRUE(fs::exists(run)) << fuse.err;
  std::string why;
  const json e = eval_objects({"--map", (run / "objects.json").string(), "--gt-objects",
                               (data / "objects_gt.txt").string()},
                              &why);
  ASSERT_TRUE(e.is_object()) << why;
  const json& counts = overall(e.at("counts"));
  const json& centroid = overall(e.at("centroid_error"));
  ASSERT_TRUE(counts.is_object() && centroid.is_object());
  check("fr3_cabinet.count_error", counts.at("error").get<double>());
  ASSERT_EQ(centroid.at("matched").get<int>(), 1) << "the cabinet is not in the map";
  check("fr3_cabinet.centroid_error_m", centroid["distance_m"]["mean"]);
  check("fr3_cabinet.obb_iou", centroid["iou"]["mean"]);
}

// scripts/bench_tables.py (make bench): `python3 bench_tables.py <args>`, output in `log`.
int bench_tables(const std::string& args, const fs::path& log) {
  const fs::path script = fs::path(OBJMAP_SOURCE_DIR_FOR_TESTS) / "scripts" / "bench_tables.py";
  const std::string cmd = "python3 " + script.string() + " " + args + " >" + log.string() + " 2>&1";
  return std::system(cmd.c_str());
}

bool has_python3() { return std::system("python3 -c pass >/dev/null 2>&1") == 0; }

// A bench output folder with one synthetic sequence: 12 true objects, 11 mapped.
void write_fake_bench(const fs::path& bench) {
  write_text(bench / "features.txt", "has_correct=0\nload_start=1.0 1.0 1.0\n");
  write_text(bench / "synth_seed9" / "meta.txt",
             "name=synth_seed9\nkind=synthetic\nframes=90\nsegmentation=/x/segmentation\n"
             "estimate=\ngt_objects=/x/objects_gt.json\n");
  write_text(bench / "synth_seed9" / "run_gt" / "run.json",
             R"({"counts": {"frames": 90, "keyframes": 90, "keyframe_mode": "motion",
                 "objects_confirmed": 11},
                 "points": {"dense_back_projected": 1000, "dense_map": 500, "objects_raw": 400,
                 "objects_voxel_filtered": 200, "objects_outlier_filtered": 150,
                 "objects_map": 150},
                 "duplicates": {"count": 1, "pairs": [{"a": 3, "b": 7, "class": "book",
                 "merge_refused": "shared_frames"}]}})");
  const std::string stats =
      R"({"count": 11, "rmse": 0.04, "mean": 0.0321, "median": 0.03, "std": 0.01, "min": 0.01,
          "max": 0.08})";
  write_text(bench / "synth_seed9" / "objects_gt_vs_truth.json",
             R"({"counts": [{"class": "overall", "reference": 12, "mapped": 11,
                 "error": 0.0833333}],
                 "centroid_error": [{"class": "overall", "reference": 12, "mapped": 11,
                 "matched": 11, "distance_m": )" +
                 stats + R"(, "iou": )" + stats + "}]}");
}

TEST(BenchTables, RenderReplacesOnlyTheGeneratedSection) {
  if (!has_python3()) GTEST_SKIP() << "no python3";
  TempDir dir;
  write_fake_bench(dir / "bench");
  const std::string head = "# Benchmarks\n\nIntro written by hand.\n\n";
  const std::string tail = "\n\n## Analysis\n\nHand-written analysis, kept.\n";
  write_text(dir / "doc.md", head + "<!-- bench:begin -->\nOLD TABLES\n<!-- bench:end -->" + tail);
  const std::string args = "render --bench " + (dir / "bench").string() + " --doc " +
                           (dir / "doc.md").string() + " --command 'make bench'";
  ASSERT_EQ(bench_tables(args, dir / "log"), 0) << read_text(dir / "log");
  const std::string doc = read_text(dir / "doc.md");
  EXPECT_EQ(doc.rfind(head, 0), 0u) << doc;
  EXPECT_EQ(doc.substr(doc.size() - tail.size()), tail) << doc;
  EXPECT_EQ(doc.find("OLD TABLES"), std::string::npos) << doc;
  // Table 3 row: 12 true objects, 11 mapped, 8.3%; Table 4-5 column: mean 0.0321 m.
  EXPECT_NE(doc.find("| synth_seed9 | 12 | 11 | 8.3% |"), std::string::npos) << doc;
  // ... and its suspected duplicates (run.json "duplicates"): count, ids, class, refusing rule.
  EXPECT_NE(doc.find("| 1: 3+7 book (shared frames) |"), std::string::npos) << doc;
  EXPECT_NE(doc.find("0.0321"), std::string::npos) << doc;
  EXPECT_NE(doc.find("0.0115"), std::string::npos) << "the paper's Table 7 beside ours";
  EXPECT_EQ(doc.find("YOLOv5n-seg masks"), std::string::npos) << "no network chain was run";

  // The network chain's table (scripts/network_chain.sh) goes in when the bench made it.
  write_text(dir / "bench" / "network_chain.md",
             "| sequence | front end |\n|---|---|\n| fr1_desk_9 | YOLOv5n-seg masks |\n");
  ASSERT_EQ(bench_tables(args, dir / "log"), 0) << read_text(dir / "log");
  const std::string with_chain = read_text(dir / "doc.md");
  EXPECT_NE(with_chain.find("| fr1_desk_9 | YOLOv5n-seg masks |"), std::string::npos) << with_chain;
  EXPECT_LT(with_chain.find("YOLOv5n-seg masks |"), with_chain.find("<!-- bench:end -->"));
  fs::remove(dir / "bench" / "network_chain.md");

  // Without markers the section goes after the intro, before the first "## " heading.
  write_text(dir / "doc.md", head + "## Analysis\n\nkept\n");
  ASSERT_EQ(bench_tables(args, dir / "log"), 0) << read_text(dir / "log");
  const std::string doc2 = read_text(dir / "doc.md");
  const auto begin = doc2.find("<!-- bench:begin -->");
  ASSERT_NE(begin, std::string::npos) << doc2;
  EXPECT_EQ(begin, head.size()) << doc2;
  EXPECT_LT(doc2.find("<!-- bench:end -->"), doc2.find("## Analysis\n\nkept\n")) << doc2;
}

// make bench's fuse steps: each step of run.json per keyframe, beside the figures of the table as
// last committed (here: the document as it is, outside git), naming the step that grew.
TEST(BenchTables, FuseStepsAreComparedWithTheLastCommittedFiguresNamingTheStepThatGrew) {
  if (!has_python3()) GTEST_SKIP() << "no python3";
  TempDir dir;
  const fs::path bench = dir / "bench";
  write_fake_bench(bench);
  write_text(bench / "perf" / "meta.txt", "dataset=/x/fr1_rpy_every4\n");
  write_text(bench / "perf" / "objmap_1.json",
             R"({"exit_code": 0, "seconds": 2.0, "cpu_seconds": 3.5, "peak_rss_mb": 300})");
  write_text(bench / "perf" / "objmap_run_1.json",
             R"({"counts": {"keyframes": 100}, "performance": {"seconds": {
                 "back-project and fuse": 1.2, "merge and filter objects": 0.4,
                 "write outputs": 0.05, "total": 1.9}}})");
  write_text(bench / "perf" / "bench_fuse.txt",
             "fuse, 2 threads         18.00 ms/keyframe  (1.80 s total, best of 3)\n"
             "decode, 1 thread         4.00 ms/keyframe\n"
             "OpenCV imread, 1 thr     8.00 ms/keyframe  (the same PNGs, libpng + zlib)\n"
             "objmap start-up          70.0 ms  (objmap --version, median of 11)\n");
  const std::string args = "render --bench " + bench.string() + " --doc " +
                           (dir / "doc.md").string() + " --command 'make bench'";
  ASSERT_EQ(bench_tables(args, dir / "log"), 0) << read_text(dir / "log");
  std::string doc = read_text(dir / "doc.md");
  // 1.2 s over 100 keyframes: 12 ms; the whole command 20 ms, 2.5x cv::imread's 8 ms.
  EXPECT_NE(doc.find("| back-project and fuse | 12.00 |  |  |"), std::string::npos) << doc;
  EXPECT_NE(doc.find("| merge and filter objects | 4.00 |"), std::string::npos) << doc;
  EXPECT_NE(doc.find("| whole command (wall) | 20.00 |"), std::string::npos) << doc;
  EXPECT_NE(doc.find("| objmap start-up (once per command, per keyframe here) | 0.70 |"),
            std::string::npos)
      << doc;
  EXPECT_NE(doc.find("| whole command / cv::imread of its PNGs (ratio, not ms) | 2.50 |"),
            std::string::npos)
      << doc;
  EXPECT_NE(doc.find("No earlier figures to compare with"), std::string::npos) << doc;

  // The committed figures said merge and filter took 3 ms and the fuse 12.1: the merge grew by
  // 1 ms (33%), the fuse's 0.1 ms is noise.
  const auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = doc.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    doc.replace(at, from.size(), to);
  };
  replace("| merge and filter objects | 4.00 |", "| merge and filter objects | 3.00 |");
  replace("| back-project and fuse | 12.00 |", "| back-project and fuse | 11.90 |");
  write_text(dir / "doc.md", doc);
  ASSERT_EQ(bench_tables(args, dir / "log"), 0) << read_text(dir / "log");
  const std::string again = read_text(dir / "doc.md");
  EXPECT_NE(again.find("| merge and filter objects | 4.00 | 3.00 | +1.00 (+33%) |"),
            std::string::npos)
      << again;
  EXPECT_NE(again.find("| back-project and fuse | 12.00 | 11.90 | +0.10 (+1%) |"),
            std::string::npos)
      << again;
  EXPECT_NE(again.find("Grew since the last committed figures (" + (dir / "doc.md").string() +
                       "): merge and filter objects (+1.00 ms per keyframe, +33%)."),
            std::string::npos)
      << again;
  EXPECT_EQ(again.find("back-project and fuse (+"), std::string::npos) << again;
  EXPECT_NE(read_text(dir / "log").find("fuse steps: Grew since"), std::string::npos);
}

TEST(BenchTables, PrepareMovesASlamEstimateOntoTheGroundTruth) {
  if (!has_python3()) GTEST_SKIP() << "no python3";
  TempDir dir;
  // Ground truth: start at (1, 2, 3) turned 90 degrees about z, then move along its x axis.
  // The estimate starts at the identity (SLAM frame) and covers the first 3 of 5 frames.
  const double s = std::sqrt(0.5);
  std::string gt, est, rgb = "# rgb\n";
  for (int i = 0; i < 5; ++i) {
    const double t = 10.0 + 0.1 * i;
    gt += std::to_string(t) + " 1 " + std::to_string(2.0 + 0.1 * i) + " 3 0 0 " +
          std::to_string(s) + " " + std::to_string(s) + "\n";
    if (i < 3) est += std::to_string(t) + " " + std::to_string(0.1 * i) + " 0 0 0 0 0 1\n";
    rgb += std::to_string(t) + " rgb/" + std::to_string(i) + ".png\n";
  }
  write_text(dir / "seq" / "groundtruth.txt", gt);
  write_text(dir / "seq" / "rgb.txt", rgb);
  write_text(dir / "est.txt", est);
  const std::string args = "prepare --dataset " + (dir / "seq").string() + " --gt " +
                           (dir / "seq" / "groundtruth.txt").string() + " --est " +
                           (dir / "est.txt").string() + " --out-dir " + (dir / "out").string();
  ASSERT_EQ(bench_tables(args, dir / "log"), 0) << read_text(dir / "log");
  const std::string log = read_text(dir / "log");
  EXPECT_NE(log.find("aligned=1"), std::string::npos) << log;
  EXPECT_NE(log.find("reference=" + (dir / "out" / "groundtruth_span.txt").string()),
            std::string::npos)
      << log;
  // Third estimate pose: 0.2 m along the camera's x, i.e. world y after the 90 degree turn.
  std::istringstream aligned(read_text(dir / "out" / "estimate_aligned.txt"));
  std::string line;
  std::vector<std::vector<double>> rows;
  while (std::getline(aligned, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream row(line);
    std::vector<double> v(8);
    for (double& x : v) row >> x;
    rows.push_back(v);
  }
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_NEAR(rows[2][1], 1.0, 1e-5);
  EXPECT_NEAR(rows[2][2], 2.2, 1e-5);
  EXPECT_NEAR(rows[2][3], 3.0, 1e-5);
  EXPECT_NEAR(std::abs(rows[2][6]), s, 1e-5);
  EXPECT_NEAR(std::abs(rows[2][7]), s, 1e-5);
  // The reference ground truth keeps only the estimate's span (3 of 5 poses).
  std::istringstream span(read_text(dir / "out" / "groundtruth_span.txt"));
  int poses = 0;
  while (std::getline(span, line)) poses += !line.empty() && line[0] != '#';
  EXPECT_EQ(poses, 3);
}

// scripts/ablation_tables.py (make ablation) on a fixture: one row, three columns, one sweep cell
// of the hard scene set; then a run of the sweep alone, which leaves the ablation's table be.
TEST(AblationTables, RenderCellsIntoTheirMarkers) {
  if (!has_python3()) GTEST_SKIP() << "no python3";
  TempDir dir;
  const fs::path root = dir / "ablation";
  write_text(
      root / "features.txt",
      "load_start=1.0 1.0 1.0\ndate=2026-01-01 00:00 UTC\nsweep_set_hard=--orbit-speed 60\n");
  write_text(root / "columns.txt",
             "paper|paper (--method paper)|--method paper\nobjmap|objmap (defaults)|\n"
             "iou|--overlap iou|--overlap iou\n");
  // Two true objects (cups at x = 0 and x = 1); map objects: 0 and 1 matched 2 cm off (their
  // positions 1 and 3 cm from the true box centres), 2 a second cup 5 cm from the first (a
  // duplicate), 3 a book far away (not a duplicate).
  const auto objects = [](int n) {
    const double x[] = {0.02, 1.02, 0.05, 5.0};
    const char* cls[] = {"cup", "cup", "cup", "book"};
    std::string s = R"({"objects": [)";
    for (int i = 0; i < n; ++i)
      s += std::string(i ? "," : "") + R"({"id": )" + std::to_string(i) + R"(, "class": ")" +
           cls[i] + R"(", "centroid": [)" + std::to_string(x[i]) + ", 0, 0]}";
    return s + "]}";
  };
  const auto eval = [](int mapped, std::vector<int> unmatched) {
    std::string u;
    for (int id : unmatched) u += (u.empty() ? "" : ",") + std::to_string(id);
    return R"({"counts": [{"class": "overall", "reference": 2, "mapped": )" +
           std::to_string(mapped) + R"(, "error": 0}], "matches": [
             {"map_id": 0, "class": "cup", "distance_m": 0.02, "error_xyz_m": [0.02, 0, 0],
              "position_distance_m": 0.01},
             {"map_id": 1, "class": "cup", "distance_m": 0.02, "error_xyz_m": [0.02, 0, 0],
              "position_distance_m": 0.03}],
             "unmatched_map_ids": [)" +
           u + "]}";
  };
  const std::string run_json = R"({"options": {"method": "objmap", "objects": {"overlap_measure":
      "containment"}}, "points": {"objects_outlier_filtered": 35100}})";
  for (const std::string col : {"paper", "objmap", "iou"}) {
    const fs::path c = root / "ablation" / "synth_seed9" / col;
    const bool extra = col != "objmap";
    write_text(c / "run_gt" / "objects.json", objects(extra ? 4 : 2));
    write_text(c / "vs_truth.json", extra ? eval(4, {2, 3}) : eval(2, {}));
    std::string run = run_json;
    if (extra) run.replace(run.find("\"containment\""), 13, "\"iou\"");
    write_text(c / "run_gt" / "run.json", run);
  }
  write_text(root / "ablation" / "synth_seed9" / "objmap" / "est_vs_gtmap.json",
             R"({"centroid_error": [{"class": "overall", "reference": 2, "matched": 2,
                 "distance_m": {"mean": 0.047}}]})");
  const fs::path cell = root / "sweep" / "hard" / "seed11" / "wid0.3_wd0.2_wm0.5_k0.4";
  write_text(cell / "run_gt" / "objects.json", objects(2));
  write_text(cell / "vs_truth.json", eval(2, {}));

  const std::string tail = "\n\nHand-written, kept.\n";
  write_text(dir / "bench.md", "# B\n\n<!-- ablation:begin -->\nOLD\n<!-- ablation:end -->" + tail);
  write_text(dir / "fusion.md", "# F\n\n<!-- sweep:begin -->\nOLD\n<!-- sweep:end -->" + tail);
  const fs::path script = fs::path(OBJMAP_SOURCE_DIR_FOR_TESTS) / "scripts" / "ablation_tables.py";
  const auto render = [&](const fs::path& from) {
    const std::string cmd = "python3 " + script.string() + " render --ablation " + from.string() +
                            " --doc " + (dir / "bench.md").string() + " --fusion-doc " +
                            (dir / "fusion.md").string() + " >" + (dir / "log").string() + " 2>&1";
    return std::system(cmd.c_str());
  };
  ASSERT_EQ(render(root), 0) << read_text(dir / "log");
  const std::string bench = read_text(dir / "bench.md");
  EXPECT_EQ(bench.find("OLD"), std::string::npos) << bench;
  EXPECT_EQ(bench.substr(bench.size() - tail.size()), tail) << bench;
  EXPECT_NE(bench.find("| synth_seed9 | 4/2 d1 · 2.0 cm | 2/2 d0 · 2.0 cm | 4/2 d1 · 2.0 cm |"),
            std::string::npos)
      << bench;
  EXPECT_NE(bench.find("| 4.7 cm (2/2) · 35.1k |"), std::string::npos) << bench;
  // The paper differs from objmap in overlap_measure only, and the iou column covers it.
  EXPECT_NE(bench.find("`objects.overlap_measure`. Each is set"), std::string::npos) << bench;
  const std::string fusion = read_text(dir / "fusion.md");
  EXPECT_EQ(fusion.substr(fusion.size() - tail.size()), tail) << fusion;
  EXPECT_NE(fusion.find("| 0.3, 0.2 | **2/2 d0 · 2.0 cm · 1/1 exact** (default) |"),
            std::string::npos)
      << fusion;
  EXPECT_NE(fusion.find("#### Scenes that put the weights to the test: `objmap synth --seed N "
                        "--orbit-speed 60`"),
            std::string::npos)
      << fusion;
  EXPECT_NE(fusion.find("Cells that map every seed exactly: 1 of 1; objmap's default is one of "
                        "them."),
            std::string::npos)
      << fusion;
  // The sweep alone (ABLATION_PARTS=sweep): the ablation's table stays as it was.
  fs::remove_all(root / "ablation");
  ASSERT_EQ(render(root), 0) << read_text(dir / "log");
  EXPECT_EQ(read_text(dir / "bench.md"), bench);
}

// scripts/frame_planes.sh (docs/scene.md's per-frame plane lean) on the synthetic scene, whose
// groundtruth.txt is z up and whose floor is level: in each frame it checks, the floor (height 0)
// leans under a degree. A missing sequence is refused in one line with exit code 2.
TEST(FramePlanes, ALevelSyntheticFloorLeansUnderADegreeInEveryFrame) {
  if (!has_python3()) GTEST_SKIP() << "no python3";
  const SyntheticRuns& s = synthetic();
  ASSERT_TRUE(fs::exists(s.scene)) << s.synth.err;
  TempDir dir;
  const fs::path script = fs::path(OBJMAP_SOURCE_DIR_FOR_TESTS) / "scripts" / "frame_planes.sh";
  const auto run = [&](const fs::path& sequence) {
    const std::string cmd = "bash " + script.string() + " " + sequence.string() +
                            " segmentation 45 " + objmap_binary().string() + " >" +
                            (dir / "out").string() + " 2>" + (dir / "err").string();
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  ASSERT_EQ(run(s.scene), 0) << read_text(dir / "err");
  std::istringstream out(read_text(dir / "out"));
  std::string line;
  std::getline(out, line);
  EXPECT_EQ(line.rfind("frame  planes within 20 deg of +z", 0), 0u) << line;
  int frames = 0;
  while (std::getline(out, line)) {
    SCOPED_TRACE(line);
    ++frames;
    // "FRAME ANGLE@POINTS (HEIGHT) [X Y] ...": the floor is the plane at height 0.
    std::istringstream fields(line);
    std::string frame, plane, height, x, y;
    fields >> frame;
    bool floor = false;
    while (fields >> plane >> height >> x >> y)
      if (std::fabs(std::stod(height.substr(1))) < 0.03) {
        floor = true;
        EXPECT_LT(std::stod(plane.substr(0, plane.find('@'))), 1.0);
      }
    EXPECT_TRUE(floor) << "no floor plane in this frame";
  }
  EXPECT_GE(frames, 2);

  EXPECT_EQ(run(dir / "nowhere"), 2);
  const std::string err = read_text(dir / "err");
  EXPECT_NE(err.find("nowhere: no such folder; expected a TUM sequence"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

}  // namespace
}  // namespace objmap::test
