#include "objmap/io/obj_mesh.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "objmap/core/error.h"

namespace objmap::io {

namespace {

// The vertex index of one face token ("7", "7/2", "7//3", "-1/..."), 0-based.
std::int64_t face_index(const std::string& token, std::size_t vertices, const std::string& at) {
  std::int64_t i = 0;
  try {
    i = std::stoll(token.substr(0, token.find('/')));
  } catch (const std::exception&) {
    throw InputError(at, "bad face index '" + token + "'");
  }
  const std::int64_t n = static_cast<std::int64_t>(vertices);
  const std::int64_t zero_based = i < 0 ? n + i : i - 1;
  if (i == 0 || zero_based < 0 || zero_based >= n)
    throw InputError(at, "face index " + std::to_string(i) + " names no vertex (" +
                             std::to_string(vertices) + " so far)");
  return zero_based;
}

}  // namespace

TriangleMesh read_obj_mesh(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "cannot open for reading");
  TriangleMesh mesh;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    const std::string at = file.string() + ":" + std::to_string(line_no);
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "v") {
      double x, y, z;
      if (!(ls >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
        throw InputError(at, "expected 'v x y z' with three numbers");
      mesh.vertices.emplace_back(static_cast<float>(x), static_cast<float>(y),
                                 static_cast<float>(z));
    } else if (word == "f") {
      std::vector<std::int64_t> index;
      for (std::string token; ls >> token;)
        index.push_back(face_index(token, mesh.vertices.size(), at));
      if (index.size() < 3) throw InputError(at, "a face needs at least 3 vertices");
      for (std::size_t k = 2; k < index.size(); ++k)
        mesh.triangles.push_back({static_cast<std::uint32_t>(index[0]),
                                  static_cast<std::uint32_t>(index[k - 1]),
                                  static_cast<std::uint32_t>(index[k])});
    }
  }
  if (mesh.triangles.empty()) throw InputError(file.string(), "no faces; expected a mesh");
  return mesh;
}

std::vector<ModelPose> read_model_poses(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "cannot open for reading");
  std::vector<ModelPose> out;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::string label;
    ModelPose p;
    double t[3], q[4];
    if (!(ls >> label >> p.name >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3]))
      throw InputError(file.string() + ":" + std::to_string(line_no),
                       "expected 'label name tx ty tz qx qy qz qw'");
    const Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);
    if (std::abs(rotation.norm() - 1.0) > 1e-3)
      throw InputError(file.string() + ":" + std::to_string(line_no),
                       "quaternion is not of unit length");
    p.world_from_object = Pose::Identity();
    p.world_from_object.linear() = rotation.normalized().toRotationMatrix();
    p.world_from_object.translation() = Vec3(t[0], t[1], t[2]);
    out.push_back(p);
  }
  if (out.empty()) throw InputError(file.string(), "no model poses");
  return out;
}

}  // namespace objmap::io
