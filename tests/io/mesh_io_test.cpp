// Mesh PLY (write_mesh_ply, read_mesh_ply), OBJ models and model poses (io/obj_mesh.h).
#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "objmap/io/obj_mesh.h"
#include "objmap/io/ply.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

TriangleMesh two_triangles() {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5f}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0.6f, 0.8f}, {0, 0, 1}};
  m.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {7, 8, 9}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(MeshPly, WrittenMeshReadsBackExactly) {
  TempDir dir;
  const TriangleMesh m = two_triangles();
  io::write_mesh_ply(dir / "m.ply", m);
  const TriangleMesh r = io::read_mesh_ply(dir / "m.ply");
  EXPECT_EQ(r.vertices, m.vertices);
  EXPECT_EQ(r.normals, m.normals);
  EXPECT_EQ(r.colors, m.colors);
  EXPECT_EQ(r.triangles, m.triangles);
  // The point-cloud reader takes its vertices and ignores the faces.
  EXPECT_EQ(io::read_ply(dir / "m.ply").points, m.vertices);
  EXPECT_NE(read_text(dir / "m.ply").find("property list uchar int vertex_indices"),
            std::string::npos);
}

TEST(MeshPly, AsciiQuadsBecomeTwoTrianglesAndBadIndicesAreNamed) {
  TempDir dir;
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
  write_text(dir / "quad.ply", head + "4 0 1 2 3\n");
  const TriangleMesh q = io::read_mesh_ply(dir / "quad.ply");
  ASSERT_EQ(q.triangles.size(), 2u);
  EXPECT_EQ(q.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_DOUBLE_EQ(q.area(), 1.0);
  write_text(dir / "bad.ply", head + "3 0 1 9\n");
  try {
    io::read_mesh_ply(dir / "bad.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("names vertex 9 of 4"), std::string::npos) << e.what();
  }
}

TEST(ObjMesh, ReadsVerticesAndFacesOfEveryTokenForm) {
  TempDir dir;
  write_text(dir / "m.obj",
             "# model\nmtllib x.mtl\nvn 0 0 1\nv 0 0 0 0.5 0.5 0.5\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
             "vt 0 0\nf 1/1/1 2//1 3\nf -4 -2 -1\n");
  const TriangleMesh m = io::read_obj_mesh(dir / "m.obj");
  ASSERT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
  write_text(dir / "bad.obj", "v 0 0 0\nf 1 2 3\n");
  try {
    io::read_obj_mesh(dir / "bad.obj");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.obj:2"), std::string::npos) << e.what();
  }
}

TEST(ModelPoses, ReadsTranslationAndQuaternion) {
  TempDir dir;
  write_text(dir / "p.txt",
             "# label name t q\n8 009_gelatin_box 1 2 3 0 0 0.7071068 0.7071068 spread_mm 0.1\n");
  const auto poses = io::read_model_poses(dir / "p.txt");
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].name, "009_gelatin_box");
  const Vec3 x = poses[0].world_from_object * Vec3::UnitX();  // 90 degrees about z, then (1,2,3)
  EXPECT_NEAR((x - Vec3(1, 3, 3)).norm(), 0.0, 1e-6);
  write_text(dir / "bad.txt", "8 box 1 2 3 0 0 0\n");
  EXPECT_THROW(io::read_model_poses(dir / "bad.txt"), InputError);
}

}  // namespace
}  // namespace objmap::test
