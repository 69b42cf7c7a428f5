// The OpenVDB side of the TSDF models, built as the module libobjmap_vdb.so (vdb_backend.h).
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <numeric>
#include <utility>

#include "objmap/mesh/vdb_backend.h"

namespace objmap::mesh {

using detail::fast_floor;

namespace {

using openvdb::Coord;
using FloatGrid = openvdb::FloatGrid;
using ColorGrid = openvdb::Vec3SGrid;

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// Depth noise of a structured-light camera at range z (Nguyen et al. 2012), metres.
double depth_sigma(double z) { return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4); }

// One ray: its end (the measured point) and its colour.
struct Ray {
  Vec3 end = Vec3::Zero();
  Vec3 color = Vec3::Zero();
  bool has_color = false;
};

// The ray o + t·dir inside the box: [t_in, t_out], false when it misses.
bool clip_to_box(const Vec3& o, const Vec3& dir, const Aabb& box, double& t_in, double& t_out) {
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-12) {
      if (o[a] < box.min[a] || o[a] > box.max[a]) return false;
      continue;
    }
    double t0 = (box.min[a] - o[a]) / dir[a], t1 = (box.max[a] - o[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  return t_in <= t_out;
}

// The grids of one model: signed distance (metres, background +truncation), weight, colour sum
// and its weight.
struct Volume {
  double voxel_m, trunc_m;
  FloatGrid::Ptr tsdf, weight, color_weight;
  ColorGrid::Ptr color;
  Volume(double voxel, double trunc)
      : voxel_m(voxel),
        trunc_m(trunc),
        tsdf(FloatGrid::create(static_cast<float>(trunc))),
        weight(FloatGrid::create(0.0f)),
        color_weight(FloatGrid::create(0.0f)),
        color(ColorGrid::create(openvdb::Vec3s(0.0f))) {
    tsdf->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
  }
};

// Fuses one ray: the band ±truncation around its end, and with carving the free space in front
// of the band, each voxel once, inside `box`.
void fuse_ray(const Vec3& origin, const Ray& ray, const Aabb& box, const TsdfOptions& options,
              Volume& v, FloatGrid::Accessor& tsdf, FloatGrid::Accessor& weight,
              FloatGrid::Accessor& cweight, ColorGrid::Accessor& color) {
  const Vec3 diff = ray.end - origin;
  const double depth = diff.norm();
  if (depth < 1e-6) return;
  const Vec3 dir = diff / depth;
  double t_in = depth - v.trunc_m, t_out = depth + v.trunc_m;
  if (options.space_carving)
    t_in = options.carving_depth_m > 0.0 ? std::max(0.0, t_in - options.carving_depth_m) : 0.0;
  if (!clip_to_box(origin, dir, box, t_in, t_out)) return;
  const double sigma_ref = depth_sigma(options.reference_depth_m), sigma = depth_sigma(depth);
  const float w = static_cast<float>((sigma_ref * sigma_ref) / (sigma * sigma));
  const double band_start = depth - v.trunc_m;
  const double inverse_voxel = 1.0 / v.voxel_m;
  Coord last(std::numeric_limits<int>::min());
  for (double t = t_in; t <= t_out;) {
    const Vec3 x = origin + t * dir;
    const Vec3 g = x * inverse_voxel + Vec3::Constant(0.5);  // the nearest voxel centre
    const Coord c(static_cast<int>(fast_floor(g.x())), static_cast<int>(fast_floor(g.y())),
                  static_cast<int>(fast_floor(g.z())));
    t += t < band_start ? v.voxel_m : 0.5 * v.voxel_m;  // carving in voxel steps, the band finer
    if (c == last) continue;
    last = c;
    const Vec3 centre = Vec3(c.x(), c.y(), c.z()) * v.voxel_m;
    const double sdf = depth - (centre - origin).norm();
    if (sdf < -v.trunc_m) continue;
    const float value = static_cast<float>(std::min(sdf, v.trunc_m));
    const float w_old = weight.getValue(c), w_new = w_old + w;
    tsdf.setValue(c, (tsdf.getValue(c) * w_old + value * w) / w_new);
    weight.setValue(c, w_new);
    if (ray.has_color && std::abs(sdf) < v.trunc_m) {
      const Vec3 rgb = ray.color * w;
      color.setValue(c, color.getValue(c) + openvdb::Vec3s(static_cast<float>(rgb.x()),
                                                           static_cast<float>(rgb.y()),
                                                           static_cast<float>(rgb.z())));
      cweight.setValue(c, cweight.getValue(c) + w);
    }
  }
}

// True when every voxel of the cell holding `p` (index space) has at least `min_weight`.
bool observed_cell(const openvdb::Vec3d& p, float min_weight, FloatGrid::ConstAccessor& weight) {
  const Coord base(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())),
                   static_cast<int>(std::floor(p.z())));
  for (int dx = 0; dx < 2; ++dx)
    for (int dy = 0; dy < 2; ++dy)
      for (int dz = 0; dz < 2; ++dz)
        if (weight.getValue(base.offsetBy(dx, dy, dz)) < min_weight) return false;
  return true;
}

