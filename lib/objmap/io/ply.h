#pragma once
#include <filesystem>
#include <string>

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

}  // namespace objmap::io
