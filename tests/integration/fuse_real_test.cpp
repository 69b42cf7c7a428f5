// objmap fuse on real TUM RGB-D data.
#include <gtest/gtest.h>

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

TEST(FuseReal, Fr3CabinetGivesOneObjectInsideTheGroundTruthCuboid) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr3_cabinet_58kf");
  TempDir dir;
  const auto r = run_objmap({"fuse", "--dataset", data.string(), "--trajectory",
                             (data / "groundtruth.txt").string(), "--segmentation",
                             (data / "boxes_yolov2").string(), "--out", (dir / "run").string()});
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

}  // namespace
}  // namespace objmap::test
