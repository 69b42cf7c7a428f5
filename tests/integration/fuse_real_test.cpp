// objmap fuse on real TUM RGB-D data.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fuse_helpers.h"
#include "objmap/io/ply.h"

namespace objmap::test {
namespace {

// fr3_cabinet_58kf/objects_gt.txt: "x y z yaw half_x half_y half_z" (CubeSLAM: yaw about world z).
GtObject read_cabinet(const fs::path& file) {
  std::istringstream in(read_text(file));
  std::string line;
  GtObject g;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream row(line);
    double x, y, z, yaw, hx, hy, hz;
    row >> x >> y >> z >> yaw >> hx >> hy >> hz;
    g.cls = "object";
    g.center = g.centroid = {x, y, z};
    g.rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    g.half_extent = {hx, hy, hz};
  }
  return g;
}

// `objmap fuse` of a real sequence with its groundtruth.txt and the segmentation folder `seg`.
RunResult fuse_real(const fs::path& data, const std::string& seg, const fs::path& out,
                    const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{"fuse",
                                "--dataset",
                                data.string(),
                                "--trajectory",
                                (data / "groundtruth.txt").string(),
                                "--segmentation",
                                (data / seg).string(),
                                "--out",
                                out.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_objmap(args);
}

TEST(FuseReal, Fr3CabinetGivesOneObjectInsideTheGroundTruthCuboid) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr3_cabinet_58kf");
  TempDir dir;
  const auto r = fuse_real(data, "boxes_yolov2", dir / "run");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto fused = read_fused_objects(dir / "run" / "objects.json");
  ASSERT_EQ(fused.size(), 1u) << r.out;
  const GtObject cabinet = read_cabinet(data / "objects_gt.txt");
  EXPECT_TRUE(cabinet.contains(fused[0].centroid))
      << "centroid " << fused[0].centroid.transpose() << " vs cuboid centre "
      << cabinet.center.transpose();
  const PointCloud cloud = io::read_ply(dir / "run" / fused[0].ply);
  ASSERT_GT(cloud.size(), 100u);
  std::size_t inside = 0;
  for (const auto& p : cloud.points) inside += cabinet.contains(p.cast<double>(), 0.05);
  EXPECT_GE(static_cast<double>(inside) / cloud.size(), 0.90) << inside << " of " << cloud.size();
}

TEST(FuseReal, YcbVideoClipWithDefaultsFindsItsThreeObjects) {
  // ycbv_0000_10f as it is: PNG label images with classes.txt, depth factor 10000, its own
  // camera.json, and a camera that moves less than 5 cm / 5 degrees over the 10 frames. Motion
  // keeps one keyframe, fewer than the 3 observations an object needs: fuse's default (auto) then
  // uses every posed frame, and the three objects are found at their model origins.
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f");
  TempDir dir;
  const auto r = fuse_real(data, "masks", dir / "run");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto run = read_json(dir / "run" / "run.json");
  EXPECT_EQ(run["counts"]["keyframes"].get<int>(), 10);
  EXPECT_EQ(run["counts"]["keyframe_mode"].get<std::string>(), "all");
  EXPECT_NE(run["counts"]["keyframe_mode_reason"].get<std::string>().find("motion kept 1 of"),
            std::string::npos);
  const auto fused = read_fused_objects(dir / "run" / "objects.json");
  ASSERT_EQ(fused.size(), 3u) << r.out;
  // objects_gt.txt: "label class x y z spread_mm s" (the model origins).
  std::istringstream in(read_text(data / "objects_gt.txt"));
  std::string line;
  int matched = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream row(line);
    int label;
    std::string cls;
    Eigen::Vector3d origin;
    row >> label >> cls >> origin.x() >> origin.y() >> origin.z();
    std::replace(cls.begin(), cls.end(), '_', ' ');
    for (const auto& f : fused) {
      if (f.cls != cls) continue;
      ++matched;
      EXPECT_LT((f.position - origin).norm(), 0.03) << cls << " at " << f.position.transpose();
    }
  }
  EXPECT_EQ(matched, 3) << r.out;

  // Asked for by name, motion is kept, and the summary says why nothing can be confirmed.
  const auto m =
      run_objmap({"fuse", "--dataset", data.string(), "--trajectory",
                  (data / "groundtruth.txt").string(), "--segmentation", (data / "masks").string(),
                  "--out", (dir / "motion").string(), "--keyframes", "motion"});
  ASSERT_EQ(m.exit_code, 0) << m.err;
  EXPECT_TRUE(read_fused_objects(dir / "motion" / "objects.json").empty());
  EXPECT_NE(m.out.find("only 1 keyframe(s): an object needs 3 observations"), std::string::npos)
      << m.out;
}

}  // namespace
}  // namespace objmap::test
