// objmap report on a fuse run of a synthetic scene (the cached seed-3 run of tests/integration).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/eval/ate.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/trajectory.h"
#include "support/test_support.h"
#include "xml_check.h"

namespace objmap::test {
namespace {

struct Cached {
  fs::path scene, run;
  RunResult result;
};

const Cached& cached_run() {
  static Cached c = [] {
    Cached r;
    r.scene =
        cached_output("seed3-orbit60-scene",
                      {"synth", "--out", "{OUT}", "--seed", "3", "--orbit-speed", "60"}, &r.result);
    if (!fs::exists(r.scene)) return r;
    r.run = cached_output("seed3-orbit60-fuse",
                          {"fuse", "--dataset", r.scene.string(), "--trajectory",
                           (r.scene / "groundtruth.txt").string(), "--segmentation",
                           (r.scene / "segmentation").string(), "--out", "{OUT}"},
                          &r.result);
    return r;
  }();
  return c;
}

// Every PNG embedded in the page, decoded.
std::vector<cv::Mat> embedded_pngs(const std::string& html) {
  std::vector<cv::Mat> images;
  const std::string key = "src=\"data:image/png;base64,";
  for (std::size_t at = html.find(key); at != std::string::npos; at = html.find(key, at + 1)) {
    const std::size_t start = at + key.size();
    const std::string bytes = base64_decode(html.substr(start, html.find('"', start) - start));
    images.push_back(
        cv::imdecode(std::vector<uchar>(bytes.begin(), bytes.end()), cv::IMREAD_COLOR));
  }
  return images;
}

// DIR/run: the files `names` of the run linked (the big maps), its objects/ copied: the object
// PLYs that objects.json names must lie inside the run folder, and a link leads out of it.
fs::path copy_of_run(const fs::path& run, const std::vector<std::string>& names,
                     const fs::path& dir) {
  const fs::path copy = dir / "run";
  fs::create_directories(copy);
  for (const std::string& name : names) fs::create_symlink(fs::absolute(run / name), copy / name);
  fs::copy(run / "objects", copy / "objects", fs::copy_options::recursive);
  return copy;
}

// A copy of the run (big files linked) whose run.json names `trajectory` as the estimate, so that
// the dataset's groundtruth.txt is a different file: the ground truth of the report.
fs::path run_with_estimate(const fs::path& run, const fs::path& trajectory, const fs::path& dir) {
  const fs::path copy = copy_of_run(run, {"objects.json", "map_semantic.ply"}, dir);
  auto doc = nlohmann::json::parse(read_text(run / "run.json"));
  doc["inputs"]["trajectory"]["path"] = fs::absolute(trajectory).string();
  write_text(copy / "run.json", doc.dump(1));
  return copy;
}

TEST(ReportCli, PageHasOneThumbnailPerObjectAndEveryPictureDecodes) {
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  const fs::path out = dir / "rep";
  const RunResult r = run_objmap({"report", "--run", c.run.string(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto objects = io::read_objects_json(c.run / "objects.json");
  ASSERT_EQ(objects.size(), 12u);

  // The page: well-formed, one thumbnail figure per object, every picture embedded and decoding.
  const std::string html = read_text(out / "report.html");
  EXPECT_EQ(xml_problem(html), "");
  EXPECT_EQ(count_of(html, "data-object-id=\""), objects.size());
  for (const auto& o : objects)
    EXPECT_NE(html.find("data-object-id=\"" + std::to_string(o.id) + "\""), std::string::npos);
  const auto images = embedded_pngs(html);
  ASSERT_EQ(images.size(), objects.size() + 1);  // the top view and the thumbnails
  EXPECT_GT(images[0].cols, 300);
  for (std::size_t i = 1; i < images.size(); ++i) {
    ASSERT_FALSE(images[i].empty()) << i;
    EXPECT_EQ(images[i].size(), cv::Size(160, 160)) << i;
  }
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);  // nothing from the network

  // The files beside it.
  const cv::Mat top = cv::imread((out / "topview.png").string(), cv::IMREAD_COLOR);
  EXPECT_EQ(top.size(), images[0].size());
  std::size_t thumbnails = 0;
  for (const auto& entry : fs::directory_iterator(out / "thumbnails")) {
    const cv::Mat t = cv::imread(entry.path().string(), cv::IMREAD_COLOR);
    EXPECT_EQ(t.size(), cv::Size(160, 160)) << entry.path();
    ++thumbnails;
  }
  EXPECT_EQ(thumbnails, objects.size());
  const std::string md = read_text(out / "report.md");
  for (const auto& o : objects)
    EXPECT_NE(md.find("| " + std::to_string(o.id) + " | " + o.class_name + " |"), std::string::npos)
        << o.id;

  // Fused with groundtruth.txt itself: the trajectory alone, no error plot; the scene's
  // objects_gt.json gives Tables 3-5 (all 12 objects matched, as the integration test asserts).
  const std::string svg = read_text(out / "trajectory.svg");
  EXPECT_EQ(xml_problem(svg), "");
  EXPECT_EQ(count_of(svg, "<polyline"), 1u);
  EXPECT_FALSE(fs::exists(out / "ate.svg"));
  EXPECT_NE(r.out.find("note: the run was fused with the dataset's groundtruth.txt"),
            std::string::npos)
      << r.out;
  EXPECT_NE(html.find("Table 3: number of objects per class"), std::string::npos);
  EXPECT_NE(r.out.find("12/12 ground-truth objects matched"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(out.string() + "/report.html"), std::string::npos) << r.out;
}

TEST(ReportCli, SuspectedDuplicatesOfRunJsonAreShownAndMarkedInTheTopView) {
  // The seed-3 scene's two stacked books touch and are seen together (tests/integration): one
  // suspected pair, refused for shared keyframes.
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  const auto run = nlohmann::json::parse(read_text(c.run / "run.json"));
  ASSERT_GE(run["duplicates"]["pairs"].size(), 1u);
  const auto& pair = run["duplicates"]["pairs"][0];
  TempDir dir;
  const RunResult r =
      run_objmap({"report", "--run", c.run.string(), "--out", (dir / "rep").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string md = read_text(dir / "rep" / "report.md");
  const std::string ids =
      std::to_string(pair["a"].get<int>()) + " + " + std::to_string(pair["b"].get<int>());
  EXPECT_NE(md.find("## Suspected duplicates"), std::string::npos) << md;
  EXPECT_NE(md.find("| " + ids + " | " + pair["class"].get<std::string>() + " |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("seen together in "), std::string::npos) << md;
  EXPECT_NE(md.find("(dup N)"), std::string::npos);  // the top view's caption explains the mark
  EXPECT_NE(read_text(dir / "rep" / "report.html").find("<h2>Suspected duplicates</h2>"),
            std::string::npos);

  // A run.json without the section (an older objmap): no section; a broken one: exit 2.
  auto doc = run;
  doc.erase("duplicates");
  const fs::path copy = copy_of_run(c.run, {"objects.json", "map_semantic.ply"}, dir.path());
  write_text(copy / "run.json", doc.dump(1));
  const RunResult old =
      run_objmap({"report", "--run", copy.string(), "--out", (dir / "rep_old").string()});
  ASSERT_EQ(old.exit_code, 0) << old.err;
  EXPECT_EQ(read_text(dir / "rep_old" / "report.md").find("Suspected duplicates"),
            std::string::npos);
  doc["duplicates"] = {{"pairs", {{{"a", 1}}}}};
  write_text(copy / "run.json", doc.dump(1));
  const RunResult bad =
      run_objmap({"report", "--run", copy.string(), "--out", (dir / "rep_bad").string()});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("run.json"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("duplicates"), std::string::npos) << bad.err;
}

TEST(ReportCli, ARunWithoutTheDenseMapsShowsTheObjectsMap) {
  // A run fused with --dense-map false has no map_semantic.ply: the top view is map_objects.ply.
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  const fs::path copy =
      copy_of_run(c.run, {"objects.json", "map_objects.ply", "run.json"}, dir.path());
  const RunResult r =
      run_objmap({"report", "--run", copy.string(), "--out", (dir / "rep").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string md = read_text(dir / "rep" / "report.md");
  EXPECT_NE(md.find("map_objects.ply seen from above"), std::string::npos);
  EXPECT_EQ(md.find("map_semantic.ply seen from above"), std::string::npos);
  EXPECT_FALSE(cv::imread((dir / "rep" / "topview.png").string(), cv::IMREAD_COLOR).empty());

  // Without either map: exit 2 naming the semantic map, nothing written (docs/cli.md).
  fs::remove(copy / "map_objects.ply");
  const RunResult none =
      run_objmap({"report", "--run", copy.string(), "--out", (dir / "rep2").string()});
  EXPECT_EQ(none.exit_code, 2) << none.err;
  EXPECT_NE(
      none.err.find((copy / "map_semantic.ply").string() + ": missing, and so is map_objects.ply"),
      std::string::npos)
      << none.err;
  EXPECT_FALSE(fs::exists(dir / "rep2"));
}

TEST(ReportCli, TrajectoriesAgainstTheGroundTruthThenTheCorrectedOne) {
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  const fs::path run = run_with_estimate(c.run, c.scene / "estimated.txt", dir.path());
  RunResult r = run_objmap({"report", "--run", run.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string svg = read_text(run / "report" / "trajectory.svg");
  EXPECT_EQ(xml_problem(svg), "");
  EXPECT_EQ(count_of(svg, "<polyline"), 2u);  // ground truth + estimate
  std::string ate = read_text(run / "report" / "ate.svg");
  EXPECT_EQ(xml_problem(ate), "");
  EXPECT_EQ(count_of(ate, "<polyline"), 1u);
  // The ATE shown is the one of eval ate (same association and alignment).
  const auto expected = eval::evaluate_ate(io::read_trajectory(c.scene / "groundtruth.txt"),
                                           io::read_trajectory(c.scene / "estimated.txt"), {});
  char rmse[64];
  std::snprintf(rmse, sizeof rmse, "ATE RMSE estimated %.4f m (%zu pose pairs)",
                expected.stats.rmse, expected.stats.count);
  EXPECT_GT(expected.stats.rmse, 0.005);
  EXPECT_NE(r.out.find(rmse), std::string::npos) << r.out << "\nexpected: " << rmse;
  std::snprintf(rmse, sizeof rmse, "estimated (RMSE %.4f m)", expected.stats.rmse);
  EXPECT_NE(ate.find(rmse), std::string::npos) << rmse;  // the error plot's legend

  // A corrected trajectory beside the run: a third line, a second error curve.
  Trajectory corrected = io::read_trajectory(c.scene / "groundtruth.txt");
  for (std::size_t i = 0; i < corrected.poses.size(); ++i)
    corrected.poses[i].world_from_cam.translation().x() += i % 2 ? 0.004 : -0.004;
  io::write_trajectory(run / "trajectory_corrected.txt", corrected);
  r = run_objmap({"report", "--run", run.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  svg = read_text(run / "report" / "trajectory.svg");
  EXPECT_EQ(xml_problem(svg), "");
  EXPECT_EQ(count_of(svg, "<polyline"), 3u);
  ate = read_text(run / "report" / "ate.svg");
  EXPECT_EQ(xml_problem(ate), "");
  EXPECT_EQ(count_of(ate, "<polyline"), 2u);
  EXPECT_NE(r.out.find(", corrected 0.004"), std::string::npos) << r.out;
  EXPECT_EQ(xml_problem(read_text(run / "report" / "report.html")), "");

  // A run written by `objmap correct` was fused with its corrected trajectory; the estimate shown
  // is still the correction's input (correction.json), not the corrected file a second time.
  auto doc = nlohmann::json::parse(read_text(run / "run.json"));
  doc["inputs"]["trajectory"]["path"] = fs::absolute(run / "trajectory_corrected.txt").string();
  write_text(run / "run.json", doc.dump(1));
  write_text(run / "correction.json",
             nlohmann::json{{"input_trajectory", fs::absolute(c.scene / "estimated.txt").string()}}
                 .dump());
  r = run_objmap({"report", "--run", run.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::snprintf(rmse, sizeof rmse, "ATE RMSE estimated %.4f m, corrected 0.004",
                expected.stats.rmse);
  EXPECT_NE(r.out.find(rmse), std::string::npos) << r.out << "\nexpected: " << rmse;
}

// The values of `attribute` in `doc`, in order ("object 3" for data-node="object 3").
std::vector<std::string> attribute_values(const std::string& doc, const std::string& attribute) {
  std::vector<std::string> out;
  const std::string key = attribute + "=\"";
  for (std::size_t at = doc.find(key); at != std::string::npos; at = doc.find(key, at + 1)) {
    const std::size_t start = at + key.size();
    out.push_back(doc.substr(start, doc.find('"', start) - start));
  }
  return out;
}

TEST(ReportCli, SceneGraphHoldsTheObjectsSurfacesAndOnEdgesOfObjectsJson) {
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  const fs::path out = dir / "rep";
  const RunResult r = run_objmap({"report", "--run", c.run.string(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out / "scene_graph.svg"));
  const std::string svg = read_text(out / "scene_graph.svg");
  EXPECT_EQ(xml_problem(svg), "");

  // Expected from objects.json itself: a node per object and per surface, an edge per `on`.
  const auto doc = nlohmann::json::parse(read_text(c.run / "objects.json"));
  std::multiset<std::string> nodes, edges;
  for (const auto& s : doc.at("surfaces"))
    nodes.insert("surface " + std::to_string(s.at("id").get<int>()));
  for (const auto& o : doc.at("objects")) {
    nodes.insert("object " + std::to_string(o.at("id").get<int>()));
    const auto& on = o.at("relations").at("on");
    if (!on.is_null())
      edges.insert("on object " + std::to_string(o.at("id").get<int>()) + " " +
                   on.at("kind").get<std::string>() + " " + std::to_string(on.at("id").get<int>()));
  }
  ASSERT_FALSE(doc.at("surfaces").empty());
  ASSERT_FALSE(edges.empty());
  // The seed-3 scene's stacked books: at least one object stands on another.
  EXPECT_TRUE(std::any_of(edges.begin(), edges.end(), [](const std::string& e) {
    return e.find(" object ", 3) != std::string::npos;
  }));
  const auto svg_nodes = attribute_values(svg, "data-node");
  const auto svg_edges = attribute_values(svg, "data-edge");
  EXPECT_EQ(std::multiset<std::string>(svg_nodes.begin(), svg_nodes.end()), nodes);
  EXPECT_EQ(std::multiset<std::string>(svg_edges.begin(), svg_edges.end()), edges);
  // Heights above the floor, the svg within the page's width.
  EXPECT_NE(svg.find("m above the floor"), std::string::npos) << svg;
  const std::string md = read_text(out / "report.md");
  for (const auto& o : doc.at("objects"))  // the nested list names every object
    EXPECT_NE(md.find("  - " + std::to_string(o.at("id").get<int>()) + " " +
                      o.at("class").get<std::string>() + "\n"),
              std::string::npos)
        << md;

  // On the page (inline) and in report.md (the file), and named in the summary.
  const std::string html = read_text(out / "report.html");
  EXPECT_EQ(count_of(html, "data-edge=\""), edges.size());
  EXPECT_NE(read_text(out / "report.md").find("](scene_graph.svg)"), std::string::npos);
  EXPECT_NE(r.out.find("scene_graph.svg"), std::string::npos) << r.out;
}

TEST(ReportCli, ARunWithoutTheSceneHasNoSceneGraphAndSaysSo) {
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  const fs::path run = run_with_estimate(c.run, c.scene / "groundtruth.txt", dir.path());
  auto doc = nlohmann::json::parse(read_text(c.run / "objects.json"));
  doc.erase("up_in_world");
  doc.erase("surfaces");
  fs::remove(run / "objects.json");
  write_text(run / "objects.json", doc.dump(1));
  const RunResult r =
      run_objmap({"report", "--run", run.string(), "--out", (dir / "rep").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir / "rep" / "scene_graph.svg"));
  EXPECT_NE(r.out.find("note: no scene graph"), std::string::npos) << r.out;
  EXPECT_EQ(read_text(dir / "rep" / "report.html").find("data-edge="), std::string::npos);
}

TEST(ReportCli, RunWithoutObjectsJsonIsExit2NamingTheFile) {
  TempDir dir;
  fs::create_directories(dir / "run");
  write_text(dir / "run" / "run.json", "{}");
  const auto r = run_objmap({"report", "--run", (dir / "run").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "run" / "objects.json").string()), std::string::npos) << r.err;
  EXPECT_EQ(count_of(r.err, "\n"), 1u) << r.err;
  EXPECT_FALSE(fs::exists(dir / "run" / "report"));
}

// A copy of the run whose objects.json gives objects[3] the PLY path `ply`; `outside.ply` (a real
// object cloud) lies beside the run folder.
fs::path run_with_ply(const fs::path& run, const std::string& ply, const fs::path& dir) {
  const fs::path copy = copy_of_run(run, {"map_semantic.ply", "run.json"}, dir);
  auto doc = nlohmann::json::parse(read_text(run / "objects.json"));
  if (!fs::exists(dir / "outside.ply"))
    fs::copy_file(run / doc["objects"][3]["ply"].get<std::string>(), dir / "outside.ply");
  doc["objects"][3]["ply"] = ply;
  write_text(copy / "objects.json", doc.dump(1));
  return copy;
}

TEST(ReportCli, AnObjectFileOutsideTheRunIsExit2NamingTheFieldAndThePath) {
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  const fs::path outside = fs::absolute(dir / "outside.ply");
  const auto expect_refused = [&](const std::string& ply, const std::string& why) {
    const fs::path run = run_with_ply(c.run, ply, dir.path());
    const RunResult r =
        run_objmap({"report", "--run", run.string(), "--out", (dir / "rep").string()});
    EXPECT_EQ(r.exit_code, 2) << why << ": " << r.err;
    EXPECT_NE(r.err.find((run / "objects.json").string() + ": objects[3].ply: '" + ply +
                         "' resolves outside the run folder"),
              std::string::npos)
        << why << ": " << r.err;
    EXPECT_EQ(count_of(r.err, "\n"), 1u) << r.err;
    EXPECT_FALSE(fs::exists(dir / "rep")) << why;
    // Every other reader of a run's object files: the same refusal, before any work.
    const std::vector<std::vector<std::string>> readers = {
        {"eval", "objects", "--map", (run / "objects.json").string(), "--reference",
         (c.run / "objects.json").string()},
        {"eval", "masks", "--run", run.string()},
        {"correct", "--run", run.string(), "--out", (dir / "corrected").string()}};
    for (const auto& args : readers) {
      const RunResult e = run_objmap(args);
      EXPECT_EQ(e.exit_code, 2) << why << ", " << args[0] << " " << args[1] << ": " << e.err;
      EXPECT_NE(e.err.find("objects.json: objects[3].ply: '" + ply + "' resolves outside"),
                std::string::npos)
          << e.err;
    }
    EXPECT_FALSE(fs::exists(dir / "corrected"));
    fs::remove_all(run);
  };
  expect_refused("../outside.ply", "up and out");
  expect_refused("objects/../../outside.ply", "in and then out");
  expect_refused(outside.string(), "an absolute path");
  // A link inside the run that points out of it.
  {
    const fs::path run = run_with_ply(c.run, "objects/link.ply", dir.path());
    fs::create_symlink(outside, run / "objects" / "link.ply");
    const RunResult r =
        run_objmap({"report", "--run", run.string(), "--out", (dir / "rep").string()});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("objects[3].ply: 'objects/link.ply' resolves outside the run folder"),
              std::string::npos)
        << r.err;
    fs::remove_all(run);
  }
  // A path that goes up and comes back stays inside: read.
  const auto doc = nlohmann::json::parse(read_text(c.run / "objects.json"));
  const std::string back = "objects/../" + doc["objects"][3]["ply"].get<std::string>();
  const fs::path run = run_with_ply(c.run, back, dir.path());
  const RunResult r =
      run_objmap({"report", "--run", run.string(), "--out", (dir / "rep").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST(ReportCli, RunNamesAreTextOnThePageNeverMarkup) {
  // A run from someone else: class names and a duplicate's reason with markup in them.
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  const fs::path run = copy_of_run(c.run, {"map_semantic.ply"}, dir.path());
  auto objects = nlohmann::json::parse(read_text(c.run / "objects.json"));
  objects["objects"][0]["class"] = "<script>alert(1)</script>";
  objects["objects"][1]["class"] = "a\"b&c";
  // An object file named with markup (inside the run): its thumbnail's name is made plain.
  fs::copy_file(c.run / objects["objects"][2]["ply"].get<std::string>(),
                run / "objects" / "x<b>(y).ply");
  objects["objects"][2]["ply"] = "objects/x<b>(y).ply";
  write_text(run / "objects.json", objects.dump(1));
  auto doc = nlohmann::json::parse(read_text(c.run / "run.json"));
  ASSERT_GE(doc["duplicates"]["pairs"].size(), 1u);
  doc["duplicates"]["pairs"][0]["class"] = "<img src=x onerror=alert(1)>";
  doc["duplicates"]["pairs"][0]["merge_reason"] = "<script>alert(2)</script>";
  write_text(run / "run.json", doc.dump(1));
  const RunResult r =
      run_objmap({"report", "--run", run.string(), "--out", (dir / "rep").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* file : {"report.html", "scene_graph.svg"}) {
    const std::string text = read_text(dir / "rep" / file);
    EXPECT_EQ(xml_problem(text), "") << file;
    // The page's own scripts (the 3D view's data and viewer) are the only ones.
    EXPECT_EQ(count_of(text, "<script"), file == std::string("report.html") ? 2u : 0u) << file;
    EXPECT_EQ(text.find("alert(1)</"), std::string::npos) << file;
    EXPECT_EQ(text.find("<img src=x"), std::string::npos) << file;
    EXPECT_EQ(text.find("a\"b"), std::string::npos) << file;  // a quote would end an attribute
    EXPECT_NE(text.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos) << file;
    EXPECT_NE(text.find("a&quot;b&amp;c"), std::string::npos) << file;
  }
  const std::string html = read_text(dir / "rep" / "report.html");
  EXPECT_NE(html.find("&lt;script&gt;alert(2)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(html.find("&lt;img src=x onerror=alert(1)&gt;"), std::string::npos);
  // In the 3D view's JSON, '<' and '>' as \u escapes: the name reads back, the script goes on.
  EXPECT_NE(html.find("\"class\":\"\\u003cscript\\u003ealert(1)\\u003c/script\\u003e\""),
            std::string::npos);
  // report.md: Markdown passes raw HTML on, so the names are entities there too.
  const std::string md = read_text(dir / "rep" / "report.md");
  EXPECT_EQ(md.find("<script"), std::string::npos) << md;
  EXPECT_EQ(md.find("<img"), std::string::npos) << md;
  EXPECT_NE(md.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos) << md;
  EXPECT_NE(md.find("a\"b&amp;c"), std::string::npos) << md;
  EXPECT_EQ(md.find("<b>"), std::string::npos) << md;
  EXPECT_NE(md.find("](thumbnails/x_b__y_.png)"), std::string::npos) << md;
  EXPECT_TRUE(fs::exists(dir / "rep" / "thumbnails" / "x_b__y_.png"));
}

TEST(ReportCli, BadGroundTruthIsExit2NamingTheLine) {
  const Cached& c = cached_run();
  ASSERT_TRUE(fs::exists(c.run)) << c.result.err;
  TempDir dir;
  write_text(dir / "gt.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  const auto r = run_objmap({"report", "--run", c.run.string(), "--gt", (dir / "gt.txt").string(),
                             "--out", (dir / "rep").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "gt.txt").string() + ":2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "rep"));
}

TEST(ObjectsJson, MissingFieldIsNamed) {
  TempDir dir;
  write_text(dir / "objects.json", R"({"objects":[{"id":1,"class":"cup"}]})");
  try {
    io::read_objects_json(dir / "objects.json");
    FAIL() << "no throw";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("objects[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("score"), std::string::npos) << e.what();
  }
}

// One object of an objects.json with these id, half extent, point count and observation count.
std::string object_json(const std::string& id, const std::string& half = "[0.1,0.1,0.1]",
                        const std::string& points = "5", const std::string& seen = "3") {
  return R"({"id":)" + id +
         R"(,"class":"cup","score":0.9,"centroid":[0,0,0],"aabb":{"min":[0,0,0],"max":[1,1,1]},)"
         R"("obb":{"center":[0,0,0],"half_extent":)" +
         half + R"(,"rotation":[1,0,0,0,1,0,0,0,1]},"points":{"outlier_filtered":)" + points +
         R"(},"observation_count":)" + seen + R"(,"ply":"objects/x.ply"})";
}

// The message of read_objects_json on {"objects":[<objects>]} written in `dir`, or "no error".
std::string objects_json_error(const fs::path& dir, const std::string& objects) {
  write_text(dir / "objects.json", R"({"objects":[)" + objects + "]}");
  try {
    io::read_objects_json(dir / "objects.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ObjectsJson, DuplicateIdsAndNegativeExtentsAreNamed) {
  // eval objects took both (exit 0, garbage IoU).
  TempDir dir;
  EXPECT_EQ(objects_json_error(dir.path(), object_json("1")), "no error");
  EXPECT_NE(objects_json_error(dir.path(), object_json("1") + "," + object_json("1"))
                .find("objects[1].id: id 1 appears twice; expected unique ids"),
            std::string::npos);
  EXPECT_NE(objects_json_error(dir.path(), object_json("1", "[0.1,-0.1,0.1]"))
                .find("objects[0].obb.half_extent: negative half extent"),
            std::string::npos);
}

TEST(ObjectsJson, AFolderIsExit2NamingIt) {
  // `objmap eval objects --map RUN` (the run folder, not its objects.json) was exit 1, "internal
  // error: basic_filebuf::underflow error reading the file: Is a directory".
  TempDir dir;
  const auto r = run_objmap({"eval", "objects", "--map", dir.path().string(), "--gt-objects",
                             (dir / "gt.json").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(dir.path().string() + ": is a folder; expected RUN/objects.json"),
            std::string::npos)
      << r.err;
}

TEST(ObjectsJson, CountsAndIdsMustBeWholeNumbersInRange) {
  // "id": 1e300 was cast to int (undefined: UBSan float-cast-overflow in the fuzz build,
  // fuzz_objects_json); a negative or fractional count was taken as some size_t.
  TempDir dir;
  EXPECT_EQ(objects_json_error(dir.path(), object_json("7")), "no error");
  EXPECT_EQ(
      objects_json_error(dir.path(), object_json("1e300")),
      (dir / "objects.json").string() +
          ": objects[0].id: expected a whole number in [-2147483648, 2147483647], got 1e+300");
  EXPECT_NE(objects_json_error(dir.path(), object_json("7", "[1,1,1]", "-1"))
                .find("objects[0].points.outlier_filtered: expected a whole number in [0, "
                      "9007199254740992], got -1"),
            std::string::npos);
  EXPECT_NE(objects_json_error(dir.path(), object_json("7", "[1,1,1]", "5", "2.5"))
                .find("objects[0].observation_count: expected a whole number in [0, 2147483647], "
                      "got 2.5"),
            std::string::npos);
}

}  // namespace
}  // namespace objmap::test
