// objmap synth -> objmap fuse on synthetic scenes whose objects are known exactly.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <thread>

#include "fuse_helpers.h"
#include "objmap/fusion/palette.h"
#include "objmap/geometry/voxel_key.h"
#include "objmap/io/ply.h"
#include "support/schema_check.h"

namespace objmap::test {
namespace {

// One scene and one fuse run per configuration, made once and shared by the test processes.
struct SceneRun {
  fs::path scene, out;
  RunResult synth, fuse;
};

// `objmap fuse` of a synthetic scene with its ground-truth trajectory: `segmentation` (default: the
// scene's own) into `out`, then `extra`.
std::vector<std::string> fuse_args(const fs::path& scene, const std::string& out,
                                   const std::vector<std::string>& extra = {},
                                   const fs::path& segmentation = {}) {
  std::vector<std::string> args{
      "fuse",
      "--dataset",
      scene.string(),
      "--trajectory",
      (scene / "groundtruth.txt").string(),
      "--segmentation",
      (segmentation.empty() ? scene / "segmentation" : segmentation).string(),
      "--out",
      out};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

SceneRun make_run(const std::string& key, const std::vector<std::string>& synth_args,
                  const std::vector<std::string>& extra_fuse_args) {
  SceneRun r;
  std::vector<std::string> s{"synth", "--out", "{OUT}"};
  s.insert(s.end(), synth_args.begin(), synth_args.end());
  r.scene = cached_output(key + "-scene", s, &r.synth);
  if (!fs::exists(r.scene)) return r;
  r.synth.exit_code = 0;
  r.out = cached_output(key + "-fuse", fuse_args(r.scene, "{OUT}", extra_fuse_args), &r.fuse);
  if (fs::exists(r.out)) r.fuse.exit_code = 0;
  return r;
}

const SceneRun& default_run() {
  // 60°/s: the 3 s orbit sees 180° of every object (the default 20°/s sees 60°, so backs and
  // bottoms are never observed and no surface estimate can reach a volume centroid).
  static SceneRun run = make_run("seed3-orbit60", {"--seed", "3", "--orbit-speed", "60"}, {});
  return run;
}

// The position criterion: within max(2 cm, 10% of the object's largest dimension) of the
// ground truth. The reference is the ground-truth object's box centre (objects_gt.json obb.center),
// what the real data's references are (fr3_cabinet's cuboid, the YCB-Video model origins) and
// what a surface sensor can observe; the volume centroid (objects_gt.json centroid) is not: a
// chair's lies 12.6 cm from its box centre, inside the seat (docs/benchmarks.md).
double position_tolerance(const GtObject& g) { return std::max(0.02, 0.1 * g.largest_dimension()); }

TEST(FuseSynthetic, DefaultSceneEveryObjectFoundOnceAtItsBoxCentre) {
  // `objmap synth` with its defaults (seed 1, orbit 20°/s: each object seen over 60°), default mask
  // noise, ground-truth poses: the criterion as it stands.
  const SceneRun r = make_run("default", {}, {});
  ASSERT_EQ(r.synth.exit_code, 0) << r.synth.err;
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const auto gt = read_gt_objects(r.scene / "objects_gt.json");
  const auto fused = read_fused_objects(r.out / "objects.json");
  EXPECT_EQ(fused.size(), gt.size()) << r.fuse.out;  // count error 0
  const auto matches = match_objects(gt, fused, 0.3, /*same_class=*/true);
  EXPECT_EQ(matches.size(), gt.size()) << r.fuse.out;
  for (const auto& [i, j] : matches) {
    const double error = (gt[i].center - fused[j].position).norm();
    EXPECT_LE(error, position_tolerance(gt[i]))
        << gt[i].cls << " " << gt[i].id << " (fused " << fused[j].id << ")";
  }
}

TEST(FuseSynthetic, EveryObjectFoundOnceNearItsBoxCentre) {
  const SceneRun& r = default_run();
  ASSERT_EQ(r.synth.exit_code, 0) << r.synth.err;
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const auto gt = read_gt_objects(r.scene / "objects_gt.json");
  const auto fused = read_fused_objects(r.out / "objects.json");
  EXPECT_EQ(fused.size(), gt.size()) << r.fuse.out;
  const auto matches = match_objects(gt, fused, 0.3, /*same_class=*/true);
  EXPECT_EQ(matches.size(), gt.size()) << r.fuse.out;
  // 60°/s: 180° of every object seen. Measured over seeds 1, 2, 3, 5, 7 (docs/benchmarks.md): 59
  // of 60 objects within the tolerance; the other is this scene's cup, 2.3 cm for 2.0. So: all
  // within 1.2x, at most one of 12 beyond 1x.
  int beyond = 0;
  for (const auto& [i, j] : matches) {
    const double error = (gt[i].center - fused[j].position).norm();
    EXPECT_LE(error, 1.2 * position_tolerance(gt[i]))
        << gt[i].cls << " " << gt[i].id << " (fused " << fused[j].id << ")";
    beyond += error > position_tolerance(gt[i]);
  }
  EXPECT_LE(beyond, 1);
}

// Every ground-truth object matched once (same class, within 0.3 m) and its position error.
std::vector<std::pair<const GtObject*, double>> position_errors(const SceneRun& r,
                                                                const fs::path& run) {
  static std::map<fs::path, std::vector<GtObject>> gts;
  auto& gt = gts[r.scene];
  if (gt.empty()) gt = read_gt_objects(r.scene / "objects_gt.json");
  const auto fused = read_fused_objects(run / "objects.json");
  std::vector<std::pair<const GtObject*, double>> errors;
  for (const auto& [i, j] : match_objects(gt, fused, 0.3, /*same_class=*/true))
    errors.push_back({&gt[i], (gt[i].center - fused[j].position).norm()});
  return errors;
}

TEST(FuseSynthetic, MaskBleedOntoTheTableBehindDoesNotMoveObjectsAtTheEdge) {
  // The edge preset's objects stand 1-2.5 cm from the table's edges and the masks bleed
  // 3 px onto whatever lies behind (table top, floor, walls) on top of the usual mask noise.
  // Without the depth gate the near cup and the mouse are dragged across the table top behind
  // them (6.8-15 cm over seeds 1-3, docs/fusion.md); with it, every object is within tolerance.
  const SceneRun r = make_run("edge-bleed3", {"--preset", "edge", "--mask-bleed-px", "3"}, {});
  ASSERT_EQ(r.synth.exit_code, 0) << r.synth.err;
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const auto errors = position_errors(r, r.out);
  EXPECT_EQ(errors.size(), read_gt_objects(r.scene / "objects_gt.json").size()) << r.fuse.out;
  EXPECT_EQ(read_fused_objects(r.out / "objects.json").size(), errors.size()) << r.fuse.out;
  for (const auto& [gt, error] : errors)
    EXPECT_LE(error, position_tolerance(*gt)) << gt->cls << " " << gt->id;

  // Without the gate the strip of the table behind makes the cup and the mouse wider than their
  // classes allow, and the oversize cut trims it: within tolerance too. Without both, some object
  // is beyond twice its tolerance.
  const auto worst_of = [&](const std::string& key, const std::vector<std::string>& extra) {
    const fs::path run = cached_output(key, fuse_args(r.scene, "{OUT}", extra));
    double worst = 0.0;
    for (const auto& [gt, error] : position_errors(r, run))
      worst = std::max(worst, error / position_tolerance(*gt));
    return worst;
  };
  EXPECT_LE(worst_of("edge-bleed3-nogate", {"--depth-gate", "false"}), 1.0);
  EXPECT_GT(
      worst_of("edge-bleed3-nogate-nocut", {"--depth-gate", "false", "--split-oversize", "false"}),
      2.0)
      << "without the gate and the cut some object should be beyond twice its tolerance";
}

TEST(FuseSynthetic, TheTableAMaskBledOntoIsLeftOutOfThePositionOfAnObjectSeenFromOneSide) {
  // 30 frames at 20°/s: each object is seen over 20° only, and its masks bleed 4 px onto what lies
  // behind it, the table top. Seen from one side, nothing of the object balances that strip: the
  // 1-99 % box follows it 3-5 cm back (docs/fusion.md, "Records"). The strip is left out.
  const SceneRun r = make_run("oneside-bleed4", {"--frames", "30", "--mask-bleed-px", "4"}, {});
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const fs::path plain =
      cached_output("oneside-bleed4-nostrip",
                    fuse_args(r.scene, "{OUT}", {"--position-without-support", "false"}));
  ASSERT_TRUE(fs::exists(plain));
  const auto small_objects_mean = [&](const fs::path& run) {
    double sum = 0.0;
    int n = 0;
    for (const auto& [gt, error] : position_errors(r, run)) {
      if (gt->cls != "cup" && gt->cls != "bottle" && gt->cls != "book") continue;
      EXPECT_LE(error, 0.05) << gt->cls << " " << gt->id << " in " << run.filename();
      sum += error;
      ++n;
    }
    EXPECT_GE(n, 5) << run;
    return n ? sum / n : 0.0;
  };
  EXPECT_LT(small_objects_mean(r.out), 0.02);
  EXPECT_GT(small_objects_mean(plain), 0.03)
      << "the strip should move the positions (the case bites)";
  int with_strip = 0;
  const auto doc = read_json(r.out / "objects.json");
  for (const auto& o : doc["objects"]) with_strip += o["points"]["support_strip"].get<int>() > 0;
  EXPECT_GE(with_strip, 5);
}

TEST(FuseSynthetic, EveryFrameGivesTheSameObjectsAsTheKeyframes) {
  // More frames of the same scene must not make more objects. Seeds 1-3 with their
  // defaults (motion keeps 30 of the 90 frames) fused again with --keyframes all.
  for (const char* seed : {"1", "2", "3"}) {
    const SceneRun r = make_run(std::string("seed") + seed + "-motion", {"--seed", seed}, {});
    ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
    const fs::path all = cached_output(std::string("seed") + seed + "-all",
                                       fuse_args(r.scene, "{OUT}", {"--keyframes", "all"}));
    ASSERT_TRUE(fs::exists(all)) << "seed " << seed;
    const auto keyframes = read_json(r.out / "run.json"), every = read_json(all / "run.json");
    EXPECT_GT(every["counts"]["keyframes"].get<int>(),
              2 * keyframes["counts"]["keyframes"].get<int>());
    const double n_keyframes = keyframes["counts"]["objects_confirmed"].get<double>();
    const double n_all = every["counts"]["objects_confirmed"].get<double>();
    EXPECT_LE(std::abs(n_all - n_keyframes), 0.1 * n_keyframes) << "seed " << seed;
    EXPECT_LE(every["duplicates"]["count"].get<int>(), keyframes["duplicates"]["count"].get<int>())
        << "seed " << seed;
  }
}

TEST(FuseSynthetic, OutputsValidateAndReadBack) {
  const SceneRun& r = default_run();
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const auto doc = read_json(r.out / "objects.json");
  const auto errors = validate_json(doc, load_schema("objects.schema.json"));
  EXPECT_TRUE(errors.empty()) << errors.front();
  for (const auto& o : read_fused_objects(r.out / "objects.json")) {
    const PointCloud cloud = io::read_ply(r.out / o.ply);
    EXPECT_EQ(static_cast<long>(cloud.size()), o.points) << o.ply;
    EXPECT_TRUE(cloud.has_colors());
  }
  const PointCloud dense = io::read_ply(r.out / "map_dense.ply");
  const PointCloud semantic = io::read_ply(r.out / "map_semantic.ply");
  const PointCloud objects = io::read_ply(r.out / "map_objects.ply");
  EXPECT_GT(dense.size(), 10000u);
  EXPECT_EQ(semantic.size(), dense.size());
  EXPECT_GT(objects.size(), 0u);
  EXPECT_LT(objects.size(), dense.size());
  const auto run = read_json(r.out / "run.json");
  EXPECT_TRUE(validate_json(run, load_schema("run.schema.json")).empty());
  EXPECT_EQ(run["points"]["dense_map"].get<std::size_t>(), dense.size());
}

TEST(FuseSynthetic, RunJsonListsSuspectedDuplicatesWithTheMergeVerdict) {
  // Every pair of run.json "duplicates" is two objects of objects.json of one class that overlap
  // or touch, kept apart by a named rule. This scene's objects are all distinct (each found once,
  // above); its two stacked books touch and are seen together: reported, refused for shared
  // keyframes (two objects), not for a score the next change could tip.
  const SceneRun& r = default_run();
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const auto run = read_json(r.out / "run.json");
  ASSERT_TRUE(run.contains("duplicates"));
  const auto& d = run["duplicates"];
  const double touch_m = d["touch_distance_m"].get<double>();
  std::map<int, std::string> class_of;
  for (const auto& o : read_fused_objects(r.out / "objects.json")) class_of[o.id] = o.cls;
  ASSERT_EQ(d["count"].get<std::size_t>(), d["pairs"].size());
  EXPECT_GE(d["pairs_checked"].get<std::size_t>(), d["pairs"].size());
  ASSERT_GE(d["pairs"].size(), 1u) << r.fuse.out;
  int books = 0;
  for (const auto& p : d["pairs"]) {
    const int a = p["a"].get<int>(), b = p["b"].get<int>();
    EXPECT_LT(a, b);
    ASSERT_TRUE(class_of.count(a) && class_of.count(b)) << a << " " << b;
    EXPECT_EQ(class_of[a], class_of[b]);
    EXPECT_EQ(p["class"].get<std::string>(), class_of[a]);
    EXPECT_TRUE(p["obb_overlap"].get<double>() > 0.0 ||
                p["surface_distance_m"].get<double>() <= touch_m);
    EXPECT_EQ(p["merge_refused"].get<std::string>(), "shared_frames") << p.dump();
    EXPECT_GT(p["merge"]["shared_frames"].get<double>(),
              0.3 * p["merge"]["smaller_frames"].get<double>());
    books += p["class"].get<std::string>() == "book";
  }
  EXPECT_EQ(books, 1);
  // The console line (the run's stdout is there when this process made the cached run).
  if (!r.fuse.out.empty()) {
    EXPECT_NE(r.fuse.out.find("suspected duplicates: " + std::to_string(d["pairs"].size())),
              std::string::npos)
        << r.fuse.out;
  }
}

TEST(FuseSynthetic, SemanticMapIsTheDenseMapWithTheObjectsInClassColours) {
  // map_semantic.ply: the dense points in the same order; a voxel holding a point of an object
  // takes its class colour (the object with more observations, then the lower id, when several);
  // every other voxel keeps its mean colour.
  const SceneRun& r = default_run();
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const PointCloud dense = io::read_ply(r.out / "map_dense.ply");
  const PointCloud semantic = io::read_ply(r.out / "map_semantic.ply");
  ASSERT_EQ(semantic.points, dense.points);
  ASSERT_TRUE(dense.has_colors() && semantic.has_colors());
  // The dense points are their voxels' means, sorted by voxel key (1 cm, the default).
  const float inv_voxel = static_cast<float>(1.0 / 0.01);
  std::map<geometry::VoxelKey, std::size_t> index;
  geometry::VoxelKey last = 0;
  for (std::size_t i = 0; i < dense.size(); ++i) {
    const geometry::VoxelKey key = geometry::voxel_key(dense.points[i], inv_voxel);
    ASSERT_TRUE(i == 0 || key > last) << "dense point " << i << " not in its own voxel";
    last = key;
    index.emplace_hint(index.end(), key, i);
  }
  std::vector<Rgb> expected = dense.colors;
  std::vector<std::pair<long, int>> owner(dense.size(), {-1, 0});  // (observations, -id) of owner
  const auto doc = read_json(r.out / "objects.json");
  std::size_t claimed = 0;
  for (const auto& o : doc.at("objects")) {
    const long observations = o["observation_count"].get<long>();
    const int id = o["id"].get<int>();
    const Rgb colour = fusion::class_color(o["class"].get<std::string>());
    for (const Vec3f& p : io::read_ply(r.out / o["ply"].get<std::string>()).points) {
      const auto it = index.find(geometry::voxel_key(p, inv_voxel));
      if (it == index.end()) continue;
      const std::pair<long, int> rank{observations, -id};
      if (owner[it->second].first >= 0 && rank <= owner[it->second]) continue;
      claimed += owner[it->second].first < 0;
      owner[it->second] = rank;
      expected[it->second] = colour;
    }
  }
  EXPECT_GT(claimed, 1000u);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < dense.size(); ++i) differ += !(semantic.colors[i] == expected[i]);
  EXPECT_EQ(differ, 0u) << "of " << dense.size() << " voxels, " << claimed << " of objects";
}

TEST(FuseSynthetic, IdenticalOutputsForAnyThreadCount) {
  // The default run uses the cores, at most 8 (--threads 0); 1 and 3 threads give the same files.
  const SceneRun& r = default_run();
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const auto run = read_json(r.out / "run.json");
  EXPECT_EQ(run["options"]["threads"].get<int>(), 0);
  const unsigned cores = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  EXPECT_EQ(run["performance"]["threads"].get<unsigned>(), cores);
  for (const char* threads : {"1", "3"}) {
    TempDir other;
    const auto f =
        run_objmap(fuse_args(r.scene, (other.path() / "run").string(), {"--threads", threads}));
    ASSERT_EQ(f.exit_code, 0) << f.err;
    for (const auto& e : fs::recursive_directory_iterator(r.out)) {
      if (!e.is_regular_file()) continue;
      const auto rel = fs::relative(e.path(), r.out);
      if (rel == "run.json") {
        auto a = read_json(e.path()), b = read_json(other.path() / "run" / rel);
        a.erase("performance");
        b.erase("performance");
        a["options"].erase("threads");
        b["options"].erase("threads");
        EXPECT_EQ(a, b) << "--threads " << threads;
      } else {
        EXPECT_EQ(read_text(e.path()), read_text(other.path() / "run" / rel))
            << rel << " with --threads " << threads;
      }
    }
  }
}

TEST(FuseSynthetic, DensePruningDropsNoiseVoxelsTheSameForAnyThreadCount) {
  // --dense-prune-every 4: the dense map loses voxels (run.json counts them), is identical for 1
  // and 3 threads (the prunes fall between the same keyframes), and the objects keep their points.
  const SceneRun& r = default_run();
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  TempDir dir;
  std::string dense;
  for (const char* threads : {"1", "3"}) {
    const fs::path out = dir.path() / threads;
    const auto f = run_objmap(
        fuse_args(r.scene, out.string(), {"--dense-prune-every", "4", "--threads", threads}));
    ASSERT_EQ(f.exit_code, 0) << f.err;
    const auto run = read_json(out / "run.json");
    EXPECT_TRUE(validate_json(run, load_schema("run.schema.json")).empty());
    const auto before = read_json(r.out / "run.json");
    const std::size_t pruned = run["points"]["dense_pruned"].get<std::size_t>();
    EXPECT_GT(pruned, 0u);
    EXPECT_LT(run["points"]["dense_map"].get<std::size_t>(),
              before["points"]["dense_map"].get<std::size_t>());
    EXPECT_EQ(run["points"]["dense_back_projected"], before["points"]["dense_back_projected"]);
    EXPECT_EQ(run["points"]["objects_raw"], before["points"]["objects_raw"]);
    EXPECT_EQ(run["options"]["map"]["prune_every"].get<int>(), 4);
    const auto a = read_json(r.out / "objects.json"), b = read_json(out / "objects.json");
    ASSERT_EQ(a["objects"].size(), b["objects"].size());
    for (std::size_t i = 0; i < a["objects"].size(); ++i)
      for (const char* key : {"id", "class", "centroid", "points", "observations"})
        EXPECT_EQ(a["objects"][i][key], b["objects"][i][key]) << key;
    const std::string ply = read_text(out / "map_dense.ply");
    if (dense.empty())
      dense = ply;
    else
      EXPECT_TRUE(ply == dense) << "map_dense.ply differs between 1 and 3 threads";
  }
}

TEST(FuseSynthetic, WithoutTheDenseMapTheObjectsAreTheSame) {
  // --dense-map false: no map_dense.ply / map_semantic.ply, every object cloud byte-identical; in
  // objects.json the same objects with the same points (the up direction, so the boxes, come from
  // the cameras alone without a dense map, and there are no surfaces).
  const SceneRun& r = default_run();
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  TempDir other;
  const fs::path out = other.path() / "run";
  const auto f = run_objmap(fuse_args(r.scene, out.string(), {"--dense-map", "false"}));
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_NE(f.out.find("dense: none (--dense-map false)"), std::string::npos) << f.out;
  EXPECT_FALSE(fs::exists(out / "map_dense.ply"));
  EXPECT_FALSE(fs::exists(out / "map_semantic.ply"));
  std::size_t compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(r.out)) {
    if (!e.is_regular_file()) continue;
    const auto rel = fs::relative(e.path(), r.out);
    if (rel == "run.json" || rel == "map_dense.ply" || rel == "map_semantic.ply") continue;
    if (rel == "objects.json") {
      const auto a = read_json(e.path()), b = read_json(out / rel);
      ASSERT_EQ(a["objects"].size(), b["objects"].size());
      for (std::size_t i = 0; i < a["objects"].size(); ++i)
        for (const char* key : {"id", "class", "centroid", "aabb", "points", "observations"})
          EXPECT_EQ(a["objects"][i][key], b["objects"][i][key]) << key;
      EXPECT_TRUE(b["surfaces"].empty());
    } else {
      EXPECT_EQ(read_text(e.path()), read_text(out / rel)) << rel;
    }
    ++compared;
  }
  EXPECT_GE(compared, 14u);  // objects.json, map_objects.ply, one PLY per object
  const auto run = read_json(out / "run.json");
  EXPECT_TRUE(validate_json(run, load_schema("run.schema.json")).empty());
  EXPECT_EQ(run["points"]["dense_map"].get<std::size_t>(), 0u);
  EXPECT_EQ(run["points"]["dense_back_projected"].get<std::size_t>(), 0u);
  EXPECT_FALSE(run["options"]["map"]["dense"].get<bool>());
  // Table 6 of eval objects says there is no dense map (not a 100% reduction).
  const auto e = run_objmap({"eval", "objects", "--map", (out / "objects.json").string(),
                             "--gt-objects", (r.scene / "objects_gt.json").string()});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(e.out.find("  dense map                                              none"),
            std::string::npos)
      << e.out;
  EXPECT_NE(e.out.find("  reduction, objects-only vs dense map (Table 6)          n/a"),
            std::string::npos)
      << e.out;
}

// Every instance of the default scene listed twice, the copy with a lower score and another track
// id (a detector that boxes each object twice): the copies are dropped as duplicates and the
// objects are those of the original run, byte for byte. Without the rule (--duplicate-overlap 1)
// the copies keep objects of their own.
TEST(FuseSynthetic, InstancesListedTwiceAreOneObject) {
  const SceneRun r = make_run("default", {}, {});
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  TempDir tmp;
  const fs::path seg = tmp.path() / "segmentation";
  fs::create_directories(seg);
  std::size_t copies = 0;
  for (const auto& e : fs::directory_iterator(r.scene / "segmentation")) {
    nlohmann::json doc = read_json(e.path());
    nlohmann::json twice = nlohmann::json::array();
    for (const auto& instance : doc["instances"]) {
      twice.push_back(instance);
      nlohmann::json copy = instance;
      copy["score"] = instance["score"].get<double>() * 0.9;
      if (instance.contains("track_id") && instance["track_id"].is_number_integer())
        copy["track_id"] = instance["track_id"].get<int>() + 1000;
      twice.push_back(copy);
      ++copies;
    }
    doc["instances"] = twice;
    std::ofstream(seg / e.path().filename()) << doc.dump();
  }
  ASSERT_GT(copies, 100u);
  const auto fuse = [&](const fs::path& out, const std::vector<std::string>& extra) {
    return run_objmap(fuse_args(r.scene, out.string(), extra, seg));
  };
  const fs::path out = tmp.path() / "run";
  const auto f = fuse(out, {});
  ASSERT_EQ(f.exit_code, 0) << f.err;
  const auto run = read_json(out / "run.json");
  const auto before = read_json(r.out / "run.json");
  // Every copy is dropped (the copies of instances that give no observation too).
  EXPECT_EQ(run["counts"]["instances_duplicate"].get<std::size_t>(),
            before["counts"]["instances"].get<std::size_t>());
  EXPECT_EQ(read_text(out / "objects.json"), read_text(r.out / "objects.json"));
  for (const auto& e : fs::directory_iterator(r.out / "objects"))
    EXPECT_EQ(read_text(e.path()), read_text(out / "objects" / e.path().filename()))
        << e.path().filename();

  const fs::path all = tmp.path() / "all";
  const auto g = fuse(all, {"--duplicate-overlap", "1"});
  ASSERT_EQ(g.exit_code, 0) << g.err;
  EXPECT_EQ(read_json(all / "run.json")["counts"]["instances_duplicate"].get<std::size_t>(), 0u);
  EXPECT_GT(read_fused_objects(all / "objects.json").size(),
            read_fused_objects(r.out / "objects.json").size());
}

TEST(FuseSynthetic, ClassConfusionAndIdSwitchesStillGiveRightClasses) {
  const SceneRun r = make_run(
      "seed5-confusion", {"--seed", "5", "--confusion-rate", "0.2", "--id-switch-rate", "0.2"}, {});
  ASSERT_EQ(r.synth.exit_code, 0) << r.synth.err;
  ASSERT_EQ(r.fuse.exit_code, 0) << r.fuse.err;
  const auto gt = read_gt_objects(r.scene / "objects_gt.json");
  const auto fused = read_fused_objects(r.out / "objects.json");
  const double count_error =
      std::abs(static_cast<double>(fused.size()) - gt.size()) / static_cast<double>(gt.size());
  EXPECT_LE(count_error, 0.10) << fused.size() << " objects for " << gt.size() << "\n"
                               << r.fuse.out;
  const auto matches = match_objects(gt, fused, 0.3, /*same_class=*/false);
  EXPECT_EQ(matches.size(), gt.size());
  for (const auto& [i, j] : matches) EXPECT_EQ(fused[j].cls, gt[i].cls) << "object " << gt[i].id;
}

}  // namespace
}  // namespace objmap::test
