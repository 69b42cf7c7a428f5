// `objmap fuse --mesh`: the objects' and the scene's meshes on objmap synth's scene, whose true
// surfaces are known exactly (sim::distance_to_surface), and on ycbv_0000_10f against its YCB
// models (`objmap eval surface`).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include "fuse_helpers.h"
#include "objmap/io/ply.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/scene.h"

namespace objmap::test {
namespace {

// The noise-free tabletop scene (seed 1), 30 frames at half resolution, fused with every mesh.
fs::path noise_free_mesh_run() {
  RunResult why;
  const fs::path scene = cached_output(
      "mesh-noise-free-scene",
      {"synth", "--out", "{OUT}", "--noise-free", "--frames", "30", "--scale", "0.5"}, &why);
  EXPECT_TRUE(fs::exists(scene)) << why.err;
  const fs::path run = cached_output(
      "mesh-noise-free-run",
      {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
       "--segmentation", (scene / "segmentation_gt").string(), "--out", "{OUT}", "--mesh", "all"},
      &why);
  EXPECT_TRUE(fs::exists(run)) << why.err;
  return run;
}

// True when `p` lies within `margin` of an edge of the object's true surface: a box part's edge
// (two of its faces near), a cylinder's rim, or where two parts meet (near both).
bool near_edge(const sim::SceneObject& object, const Vec3& p, double margin) {
  int parts_near = 0;
  for (std::size_t i = 0; i < object.parts.size(); ++i) {
    const sim::Part& part = object.parts[i];
    const Vec3 q = object.world_from_part[i].inverse() * p;
    if (sim::distance_to_part_surface(part, q) > margin) continue;
    ++parts_near;
    const Vec3 h = part.half_extent;
    if (part.shape == sim::Shape::kBox) {
      int faces = 0;
      for (int a = 0; a < 3; ++a) faces += std::abs(std::abs(q[a]) - h[a]) < margin;
      if (faces >= 2) return true;
    } else if (part.shape == sim::Shape::kCylinder) {
      if (std::abs(q.head<2>().norm() - h.x()) < margin &&
          std::abs(std::abs(q.z()) - h.z()) < margin)
        return true;
    }
  }
  return parts_near >= 2;
}

TEST(FuseMesh, SyntheticObjectMeshesLieWithinHalfAVoxelOfTheTrueSurfaces) {
  const fs::path run = noise_free_mesh_run();
  ASSERT_TRUE(fs::exists(run / "objects.json"));
  const sim::Scene scene = sim::make_scene("tabletop", 1);
  const nlohmann::json doc = read_json(run / "objects.json");
  std::size_t checked = 0, within = 0, meshes = 0, total = 0;
  for (const auto& o : doc.at("objects")) {
    ASSERT_TRUE(o.contains("mesh")) << o.dump();
    if (o["mesh"]["file"].is_null()) continue;
    const TriangleMesh mesh = io::read_mesh_ply(run / o["mesh"]["file"].get<std::string>());
    EXPECT_EQ(mesh.triangles.size(), o["mesh"]["triangles"].get<std::size_t>());
    EXPECT_EQ(mesh.vertices.size(), o["mesh"]["vertices"].get<std::size_t>());
    EXPECT_TRUE(mesh.has_normals() && mesh.has_colors());
    const double voxel = o["mesh"]["voxel_m"].get<double>();
    // The true object: of the class, nearest the box centre.
    const Vec3 centre = 0.5 * (vec3(o["aabb"]["min"]) + vec3(o["aabb"]["max"]));
    const sim::SceneObject* truth = nullptr;
    for (const auto& g : scene.objects)
      if (g.class_name == o["class"].get<std::string>() &&
          (!truth || (g.centroid - centre).norm() < (truth->centroid - centre).norm()))
        truth = &g;
    ASSERT_NE(truth, nullptr) << o["class"];
    ++meshes;
    total += mesh.vertices.size();
    std::size_t object_checked = 0, object_within = 0;
    for (const Vec3f& v : mesh.vertices) {
      const Vec3 p = v.cast<double>();
      if (near_edge(*truth, p, voxel)) continue;
      ++object_checked;
      object_within += sim::distance_to_surface(*truth, p) <= 0.5 * voxel;
    }
    std::printf("%-12s voxel %.1f mm: %zu of %zu vertices away from edges within half a voxel\n",
                o["class"].get<std::string>().c_str(), 1000 * voxel, object_within, object_checked);
    checked += object_checked;
    within += object_within;
  }
  EXPECT_GE(meshes, 10u);
  std::printf("%zu of %zu vertices away from edges\n", checked, total);
  ASSERT_GT(checked, total / 2);
  EXPECT_GE(static_cast<double>(within) / checked, 0.95) << within << " of " << checked;
}

TEST(FuseMesh, MeshesAreNamedInObjectsJsonAndTheSceneMeshIsWritten) {
  const fs::path run = noise_free_mesh_run();
  ASSERT_TRUE(fs::exists(run / "objects.json"));
  const nlohmann::json doc = read_json(run / "objects.json");
  std::size_t files = 0;
  for (const auto& o : doc.at("objects"))
    if (o["mesh"]["file"].is_string()) {
      EXPECT_TRUE(fs::exists(run / o["mesh"]["file"].get<std::string>()));
      EXPECT_EQ(o["mesh"]["file"].get<std::string>(),
                fs::path(o["ply"].get<std::string>()).replace_extension().string() + "_mesh.ply");
      ++files;
    }
  EXPECT_GE(files, 10u);
  const TriangleMesh room = io::read_mesh_ply(run / "map_mesh.ply");
  const nlohmann::json counts = read_json(run / "run.json").at("counts");
  EXPECT_EQ(room.triangles.size(), counts.at("scene_mesh_triangles").get<std::size_t>());
  // The room: the floor and the table top at least (a few square metres).
  EXPECT_GT(room.area(), 2.0);
  EXPECT_EQ(read_json(run / "run.json").at("options").at("mesh").at("select"), "all");
}

TEST(FuseMesh, TheReportsThreeDViewDrawsEachObjectsMesh) {
  const fs::path run = noise_free_mesh_run();
  TempDir dir;
  const auto r = run_objmap({"report", "--run", run.string(), "--out", (dir / "r").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "r" / "report.html");
  const std::string html((std::istreambuf_iterator<char>(in)), {});
  const std::string open = "<script type=\"application/json\" id=\"view3d-data\">";
  const std::size_t at = html.find(open);
  ASSERT_NE(at, std::string::npos);
  const std::size_t begin = at + open.size();
  const nlohmann::json view =
      nlohmann::json::parse(html.substr(begin, html.find("</script>", begin) - begin));
  const nlohmann::json doc = read_json(run / "objects.json");
  ASSERT_EQ(view["objects"].size(), doc["objects"].size());
  std::size_t meshes = 0;
  for (std::size_t i = 0; i < doc["objects"].size(); ++i) {
    const nlohmann::json& mesh = doc["objects"][i]["mesh"];
    if (!mesh["file"].is_string()) continue;
    ASSERT_TRUE(view["objects"][i].contains("mesh")) << i;
    EXPECT_EQ(view["objects"][i]["mesh"]["triangles"].size(),
              3 * mesh["triangles"].get<std::size_t>())
        << i;
    ++meshes;
  }
  EXPECT_GE(meshes, 10u);
}

TEST(FuseMesh, MeshesAreTheSameForAnyThreadCount) {
  RunResult why;
  const fs::path scene = cached_output(
      "mesh-noise-free-scene",
      {"synth", "--out", "{OUT}", "--noise-free", "--frames", "30", "--scale", "0.5"}, &why);
  ASSERT_TRUE(fs::exists(scene)) << why.err;
  TempDir dir;
  for (const char* threads : {"1", "2"}) {
    const auto r = run_objmap({"fuse", "--dataset", scene.string(), "--trajectory",
                               (scene / "groundtruth.txt").string(), "--segmentation",
                               (scene / "segmentation").string(), "--out", (dir / threads).string(),
                               "--mesh", "all", "--threads", threads});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::size_t compared = 0;
  for (const auto& e : fs::directory_iterator(dir / "1" / "objects")) {
    const std::string name = e.path().filename().string();
    if (name.find("_mesh.ply") == std::string::npos) continue;
    EXPECT_EQ(read_text(e.path()), read_text(dir / "2" / "objects" / name)) << name;
    ++compared;
  }
  EXPECT_GE(compared, 8u);
  EXPECT_EQ(read_text(dir / "1" / "map_mesh.ply"), read_text(dir / "2" / "map_mesh.ply"));
}

TEST(FuseMesh, Open3dReadsTheMeshes) {
  const fs::path run = noise_free_mesh_run();
  ASSERT_TRUE(fs::exists(run / "objects.json"));
  if (std::system("/usr/bin/python3 -c 'import open3d' >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3-open3d is not installed (scripts/install-deps.sh --bench)";
  const fs::path mesh = run / "objects" / "0_tv_monitor_mesh.ply";
  ASSERT_TRUE(fs::exists(mesh));
  const TriangleMesh ours = io::read_mesh_ply(mesh);
  TempDir dir;
  const std::string script =
      "import open3d as o3d, sys\n"
      "m = o3d.io.read_triangle_mesh(sys.argv[1])\n"
      "print(len(m.vertices), len(m.triangles), int(m.has_vertex_normals()), "
      "int(m.has_vertex_colors()))\n";
  write_text(dir / "read.py", script);
  const std::string command = "/usr/bin/python3 " + (dir / "read.py").string() + " " +
                              mesh.string() + " > " + (dir / "out.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text(dir / "out.txt");
  EXPECT_EQ(read_text(dir / "out.txt"), std::to_string(ours.vertices.size()) + " " +
                                            std::to_string(ours.triangles.size()) + " 1 1\n");
}

TEST(FuseMesh, NoMeshesByDefault) {
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f");
  TempDir dir;
  const auto r = run_objmap({"fuse", "--dataset", data.string(), "--trajectory",
                             (data / "groundtruth.txt").string(), "--segmentation",
                             (data / "masks").string(), "--out", (dir / "run").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(read_json(dir / "run" / "objects.json")["objects"][0].contains("mesh"));
  EXPECT_FALSE(fs::exists(dir / "run" / "map_mesh.ply"));
  EXPECT_EQ(read_json(dir / "run" / "run.json")["options"]["mesh"]["select"], "none");
}

TEST(FuseMesh, BadMeshSelectionIsExitTwoNamingTheOption) {
  TempDir dir;
  const auto r = run_objmap({"fuse", "--dataset", (dir / "none").string(), "--segmentation",
                             (dir / "none").string(), "--out", (dir / "run").string(), "--mesh",
                             "everything"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("mesh"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("everything"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "run"));
}

TEST(FuseMesh, YcbMeshesAreCloserAndMoreCompleteThanTheClouds) {
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f");
  TempDir dir;
  auto r =
      run_objmap({"fuse", "--dataset", data.string(), "--trajectory",
                  (data / "groundtruth.txt").string(), "--segmentation", (data / "masks").string(),
                  "--out", (dir / "run").string(), "--mesh", "objects"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_objmap({"eval", "surface", "--run", (dir / "run").string(), "--models",
                  (data / "models").string(), "--poses", (data / "objects_pose.txt").string(),
                  "--json", (dir / "surface.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = read_json(dir / "surface.json");
  ASSERT_EQ(doc.at("objects").size(), 3u);
  for (const auto& o : doc["objects"]) {
    ASSERT_TRUE(o.at("mesh").is_object()) << o.dump();
    const auto& mesh = o["mesh"];
    const auto& cloud = o["cloud"];
    EXPECT_LT(mesh["accuracy_mean_mm"].get<double>(), 1.5) << o["model"];
    EXPECT_LE(mesh["accuracy_mean_mm"].get<double>(), cloud["accuracy_mean_mm"].get<double>())
        << o["model"];
    EXPECT_GE(mesh["completeness"].get<double>(), 0.95) << o["model"];
    EXPECT_GE(mesh["fscore"].get<double>(), cloud["fscore"].get<double>()) << o["model"];
  }
}

}  // namespace
}  // namespace objmap::test
