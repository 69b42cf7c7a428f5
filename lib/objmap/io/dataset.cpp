#include "objmap/io/dataset.h"

#include <algorithm>
#include <cmath>
#include <system_error>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"
#include "objmap/io/layout_common.h"
#include "objmap/io/rosbag.h"
#include "objmap/io/text_lines.h"
#include "objmap/io/tum_dataset.h"

namespace objmap::io {

namespace fs = std::filesystem;
using layout::NumberedFile;

const std::vector<std::string> kLayouts = {"tum",    "7scenes", "scannet", "replica",
                                           "open3d", "generic", "rosbag"};

void DatasetOptions::check() const {
  require(layout == "auto" || std::count(kLayouts.begin(), kLayouts.end(), layout) > 0 ||
              fs::path(layout).extension() == ".json",
          "--layout",
          "is '" + layout +
              "'; expected auto, tum, 7scenes, scannet, replica, open3d, generic or an "
              "objmap_layout.json");
  require(std::isfinite(max_diff_s) && max_diff_s > 0.0, "DatasetOptions.max_diff_s",
          "expected a finite number of seconds > 0");
  require(std::isfinite(fps) && fps > 0.0, "DatasetOptions.fps", "expected a finite rate > 0");
}

namespace {

bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}
bool is_dir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

const std::vector<std::string> kSevenScenesColor = {".color.png", ".color.jpg"};

// The folders of a 7-Scenes recording that hold frames: the folder itself, or its seq-NN/
// subfolders in order.
std::vector<fs::path> seven_scenes_folders(const fs::path& dir) {
  if (!layout::numbered_files(dir, "frame-", kSevenScenesColor).empty()) return {dir};
  std::vector<fs::path> seqs;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_directory(ec) && entry.path().filename().string().rfind("seq-", 0) == 0 &&
        !layout::numbered_files(entry.path(), "frame-", kSevenScenesColor).empty())
      seqs.push_back(entry.path());
  std::sort(seqs.begin(), seqs.end());
  return seqs;
}

// The first .log file of `dir` or dir/scene (Open3D's reconstruction system writes
// scene/trajectory.log).
std::optional<fs::path> open3d_log(const fs::path& dir) {
  for (const fs::path& d : {dir, dir / "scene"}) {
    std::vector<fs::path> logs;
    std::error_code ec;
    if (!is_dir(d)) continue;
    for (const auto& entry : fs::directory_iterator(d, ec))
      if (entry.is_regular_file(ec) && entry.path().extension() == ".log")
        logs.push_back(entry.path());
    std::sort(logs.begin(), logs.end());
    if (!logs.empty()) return logs.front();
  }
  return std::nullopt;
}

// Frame i of `frames` is pose i of `poses`; the counts must agree.
void attach_poses_in_order(Dataset& dataset, const std::vector<std::optional<Pose>>& poses,
                           const std::string& source) {
  if (poses.size() != dataset.frames.size())
    throw InputError(source, std::to_string(poses.size()) + " poses for " +
                                 std::to_string(dataset.frames.size()) +
                                 " frames; expected one pose per frame, in frame order");
  layout::attach_poses(dataset, poses, source);
}

