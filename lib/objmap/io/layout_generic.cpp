// The generic layout: any posed capture described by an objmap_layout.json (docs/formats.md
// "The generic layout").
#include <fnmatch.h>

#include <algorithm>
#include <cmath>
#include <limits>
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

const std::set<std::string> kKeys = {"color",      "depth",  "depth_scale", "depth_invalid",
                                     "intrinsics", "poses",  "pose_format", "pose_convention",
                                     "fps",        "$schema"};

// One field of the layout file, with its place for messages.
struct Field {
  const json& doc;
  std::string file;
  std::string where(const std::string& key) const { return file + ": " + key; }
  bool has(const std::string& key) const { return doc.contains(key); }
  std::string text(const std::string& key) const {
    if (!doc.contains(key) || !doc[key].is_string() || doc[key].get<std::string>().empty())
      throw InputError(where(key), "missing or not a non-empty string");
    return doc[key].get<std::string>();
  }
  double number(const std::string& key, double low, double high) const {
    if (!doc.contains(key) || !doc[key].is_number())
      throw InputError(where(key), "missing or not a number");
    const double v = doc[key].get<double>();
    if (!std::isfinite(v) || v < low || v > high)
      throw InputError(where(key), "is " + doc[key].dump() + "; expected a number in [" +
                                       json(low).dump() + ", " + json(high).dump() + "]");
    return v;
  }
};

// Files matching a glob relative to `dir` ('*', '?', [..] in the file name; the folder part taken
// as it is), sorted by the number in their names.
std::vector<NumberedFile> glob_numbered(const fs::path& dir, const std::string& pattern,
                                        const std::string& field) {
  const fs::path rel(pattern);
  const fs::path folder = dir / rel.parent_path();
  const std::string name_pattern = rel.filename().string();
  std::vector<NumberedFile> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file(ec) || fnmatch(name_pattern.c_str(), name.c_str(), 0) != 0) continue;
    const auto number = number_in_name(name);
    if (!number)
      throw InputError(entry.path().string(),
                       "matches " + field + " but has no frame number in its name");
    files.push_back({*number, entry.path()});
  }
  if (files.empty())
    throw InputError(field, "'" + pattern + "' matches no file in " + folder.string());
  std::sort(files.begin(), files.end(), [](const NumberedFile& a, const NumberedFile& b) {
    return a.number != b.number ? a.number < b.number : a.file < b.file;
  });
  for (std::size_t i = 1; i < files.size(); ++i)
    if (files[i].number == files[i - 1].number)
      throw InputError(files[i].file.string(), "has the frame number of " +
                                                   files[i - 1].file.string() + " (" + field +
                                                   "); expected one file per frame number");
  return files;
}

// The frame's timestamp: its file name when that is a number of seconds (1305031102.175304.png),
// else the number in the name / fps.
double frame_time(const NumberedFile& f, double fps) {
  const std::string stem = f.file.stem().string();
  try {
    return parse_double(stem, "", "");
  } catch (const InputError&) {
    return static_cast<double>(f.number) / fps;
  }
}

Camera generic_camera(const Field& f, const fs::path& dir, int width, int height, double scale) {
  const json& k = f.doc.contains("intrinsics") ? f.doc["intrinsics"] : json();
  if (k.is_string()) return camera_from_k_file(dir / k.get<std::string>(), width, height, scale);
  if (!k.is_object())
    throw InputError(
        f.where("intrinsics"),
        "missing; expected a path to a 3x3 matrix or {\"fx\", \"fy\", \"cx\", \"cy\"}");
  const Field kf{k, f.file + ": intrinsics"};
  for (const auto& [key, value] : k.items())
    if (key != "fx" && key != "fy" && key != "cx" && key != "cy")
      throw InputError(kf.where(key), "unknown field; expected fx, fy, cx, cy");
  Camera c;
  c.name = f.file;
  const double big = 1e7;
  c.fx = kf.number("fx", 1e-9, big);
  c.fy = kf.number("fy", 1e-9, big);
  c.cx = kf.number("cx", -big, big);
  c.cy = kf.number("cy", -big, big);
  c.width = width;
  c.height = height;
  c.depth_factor = scale;
  c.check(f.file);
  return c;
}