// The vertex's colour: the mean colour of the nearest voxel that has one (its cell's 8, then the
// 3×3×3 around it), grey when none.
Rgb vertex_color(const openvdb::Vec3d& p, ColorGrid::ConstAccessor& color,
                 FloatGrid::ConstAccessor& cweight) {
  const Coord near(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())),
                   static_cast<int>(std::lround(p.z())));
  openvdb::Vec3s sum(0.0f);
  float wsum = 0.0f;
  for (int ring = 0; ring <= 1 && wsum <= 0.0f; ++ring)
    for (int dx = -ring; dx <= ring; ++dx)
      for (int dy = -ring; dy <= ring; ++dy)
        for (int dz = -ring; dz <= ring; ++dz) {
          const Coord c = near.offsetBy(dx, dy, dz);
          sum += color.getValue(c);
          wsum += cweight.getValue(c);
        }
  if (wsum <= 0.0f) return Rgb{128, 128, 128};
  auto byte = [&](float x) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(x / wsum), 0L, 255L));
  };
  return Rgb{byte(sum.x()), byte(sum.y()), byte(sum.z())};
}

// The TSDF's outward unit normal at `p` (index space): its gradient, by central differences.
Vec3f vertex_normal(const openvdb::Vec3d& p, FloatGrid::ConstAccessor& tsdf) {
  using Sampler = openvdb::tools::BoxSampler;
  Vec3f g;
  for (int a = 0; a < 3; ++a) {
    openvdb::Vec3d lo = p, hi = p;
    lo[a] -= 0.5;
    hi[a] += 0.5;
    g[a] = Sampler::sample(tsdf, hi) - Sampler::sample(tsdf, lo);
  }
  const float n = g.norm();
  return n > 0.0f ? Vec3f(g / n) : Vec3f(0.0f, 0.0f, 1.0f);
}

// Connected pieces of the triangles (through shared vertices): the piece of each triangle.
std::vector<std::uint32_t> components(const TriangleMesh& mesh, std::uint32_t& count) {
  std::vector<std::uint32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& t : mesh.triangles) {
    const std::uint32_t a = find(t[0]), b = find(t[1]), c = find(t[2]);
    parent[b] = a;
    parent[find(c)] = a;
  }
  std::vector<std::uint32_t> label(mesh.vertices.size(), UINT32_MAX), piece;
  count = 0;
  for (const auto& t : mesh.triangles) {
    const std::uint32_t root = find(t[0]);
    if (label[root] == UINT32_MAX) label[root] = count++;
    piece.push_back(label[root]);
  }
  return piece;
}

// The triangles kept (flag per triangle) into a compact mesh: unused vertices go.
TriangleMesh compact(const TriangleMesh& mesh, const std::vector<bool>& keep) {
  TriangleMesh out;
  std::vector<std::uint32_t> index(mesh.vertices.size(), UINT32_MAX);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    if (!keep[f]) continue;
    std::array<std::uint32_t, 3> t;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = mesh.triangles[f][k];
      if (index[i] == UINT32_MAX) {
        index[i] = static_cast<std::uint32_t>(out.vertices.size());
        out.vertices.push_back(mesh.vertices[i]);
        if (mesh.has_normals()) out.normals.push_back(mesh.normals[i]);
        if (mesh.has_colors()) out.colors.push_back(mesh.colors[i]);
      }
      t[k] = index[i];
    }
    out.triangles.push_back(t);
  }
  return out;
}

