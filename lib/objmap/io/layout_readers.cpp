// The layouts of other reconstruction systems: Open3D's reconstruction system, ScanNet's
// SensReader export and objmap's own description of any posed capture (objmap_layout.json).
#include <algorithm>
#include <cmath>
#include <set>
#include <system_error>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"
#include "objmap/io/layout_common.h"
#include "objmap/io/text_lines.h"
#include "objmap/io/trajectory.h"

namespace objmap::io::layout {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

std::vector<NumberedFile> images_of(const fs::path& dir, const std::vector<std::string>& exts) {
  std::vector<NumberedFile> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string ext = entry.path().extension().string();
    if (!entry.is_regular_file(ec) || std::find(exts.begin(), exts.end(), ext) == exts.end())
      continue;
    const auto number = number_in_name(entry.path().filename().string());
    if (!number)
      throw InputError(entry.path().string(),
                       "has no frame number in its name; expected images numbered by frame");
    files.push_back({*number, entry.path()});
  }
  if (ec) throw InputError(dir.string(), "cannot list: " + ec.message());
  std::sort(files.begin(), files.end(), [](const NumberedFile& a, const NumberedFile& b) {
    return a.number != b.number ? a.number < b.number : a.file < b.file;
  });
  for (std::size_t i = 1; i < files.size(); ++i)
    if (files[i].number == files[i - 1].number)
      throw InputError(files[i].file.string(), "has the frame number of " +
                                                   files[i - 1].file.string() +
                                                   "; expected one image per frame number");
  return files;
}

// An Open3D PinholeCameraIntrinsic JSON of `dir` ({"width", "height", "intrinsic_matrix": 9
// numbers, column-major}), or nullopt when the folder has none.
std::optional<std::pair<Camera, fs::path>> open3d_intrinsic(const fs::path& dir) {
  std::vector<fs::path> jsons;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_regular_file(ec) && entry.path().extension() == ".json")
      jsons.push_back(entry.path());
  std::sort(jsons.begin(), jsons.end());
  for (const fs::path& file : jsons) {
    const json doc = read_json_file(file, "cannot open");
    if (!doc.is_object() || !doc.contains("intrinsic_matrix")) continue;
    const json& k = doc["intrinsic_matrix"];
    const std::string where = file.string() + ": intrinsic_matrix";
    if (!k.is_array() || k.size() != 9)
      throw InputError(where, "expected 9 numbers (a 3x3 matrix, column-major)");
    for (const json& v : k)
      if (!v.is_number()) throw InputError(where, "holds a value that is not a number");
    Camera c;
    c.name = file.string();
    c.fx = k[0].get<double>();
    c.fy = k[4].get<double>();
    c.cx = k[6].get<double>();
    c.cy = k[7].get<double>();
    for (const char* key : {"width", "height"}) {
      if (!doc.contains(key) || !doc[key].is_number_integer())
        throw InputError(file.string() + ": " + key, "missing or not an integer");
    }
    c.width = doc["width"].get<int>();
    c.height = doc["height"].get<int>();
    return std::make_pair(c, file);
  }
  return std::nullopt;
}

// A Redwood / Open3D .log trajectory: per frame a line "i j n" and four rows of a 4x4
// camera_to_world matrix.
std::vector<std::optional<Pose>> read_log_trajectory(const fs::path& file) {
  LineReader in(file);
  std::vector<std::optional<Pose>> poses;
  while (in.next()) {
    in.expect_fields(3, "the metadata line 'id id frame' of a .log trajectory");
    const std::string where = in.where();
    std::vector<double> m;
    for (int row = 0; row < 4; ++row) {
      if (!in.next())
        throw InputError(where, "pose ends after " + std::to_string(row) +
                                    " rows; expected 4 rows of 4 numbers");
      in.expect_fields(4, "a row of the 4x4 pose");
      for (std::size_t i = 0; i < 4; ++i) m.push_back(in.number(i, "matrix value"));
    }
    poses.push_back(pose_from_numbers(m, where));
  }
  return poses;
}

}  // namespace

