// The object models on scenes whose surfaces are known exactly: a sphere seen by a ring of cameras.
#include "objmap/mesh/tsdf.h"

#include <gtest/gtest.h>
#include <link.h>

#include <cmath>
#include <string>
#include <vector>

#include "objmap/core/error.h"

namespace objmap::mesh {
namespace {

const Vec3 kCentre(0.0, 0.0, 1.0);
constexpr double kRadius = 0.08;

// The points a pinhole camera at `eye` looking at the sphere's centre measures on it (exact
// depths; 200×200 pixels, 60 degrees field of view), each coloured red.
PointCloud render_sphere(const Vec3& eye) {
  const Vec3 forward = (kCentre - eye).normalized();
  const Vec3 right = forward.cross(Vec3::UnitZ()).norm() > 0.1
                         ? forward.cross(Vec3::UnitZ()).normalized()
                         : forward.cross(Vec3::UnitX()).normalized();
  const Vec3 down = forward.cross(right);
  PointCloud cloud;
  const int n = 200;
  const double f = n / 2.0 / std::tan(M_PI / 6.0);
  for (int v = 0; v < n; ++v)
    for (int u = 0; u < n; ++u) {
      const Vec3 dir =
          (forward * f + right * (u - n / 2.0 + 0.5) + down * (v - n / 2.0 + 0.5)).normalized();
      const Vec3 oc = eye - kCentre;
      const double b = oc.dot(dir), c = oc.squaredNorm() - kRadius * kRadius, disc = b * b - c;
      if (disc < 0) continue;
      const double t = -b - std::sqrt(disc);
      cloud.push_back((eye + t * dir).cast<float>(), Rgb{200, 30, 30});
    }
  return cloud;
}

// Cameras on a ring 0.5 m from the centre, 30 degrees above it, at `degrees` around.
std::vector<Vec3> ring_of_cameras(const std::vector<double>& degrees = {0, 45, 90, 135, 180, 225,
                                                                        270, 315}) {
  std::vector<Vec3> eyes;
  for (double d : degrees) {
    const double a = d * M_PI / 180.0;
    eyes.push_back(kCentre + 0.5 * Vec3(std::cos(a) * std::cos(M_PI / 6),
                                        std::sin(a) * std::cos(M_PI / 6), std::sin(M_PI / 6)));
  }
  return eyes;
}

Aabb box_around_sphere(double margin) {
  Aabb box;
  box.min = kCentre - Vec3::Constant(kRadius + margin);
  box.max = kCentre + Vec3::Constant(kRadius + margin);
  return box;
}

TEST(Tsdf, SphereMeshLiesWithinHalfAVoxelOfTheTrueSurface) {
  std::vector<PointCloud> clouds;
  for (const Vec3& eye : ring_of_cameras()) clouds.push_back(render_sphere(eye));
  std::vector<DepthView> views;
  const auto eyes = ring_of_cameras();
  for (std::size_t i = 0; i < eyes.size(); ++i) views.push_back({eyes[i], &clouds[i]});
  const double voxel = 0.004;
  const ModelResult r = fuse_model(views, box_around_sphere(0.03), voxel, {});
  ASSERT_GT(r.mesh.triangles.size(), 1000u);
  ASSERT_TRUE(r.mesh.has_normals());
  ASSERT_TRUE(r.mesh.has_colors());
  double worst = 0.0;
  int outward = 0, within_half = 0;
  for (std::size_t i = 0; i < r.mesh.vertices.size(); ++i) {
    const Vec3 p = r.mesh.vertices[i].cast<double>();
    const double e = std::abs((p - kCentre).norm() - kRadius);
    worst = std::max(worst, e);
    within_half += e < 0.5 * voxel;
    if (r.mesh.normals[i].cast<double>().dot((p - kCentre).normalized()) > 0.9) ++outward;
  }
  std::printf("sphere: %zu vertices, %d within half a voxel, worst %.2f mm\n",
              r.mesh.vertices.size(), within_half, 1000 * worst);
  // Away from the edge of the seen part (where the views graze the sphere), within half a voxel.
  EXPECT_GE(within_half, static_cast<int>(0.995 * r.mesh.vertices.size()));
  EXPECT_LT(worst, voxel);
  EXPECT_GE(outward, static_cast<int>(0.99 * r.mesh.vertices.size()));
  EXPECT_EQ(r.mesh.colors.front(), (Rgb{200, 30, 30}));
  // The cameras see the sphere from 30 degrees above: the upper part and the sides, not the
  // bottom; the seen part of the area 4 pi r^2 is most of it (the mesh does not close the bottom).
  const double sphere_area = 4.0 * M_PI * kRadius * kRadius;
  EXPECT_GT(r.mesh.area(), 0.6 * sphere_area);
  EXPECT_LT(r.mesh.area(), 1.0 * sphere_area);
}

TEST(Tsdf, SpaceCarvingRemovesFlyingPixelsThatOtherViewsSeeThrough) {
  const auto eyes = ring_of_cameras({0, 45, 90, 135, 180, 225, 270, 315, 80, 100});
  std::vector<PointCloud> clouds;
  for (const Vec3& eye : eyes) clouds.push_back(render_sphere(eye));
  // View 0 also measured a patch of flying pixels 4 cm off the sphere, where view 2 (and the two
  // beside it, as the frames of a video) look through at the sphere.
  const Vec3 flying = kCentre + (eyes[2] - kCentre).normalized() * (kRadius + 0.04);
  for (int i = -6; i <= 6; ++i)
    for (int j = -6; j <= 6; ++j)
      clouds[0].push_back((flying + Vec3(0.0021 * i, 0.0, 0.0021 * j)).cast<float>(), Rgb{0, 0, 0});
  std::vector<DepthView> views;
  for (std::size_t i = 0; i < eyes.size(); ++i) views.push_back({eyes[i], &clouds[i]});
  TsdfOptions options;
  options.min_component_share = 0.0;  // the carving alone
  auto near_flying = [&](const TriangleMesh& mesh) {
    int n = 0;
    for (const Vec3f& v : mesh.vertices) n += (v.cast<double>() - flying).norm() < 0.02;
    return n;
  };
  const ModelResult carved = fuse_model(views, box_around_sphere(0.06), 0.004, options);
  options.space_carving = false;
  const ModelResult kept = fuse_model(views, box_around_sphere(0.06), 0.004, options);
  // Without carving the patch is a surface of its own; with it, at most a few vertices of its rim
  // (where the rays through it no longer reach the sphere) remain.
  std::printf("vertices at the flying patch: %d kept, %d carved\n", near_flying(kept.mesh),
              near_flying(carved.mesh));
  EXPECT_GT(near_flying(kept.mesh), 20);
  EXPECT_LT(near_flying(carved.mesh), near_flying(kept.mesh) / 4);
}

TEST(Tsdf, VoxelFollowsTheSizeWithinItsBounds) {
  TsdfOptions o;
  EXPECT_DOUBLE_EQ(model_voxel_m(Vec3(0.1, 0.05, 0.02), o), 0.004);  // 2 mm: clamped up
  EXPECT_DOUBLE_EQ(model_voxel_m(Vec3(0.5, 0.3, 0.2), o), 0.01);
  EXPECT_DOUBLE_EQ(model_voxel_m(Vec3(3.0, 1.0, 1.0), o), 0.02);  // 6 cm: clamped down
  o.voxel_m = 0.007;
  EXPECT_DOUBLE_EQ(model_voxel_m(Vec3(3.0, 1.0, 1.0), o), 0.007);
}

TEST(Tsdf, BadOptionsAndSelectionsNameTheField) {
  TsdfOptions o;
  o.max_voxel_m = 0.001;
  try {
    o.check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("max_voxel_m"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(parse_mesh_selection("all", "--mesh").scene);
  EXPECT_FALSE(parse_mesh_selection("objects", "--mesh").scene);
  EXPECT_THROW(parse_mesh_selection("everything", "--mesh"), InputError);
}

TEST(Tsdf, NoViewsNoMesh) {
  const ModelResult r = fuse_model({}, box_around_sphere(0.0), 0.004, {});
  EXPECT_TRUE(r.mesh.empty());
  EXPECT_EQ(r.voxels, 0u);
}

// Whether a shared object whose path contains `name` is loaded in this process.
bool loaded(const std::string& name) {
  struct Query {
    std::string name;
    bool found = false;
  } query{name};
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) {
        auto* q = static_cast<Query*>(data);
        if (info->dlpi_name && std::string(info->dlpi_name).find(q->name) != std::string::npos)
          q->found = true;
        return 0;
      },
      &query);
  return query.found;
}

// OpenVDB is not linked into the programs (its libraries cost ~50 ms at every start): the first
// model loads it through libobjmap_vdb.so. Run alone (as ctest runs each test), nothing has loaded
// it before.
TEST(Tsdf, OpenVdbIsLoadedOnlyWhenTheFirstModelIsMade) {
  if (loaded("libobjmap_vdb")) GTEST_SKIP() << "an earlier test of this process made a model";
  EXPECT_FALSE(loaded("libopenvdb")) << "OpenVDB is linked into the program";
  TsdfOptions options;
  TsdfModel model(Aabb{Vec3(-0.1, -0.1, 0.9), Vec3(0.1, 0.1, 1.1)}, 0.01, options);
  EXPECT_TRUE(loaded("libobjmap_vdb"));
  EXPECT_TRUE(loaded("libopenvdb"));
  EXPECT_TRUE(model.mesh().mesh.empty());
}

}  // namespace
}  // namespace objmap::mesh