// Marching the zero level (OpenVDB's volumeToMesh, quads split in two), each vertex with its
// normal and colour; triangles whose cell is not observed everywhere, and small pieces, dropped;
// each triangle wound counter-clockwise about its vertices' normals.
TriangleMesh extract_mesh(const Volume& v, const TsdfOptions& options) {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*v.tsdf, points, triangles, quads, 0.0, 0.0);
  FloatGrid::ConstAccessor tsdf = v.tsdf->getConstAccessor();
  FloatGrid::ConstAccessor weight = v.weight->getConstAccessor();
  FloatGrid::ConstAccessor cweight = v.color_weight->getConstAccessor();
  ColorGrid::ConstAccessor color = v.color->getConstAccessor();
  TriangleMesh mesh;
  std::vector<bool> observed(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const openvdb::Vec3d p = v.tsdf->transform().worldToIndex(openvdb::Vec3d(points[i]));
    observed[i] = observed_cell(p, static_cast<float>(options.min_weight), weight);
    mesh.vertices.emplace_back(points[i].x(), points[i].y(), points[i].z());
    mesh.normals.push_back(vertex_normal(p, tsdf));
    mesh.colors.push_back(vertex_color(p, color, cweight));
  }
  auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    if (!observed[a] || !observed[b] || !observed[c]) return;
    const Vec3f n =
        (mesh.vertices[b] - mesh.vertices[a]).cross(mesh.vertices[c] - mesh.vertices[a]);
    if (n.dot(mesh.normals[a] + mesh.normals[b] + mesh.normals[c]) < 0.0f) std::swap(b, c);
    mesh.triangles.push_back({a, b, c});
  };
  for (const auto& t : triangles) add(t[0], t[1], t[2]);
  for (const auto& q : quads) {
    add(q[0], q[1], q[2]);
    add(q[0], q[2], q[3]);
  }
  std::uint32_t pieces = 0;
  const std::vector<std::uint32_t> piece = components(mesh, pieces);
  std::vector<std::size_t> size(pieces, 0);
  for (std::uint32_t p : piece) ++size[p];
  std::vector<bool> keep(mesh.triangles.size());
  const double least = options.min_component_share * static_cast<double>(mesh.triangles.size());
  for (std::size_t f = 0; f < keep.size(); ++f)
    keep[f] = static_cast<double>(size[piece[f]]) >= least;
  return compact(mesh, keep);
}

}  // namespace

// One model: its box, options, grids and accessors.
struct Model {
  Aabb box;
  TsdfOptions options;
  Volume volume;
  FloatGrid::Accessor tsdf, weight, cweight;
  ColorGrid::Accessor color;
  std::size_t rays = 0;
  Model(const Aabb& b, double voxel_m, const TsdfOptions& o)
      : box(b),
        options(o),
        volume(voxel_m, std::max(o.truncation_voxels * voxel_m, o.min_truncation_m)),
        tsdf(volume.tsdf->getAccessor()),
        weight(volume.weight->getAccessor()),
        cweight(volume.color_weight->getAccessor()),
        color(volume.color->getAccessor()) {}
};

namespace {

void* create_model(const Aabb& box, double voxel_m, const TsdfOptions& options) {
  init_openvdb();
  return new Model(box, voxel_m, options);
}

void destroy_model(void* model) { delete static_cast<Model*>(model); }

void add_rays(void* model, const Vec3& camera_in_world, const PointCloud& rays) {
  Model& m = *static_cast<Model*>(model);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    Ray ray;
    ray.end = rays.points[i].cast<double>();
    ray.has_color = rays.has_colors();
    if (ray.has_color) ray.color = Vec3(rays.colors[i].r, rays.colors[i].g, rays.colors[i].b);
    fuse_ray(camera_in_world, ray, m.box, m.options, m.volume, m.tsdf, m.weight, m.cweight,
             m.color);
  }
  m.rays += rays.size();
}

void mesh_model(const void* model, ModelResult& result) {
  const Model& m = *static_cast<const Model*>(model);
  result.voxel_m = m.volume.voxel_m;
  result.truncation_m = m.volume.trunc_m;
  result.rays = m.rays;
  result.voxels = m.volume.tsdf->activeVoxelCount();
  if (result.voxels > 0) result.mesh = extract_mesh(m.volume, m.options);
}

}  // namespace

}  // namespace objmap::mesh

extern "C" __attribute__((visibility("default"))) const objmap::mesh::detail::VdbBackend*
objmap_vdb_backend() {
  static const objmap::mesh::detail::VdbBackend backend{
      objmap::mesh::detail::kVdbBackendAbi, objmap::mesh::create_model, objmap::mesh::destroy_model,
      objmap::mesh::add_rays, objmap::mesh::mesh_model};
  return &backend;
}
