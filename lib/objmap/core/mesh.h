#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "objmap/core/types.h"

namespace objmap {

// A triangle mesh as parallel arrays: vertex positions in metres, and (each either empty or one per
// vertex) unit normals and colours; triangles as three vertex indices, counter-clockwise seen from
// the side the normals point to.
struct TriangleMesh {
  std::vector<Vec3f> vertices;
  std::vector<Vec3f> normals;
  std::vector<Rgb> colors;
  std::vector<std::array<std::uint32_t, 3>> triangles;

  bool empty() const { return triangles.empty(); }
  bool has_normals() const { return !normals.empty() && normals.size() == vertices.size(); }
  bool has_colors() const { return !colors.empty() && colors.size() == vertices.size(); }
  // The surface area in square metres.
  double area() const {
    double sum = 0.0;
    for (const auto& t : triangles)
      sum += 0.5 * (vertices[t[1]] - vertices[t[0]])
                       .cast<double>()
                       .cross((vertices[t[2]] - vertices[t[0]]).cast<double>())
                       .norm();
    return sum;
  }
};

}  // namespace objmap