// The poses of the frames, in frame order (matrix formats), or as a TUM trajectory.
void generic_poses(const Field& f, const fs::path& dir, Dataset& d,
                   const std::vector<NumberedFile>& color) {
  const std::string format = f.text("pose_format");
  const std::string convention =
      f.has("pose_convention") ? f.text("pose_convention") : "world_from_camera";
  if (convention != "world_from_camera" && convention != "camera_from_world")
    throw InputError(f.where("pose_convention"),
                     "is '" + convention + "'; expected world_from_camera or camera_from_world");
  const bool invert = convention == "camera_from_world";
  const std::string poses = f.text("poses");
  if (format == "tum") {
    Trajectory t = read_trajectory(dir / poses);
    if (invert)
      for (StampedPose& p : t.poses) p.world_from_cam = p.world_from_cam.inverse();
    d.poses = std::move(t);
    return;
  }
  std::vector<std::optional<Pose>> list;
  std::string source = (dir / poses).string();
  if (format == "matrix_per_line") {
    LineReader in(dir / poses);
    while (in.next()) {
      std::vector<double> row;
      for (std::size_t i = 0; i < in.size(); ++i) row.push_back(in.number(i, "matrix value"));
      if (row.size() != 12 && row.size() != 16)
        throw InputError(in.where(), std::to_string(row.size()) +
                                         " numbers; expected 12 or 16 (a row-major 4x4 pose)");
      list.push_back(pose_from_numbers(row, in.where()));
    }
  } else if (format == "matrix_per_file") {
    for (const NumberedFile& file : glob_numbered(dir, poses, f.where("poses")))
      list.push_back(pose_from_numbers(read_numbers(file.file), file.file.string()));
  } else {
    throw InputError(f.where("pose_format"),
                     "is '" + format + "'; expected tum, matrix_per_line or matrix_per_file");
  }
  if (list.size() != color.size())
    throw InputError(source, std::to_string(list.size()) + " poses for " +
                                 std::to_string(color.size()) +
                                 " frames; expected one pose per frame, in frame order");
  if (invert)
    for (auto& p : list)
      if (p) p = p->inverse();
  attach_poses(d, list, source);
}

}  // namespace

Dataset read_generic(const fs::path& dir, const fs::path& layout_file,
                     const DatasetOptions& options) {
  const json doc = read_json_file(layout_file, "cannot open; expected an objmap_layout.json");
  const std::string file = layout_file.string();
  if (!doc.is_object()) throw InputError(file, "is not a JSON object; expected objmap_layout.json");
  for (const auto& [key, value] : doc.items())
    if (!kKeys.count(key))
      throw InputError(file + ": " + key,
                       "unknown field; expected color, depth, depth_scale, depth_invalid, "
                       "intrinsics, poses, pose_format, pose_convention, fps");
  const Field f{doc, file};
  Dataset d;
  d.root = dir;
  d.layout = "generic";
  const double fps = f.has("fps") ? f.number("fps", 1e-6, 1e6) : options.fps;
  const auto color = glob_numbered(dir, f.text("color"), f.where("color"));
  const auto depth = glob_numbered(dir, f.text("depth"), f.where("depth"));
  d.rgb_rows = color.size();
  d.depth_rows = depth.size();
  d.frames = pair_in_order(color, depth, [&](const NumberedFile& c) { return frame_time(c, fps); });
  d.depth_factor = f.number("depth_scale", 1e-6, 1e9);
  if (f.has("depth_invalid"))  // 0: no value besides 0 itself, which is always "no depth"
    d.depth_invalid = static_cast<std::uint16_t>(f.number("depth_invalid", 0, 65535));
  const auto [width, height] = image_size(d.frames.front().rgb_file);
  d.camera = generic_camera(f, dir, width, height, d.depth_factor);
  d.camera_source = file;
  if (f.has("poses") || f.has("pose_format")) generic_poses(f, dir, d, color);
  return d;
}

}  // namespace objmap::io::layout