Dataset read_open3d(const fs::path& dir, const std::optional<fs::path>& log,
                    const DatasetOptions& options) {
  Dataset d;
  d.root = dir;
  d.layout = "open3d";
  const auto color = images_of(dir / "color", {".jpg", ".png", ".jpeg"});
  const auto depth = images_of(dir / "depth", {".png"});
  if (color.empty())
    throw InputError((dir / "color").string(), "no image; expected an Open3D dataset folder");
  d.rgb_rows = color.size();
  d.depth_rows = depth.size();
  d.frames = pair_in_order(color, depth, [&](const NumberedFile& f) {
    return static_cast<double>(f.number) / options.fps;
  });
  if (log) {
    const auto poses = read_log_trajectory(*log);
    if (poses.size() != d.frames.size())
      throw InputError(log->string(), std::to_string(poses.size()) + " poses for " +
                                          std::to_string(d.frames.size()) +
                                          " frames; expected one pose per frame, in frame order");
    attach_poses(d, poses, log->string());
  }
  const auto [width, height] = image_size(d.frames.front().rgb_file);
  if (auto found = open3d_intrinsic(dir)) {
    d.camera = found->first;
    d.camera_source = found->second.string();
  } else {
    Camera c;  // Open3D's default: PrimeSense
    c.name = "Open3D default (PrimeSense 525, 525, 319.5, 239.5)";
    d.camera = c;
    d.camera_source = c.name;
  }
  if (d.camera->width != width || d.camera->height != height)
    throw InputError(d.frames.front().rgb_file.string(),
                     "is " + std::to_string(width) + "x" + std::to_string(height) +
                         "; the intrinsics (" + d.camera_source + ") are for " +
                         std::to_string(d.camera->width) + "x" + std::to_string(d.camera->height));
  d.camera->depth_factor = d.depth_factor = 1000.0;
  d.camera->check(d.camera_source);
  return d;
}

Dataset read_scannet(const fs::path& dir, const DatasetOptions& options) {
  Dataset d;
  d.root = dir;
  d.layout = "scannet";
  const auto color = images_of(dir / "color", {".jpg", ".png"});
  const auto depth = images_of(dir / "depth", {".png"});
  if (color.empty()) throw InputError((dir / "color").string(), "no image; expected N.jpg");
  d.rgb_rows = color.size();
  d.depth_rows = depth.size();
  d.frames = pair_by_number(color, depth, options.fps);
  std::vector<std::optional<Pose>> poses;
  for (const FramePair& f : d.frames) {
    const fs::path pose_file = dir / "pose" / (f.rgb_file.stem().string() + ".txt");
    if (!is_file(pose_file))
      throw InputError(pose_file.string(), "not found; expected pose/N.txt for colour frame " +
                                               f.rgb_file.filename().string());
    poses.push_back(pose_from_numbers(read_numbers(pose_file), pose_file.string()));
  }
  attach_poses(d, poses, (dir / "pose" / "N.txt").string());
  const fs::path intrinsic = dir / "intrinsic";
  const auto [cw, ch] = image_size(d.frames.front().rgb_file);
  const auto [dw, dh] = image_size(d.frames.front().depth_file);
  d.camera = camera_from_k_file(intrinsic / "intrinsic_color.txt", cw, ch, 1000.0);
  d.camera_source = (intrinsic / "intrinsic_color.txt").string();
  d.depth_factor = 1000.0;
  // Each extrinsic maps its camera into the sensor rig; the colour camera's pose in the depth
  // camera's frame is extrinsic_color^-1 * extrinsic_depth (identity in SensReader's exports).
  Dataset::DepthCamera depth_camera;
  depth_camera.camera = camera_from_k_file(intrinsic / "intrinsic_depth.txt", dw, dh, 1000.0);
  Pose rig_from_color = Pose::Identity(), rig_from_depth = Pose::Identity();
  for (auto [name, pose] : {std::pair{"extrinsic_color.txt", &rig_from_color},
                            std::pair{"extrinsic_depth.txt", &rig_from_depth}}) {
    const fs::path file = intrinsic / name;
    if (!is_file(file)) continue;
    const auto p = pose_from_numbers(read_numbers(file), file.string());
    if (!p) throw InputError(file.string(), "is not finite; expected a rigid 4x4 matrix");
    *pose = *p;
  }
  depth_camera.color_from_depth = rig_from_color.inverse() * rig_from_depth;
  if (cw != dw || ch != dh || !depth_camera.color_from_depth.isApprox(Pose::Identity()) ||
      depth_camera.camera.fx != d.camera->fx || depth_camera.camera.cx != d.camera->cx)
    d.depth_camera = depth_camera;
  return d;
}

}  // namespace objmap::io::layout
