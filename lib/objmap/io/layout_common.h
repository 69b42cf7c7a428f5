#pragma once
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/camera.h"
#include "objmap/core/types.h"
#include "objmap/io/dataset.h"

// What the layout readers of io/dataset.cpp share: numbered files, matrices in text files, poses
// from 4x4 matrices, a camera from a 3x3 K. Internal to io/.
namespace objmap::io::layout {

struct NumberedFile {
  std::int64_t number = 0;
  std::filesystem::path file;
};

// The regular files of `dir` whose name is `prefix` + a decimal number + one of `suffixes`
// (e.g. "frame-", {".color.png", ".color.jpg"}), sorted by number. Two files with one number are
// an InputError naming both.
std::vector<NumberedFile> numbered_files(const std::filesystem::path& dir,
                                         const std::string& prefix,
                                         const std::vector<std::string>& suffixes);

// The number in a file name: the last run of digits of its stem ("frame000012" -> 12), or nullopt.
std::optional<std::int64_t> number_in_name(const std::string& name);

// All whitespace-separated numbers of a text file (comments with '#' skipped). "inf", "-inf" and
// "nan" are read as such (ScanNet marks lost poses with -inf); any other text is an InputError
// naming the file and line.
std::vector<double> read_numbers(const std::filesystem::path& file);

// A pose from 16 (or 12: the last row 0 0 0 1 is implied) row-major numbers of a 4x4
// world_from_cam matrix; nullopt when any number is not finite (lost tracking). The rotation is
// made orthonormal (nearest rotation); one further than 1e-2 from a rotation, a last row other
// than 0 0 0 1, or another count of numbers is an InputError naming `where`.
std::optional<Pose> pose_from_numbers(const std::vector<double>& numbers, const std::string& where);

// A camera from a 3x3 (or 4x4, as ScanNet writes it) intrinsic matrix file: fx = K(0,0),
// fy = K(1,1), cx = K(0,2), cy = K(1,2); the image size and depth factor given.
Camera camera_from_k_file(const std::filesystem::path& file, int width, int height,
                          double depth_factor);

// The size of an image file (PNG or JPEG) as (width, height), read from its pixels.
std::pair<int, int> image_size(const std::filesystem::path& file);

// Frames paired one to one in the order of their numbers: colour i with depth i. Different counts,
// or numbers that differ, are an InputError naming the first colour image without its depth.
// Timestamps are number / fps.
std::vector<FramePair> pair_by_number(const std::vector<NumberedFile>& color,
                                      const std::vector<NumberedFile>& depth, double fps);

// Colour i with depth i in the order of their numbers, whatever the numbers (one depth image per
// colour image: a lone image is an InputError naming it), at the times `time_of` gives each
// colour image; times must increase strictly.
std::vector<FramePair> pair_in_order(const std::vector<NumberedFile>& color,
                                     const std::vector<NumberedFile>& depth,
                                     const std::function<double(const NumberedFile&)>& time_of);

// Keeps the frames whose pose is known (poses[i] for frame i), counting the lost ones, and fills
// dataset.poses stamped with each kept frame's rgb timestamp; `source` names the pose files.
void attach_poses(Dataset& dataset, const std::vector<std::optional<Pose>>& poses,
                  const std::string& source);

// The readers of io/layout_readers.cpp (io/dataset.cpp reads tum, 7scenes and replica itself).
// Open3D's reconstruction system: color/, depth/ (mm), the .log trajectory `log` when there is one.
Dataset read_open3d(const std::filesystem::path& dir,
                    const std::optional<std::filesystem::path>& log, const DatasetOptions& options);
// ScanNet as its SensReader exports it, depth registered into the colour camera.
Dataset read_scannet(const std::filesystem::path& dir, const DatasetOptions& options);
// Any posed capture described by an objmap_layout.json (`layout_file`).
Dataset read_generic(const std::filesystem::path& dir, const std::filesystem::path& layout_file,
                     const DatasetOptions& options);

}  // namespace objmap::io::layout