Dataset read_seven_scenes(const fs::path& dir, const DatasetOptions& options) {
  Dataset d;
  d.root = dir;
  d.layout = "7scenes";
  const std::vector<fs::path> folders = seven_scenes_folders(dir);
  if (folders.empty())
    throw InputError(dir.string(),
                     "no frame-XXXXXX.color.png|jpg here or in seq-NN/ subfolders; "
                     "expected a 7-Scenes sequence");
  std::vector<std::optional<Pose>> poses;
  std::size_t with_pose = 0;
  std::int64_t offset = 0;  // seq-NN/ folders follow one another in time
  for (const fs::path& folder : folders) {
    std::vector<NumberedFile> color = layout::numbered_files(folder, "frame-", kSevenScenesColor);
    std::vector<NumberedFile> depth = layout::numbered_files(folder, "frame-", {".depth.png"});
    d.rgb_rows += color.size();
    d.depth_rows += depth.size();
    for (auto* files : {&color, &depth})
      for (NumberedFile& f : *files) f.number += offset;
    for (FramePair& f : layout::pair_by_number(color, depth, options.fps)) {
      std::string name = f.rgb_file.filename().string();
      name = name.substr(0, name.find('.')) + ".pose.txt";
      const fs::path pose_file = f.rgb_file.parent_path() / name;
      if (is_file(pose_file)) {
        poses.push_back(
            layout::pose_from_numbers(layout::read_numbers(pose_file), pose_file.string()));
        ++with_pose;
      } else {
        poses.emplace_back();
      }
      d.frames.push_back(std::move(f));
    }
    offset = color.back().number + 1;
  }
  if (with_pose > 0 && with_pose < d.frames.size()) {
    const std::size_t i = std::find(poses.begin(), poses.end(), std::nullopt) - poses.begin();
    throw InputError(d.frames[i].rgb_file.string(),
                     "has no frame-XXXXXX.pose.txt beside it; expected a pose for every frame or "
                     "for none");
  }
  if (with_pose > 0)
    layout::attach_poses(d, poses, (folders.front() / "frame-*.pose.txt").string());
  // 7-Scenes publishes no calibration between its depth and colour cameras; its users take the
  // depth as registered to the colour image, with fx = fy = 585 at the image centre.
  const auto [width, height] = layout::image_size(d.frames.front().rgb_file);
  const fs::path k_file = dir / "camera-intrinsics.txt";
  if (is_file(k_file)) {
    d.camera = layout::camera_from_k_file(k_file, width, height, 1000.0);
    d.camera_source = k_file.string();
  } else {
    Camera c;
    c.fx = c.fy = 585.0;
    c.cx = 320.0;
    c.cy = 240.0;
    c.width = width;
    c.height = height;
    c.depth_factor = 1000.0;
    c.name = "7scenes";
    d.camera = c;
    d.camera_source = "7-Scenes default (fx = fy = 585, cx 320, cy 240)";
  }
  d.depth_factor = 1000.0;
  d.depth_invalid = 65535;
  return d;
}

// Replica as NICE-SLAM and iMAP distribute it: results/frameNNNNNN.jpg, results/depthNNNNNN.png,
// traj.txt (a 4x4 camera_to_world matrix per line), cam_params.json beside the scene or one folder
// up ({"camera": {"w","h","fx","fy","cx","cy","scale"}}).
Dataset read_replica(const fs::path& dir, const DatasetOptions& options) {
  Dataset d;
  d.root = dir;
  d.layout = "replica";
  const fs::path results = dir / "results";
  const auto color = layout::numbered_files(results, "frame", {".jpg", ".png"});
  const auto depth = layout::numbered_files(results, "depth", {".png"});
  if (color.empty())
    throw InputError(results.string(), "no frameNNNNNN.jpg; expected a Replica (NICE-SLAM) scene");
  d.rgb_rows = color.size();
  d.depth_rows = depth.size();
  d.frames = layout::pair_by_number(color, depth, options.fps);
  const fs::path traj = dir / "traj.txt";
  if (is_file(traj)) {
    std::vector<std::optional<Pose>> poses;
    LineReader in(traj);
    while (in.next()) {
      std::vector<double> row;
      for (std::size_t i = 0; i < in.size(); ++i) row.push_back(in.number(i, "matrix value"));
      poses.push_back(layout::pose_from_numbers(row, in.where()));
    }
    attach_poses_in_order(d, poses, traj.string());
  }
  double fx = 600.0, fy = 600.0, cx = 599.5, cy = 339.5, scale = 6553.5;
  d.camera_source =
      "NICE-SLAM's Replica defaults (fx = fy = 600, cx 599.5, cy 339.5, scale 6553.5)";
  for (const fs::path& file : {dir / "cam_params.json", dir.parent_path() / "cam_params.json"}) {
    if (!is_file(file)) continue;
    const nlohmann::json doc = read_json_file(file, "cannot open");
    const std::string where = file.string() + ": camera";
    if (!doc.is_object() || !doc.contains("camera") || !doc["camera"].is_object())
      throw InputError(where,
                       "missing; expected {\"camera\": {\"fx\", \"fy\", \"cx\", \"cy\", "
                       "\"scale\", ...}}");
    const nlohmann::json& cam = doc["camera"];
    auto number = [&](const char* key, double& value) {
      if (!cam.contains(key)) return;
      if (!cam[key].is_number() || !std::isfinite(cam[key].get<double>()))
        throw InputError(where + "." + key, "is not a finite number");
      value = cam[key].get<double>();
    };
    number("fx", fx);
    number("fy", fy);
    number("cx", cx);
    number("cy", cy);
    number("scale", scale);
    d.camera_source = file.string();
    break;
  }
  const auto [width, height] = layout::image_size(d.frames.front().rgb_file);
  Camera c;
  c.name = d.camera_source;
  c.fx = fx;
  c.fy = fy;
  c.cx = cx;
  c.cy = cy;
  c.width = width;
  c.height = height;
  c.depth_factor = scale;
  c.check(d.camera_source);
  d.camera = c;
  d.depth_factor = scale;
  return d;
}

}  // namespace

