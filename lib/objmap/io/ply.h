#pragma once
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>

#include "objmap/core/mesh.h"
#include "objmap/core/types.h"

// PLY point clouds (map_dense.ply, map_semantic.ply, objects/<id>_<class>.ply).
namespace objmap::io {

struct PlyWriteOptions {
  std::string comment = "objmap";  // a `comment` header line (empty: none)
};

// Writes binary little-endian PLY: `element vertex N` with `float x, y, z` and, when the cloud has
// colours, `uchar red, green, blue` — read by CloudCompare, MeshLab, Open3D and PCL. The file is
// written under a temporary name in the same folder and renamed, so a failure leaves no half file.
// Throws InputError naming the path when the file cannot be written.
void write_ply(const std::filesystem::path& path, const PointCloud& cloud,
               const PlyWriteOptions& options = {});
// The same with the points of `cloud` and the colours `colors` (one per point) instead of its own.
void write_ply(const std::filesystem::path& path, const PointCloud& cloud,
               const std::vector<Rgb>& colors, const PlyWriteOptions& options = {});

// Reads a PLY point cloud, binary little-endian or ASCII: the `vertex` element's x, y, z (float or
// double) and red, green, blue (uchar) when present; other vertex properties are skipped; elements
// after `vertex` are ignored. Throws InputError "<path>: <what>" for anything else (big-endian,
// missing x/y/z, a list property in vertex, a truncated file, ...).
PointCloud read_ply(const std::filesystem::path& path);

// The same points read a block of at most 65536 at a time, each block handed to `take` in the
// file's order (a map read without holding it whole); throws as read_ply.
void read_ply_blocks(const std::filesystem::path& path,
                     const std::function<void(const PointCloud&)>& take);

// The vertex count of a PLY file's header, checked as read_ply checks it.
std::size_t ply_vertex_count(const std::filesystem::path& path);

// Writes a triangle mesh as binary little-endian PLY (objects/<id>_<class>_mesh.ply, map_mesh.ply):
// `element vertex` with float x, y, z, then float nx, ny, nz and uchar red, green, blue when the
// mesh has them, and `element face` with `property list uchar int vertex_indices` — read by
// MeshLab, CloudCompare, Blender and Open3D. Atomic like write_ply.
void write_mesh_ply(const std::filesystem::path& path, const TriangleMesh& mesh,
                    const PlyWriteOptions& options = {});

// Reads a PLY mesh, binary little-endian or ASCII: the vertices as read_ply reads them (with nx,
// ny, nz when present) and the `face` element's vertex_indices (any integer list types; polygons
// become triangle fans). Throws InputError "<path>: <what>" for a face that names a vertex the file
// does not have, a truncated file, and what read_ply refuses.
TriangleMesh read_mesh_ply(const std::filesystem::path& path);

}  // namespace objmap::io
