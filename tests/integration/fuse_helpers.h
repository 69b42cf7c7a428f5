#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace objmap::test {

struct GtObject {
  int id = 0;
  std::string cls;
  Eigen::Vector3d centroid;
  Eigen::Vector3d center;
  Eigen::Matrix3d rotation;  // columns: box axes in the world
  Eigen::Vector3d half_extent;
  double largest_dimension() const { return 2.0 * half_extent.maxCoeff(); }
  bool contains(const Eigen::Vector3d& p, double margin = 0.0) const {
    const Eigen::Vector3d local = rotation.transpose() * (p - center);
    return (local.cwiseAbs().array() <= half_extent.array() + margin).all();
  }
};

struct FusedObject {
  int id = 0;
  std::string cls;
  Eigen::Vector3d centroid;  // the paper's position: mean of the points
  Eigen::Vector3d position;  // objmap's robust position (percentile box centre)
  std::string ply;
  long points = 0;
};

inline nlohmann::json read_json(const fs::path& file) {
  std::ifstream in(file);
  return nlohmann::json::parse(in);
}

inline Eigen::Vector3d vec3(const nlohmann::json& a) {
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

inline std::vector<GtObject> read_gt_objects(const fs::path& file) {
  std::vector<GtObject> out;
  const nlohmann::json doc = read_json(file);
  for (const auto& o : doc.at("objects")) {
    GtObject g;
    g.id = o["id"].get<int>();
    g.cls = o["class"].get<std::string>();
    g.centroid = vec3(o["centroid"]);
    g.center = vec3(o["obb"]["center"]);
    const auto& r = o["obb"]["rotation"];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) g.rotation(i, j) = r[3 * i + j].get<double>();
    g.half_extent = vec3(o["obb"]["half_extent"]);
    out.push_back(g);
  }
  return out;
}

// The horizontal widths of an objects.json's objects by id: the larger side of each upright box
// (obb) seen from above, up = `up_in_world`.
inline std::map<int, double> horizontal_widths(const fs::path& file) {
  const nlohmann::json doc = read_json(file);
  const Eigen::Vector3d up =
      doc.contains("up_in_world") ? vec3(doc["up_in_world"]) : Eigen::Vector3d::UnitZ();
  std::map<int, double> widths;
  for (const auto& o : doc.at("objects")) {
    const auto& rot = o["obb"]["rotation"];
    const auto& half = o["obb"]["half_extent"];
    double width = 0.0;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d axis(rot[i].get<double>(), rot[3 + i].get<double>(),
                                 rot[6 + i].get<double>());
      const double along_up = std::fabs(axis.dot(up));
      width = std::max(
          width, 2.0 * half[i].get<double>() * std::sqrt(std::max(0.0, 1.0 - along_up * along_up)));
    }
    widths[o["id"].get<int>()] = width;
  }
  return widths;
}

inline std::vector<FusedObject> read_fused_objects(const fs::path& file) {
  std::vector<FusedObject> out;
  const nlohmann::json doc = read_json(file);
  for (const auto& o : doc.at("objects")) {
    FusedObject f;
    f.id = o["id"].get<int>();
    f.cls = o["class"].get<std::string>();
    f.centroid = vec3(o["centroid"]);
    f.position = vec3(o["position"]);
    f.ply = o["ply"].get<std::string>();
    f.points = o["points"]["outlier_filtered"].get<long>();
    out.push_back(f);
  }
  return out;
}

// One-to-one matching of ground-truth to fused objects by centroid distance (greedy on the sorted
// pair distances, gate in metres); `same_class` restricts pairs to equal classes.
inline std::vector<std::pair<int, int>> match_objects(const std::vector<GtObject>& gt,
                                                      const std::vector<FusedObject>& fused,
                                                      double gate_m, bool same_class) {
  std::vector<std::tuple<double, int, int>> pairs;
  for (int i = 0; i < static_cast<int>(gt.size()); ++i)
    for (int j = 0; j < static_cast<int>(fused.size()); ++j) {
      if (same_class && gt[i].cls != fused[j].cls) continue;
      const double d = (gt[i].centroid - fused[j].centroid).norm();
      if (d <= gate_m) pairs.emplace_back(d, i, j);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<bool> gt_used(gt.size()), fused_used(fused.size());
  std::vector<std::pair<int, int>> out;
  for (const auto& [d, i, j] : pairs) {
    if (gt_used[i] || fused_used[j]) continue;
    gt_used[i] = fused_used[j] = true;
    out.emplace_back(i, j);
  }
  return out;
}

}  // namespace objmap::test