// The error for a path that is neither a recording folder nor a bag.
void require_folder(const fs::path& dir) {
  if (!is_dir(dir))
    throw InputError(dir.string(), is_file(dir) ? "is a file and not a ROS 1 bag; expected a "
                                                  "recording folder or a .bag"
                                                : "folder not found");
}

std::string detect_layout(const fs::path& dir) {
  if (is_rosbag_file(dir)) return "rosbag";
  require_folder(dir);
  if (is_file(dir / "objmap_layout.json")) return "generic";
  if (is_file(dir / "rgb.txt") && is_file(dir / "depth.txt")) return "tum";
  if (!seven_scenes_folders(dir).empty()) return "7scenes";
  if (is_dir(dir / "color") && is_dir(dir / "depth") && is_dir(dir / "pose") &&
      is_dir(dir / "intrinsic"))
    return "scannet";
  if (is_dir(dir / "results") && is_file(dir / "traj.txt")) return "replica";
  if (is_dir(dir / "color") && is_dir(dir / "depth") && open3d_log(dir)) return "open3d";
  throw InputError(
      dir.string(),
      "no known dataset layout; looked for objmap_layout.json (generic), rgb.txt + "
      "depth.txt (tum), frame-XXXXXX.color.png (7scenes, also in seq-NN/), color/ "
      "depth/ pose/ intrinsic/ (scannet), results/ + traj.txt (replica), color/ "
      "depth/ + a .log trajectory (open3d), or give a ROS 1 .bag file (rosbag); --layout names "
      "one");
}

bool is_tum_listing(const fs::path& dir, const std::string& layout) {
  if (layout == "tum") return true;
  return layout == "auto" && !is_file(dir / "objmap_layout.json") && is_file(dir / "rgb.txt");
}

Dataset read_dataset(const fs::path& dir, const DatasetOptions& options) {
  options.check();
  if (options.layout == "rosbag" || (options.layout == "auto" && is_rosbag_file(dir)))
    return read_rosbag(dir, options);
  require_folder(dir);
  if (fs::path(options.layout).extension() == ".json")
    return layout::read_generic(dir, options.layout, options);
  const std::string name = options.layout == "auto" ? detect_layout(dir) : options.layout;
  if (name == "tum") {
    TumOptions tum;
    tum.max_diff_s = options.max_diff_s;
    Dataset d = read_tum_dataset(dir, tum);
    d.layout = "tum";
    return d;
  }
  if (name == "7scenes") return read_seven_scenes(dir, options);
  if (name == "replica") return read_replica(dir, options);
  if (name == "open3d") return layout::read_open3d(dir, open3d_log(dir), options);
  if (name == "scannet") return layout::read_scannet(dir, options);
  if (name == "generic") return layout::read_generic(dir, dir / "objmap_layout.json", options);
  throw InputError(dir.string(), "the " + name + " layout is not read by this build of objmap");
}

}  // namespace objmap::io
