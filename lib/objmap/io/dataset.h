#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/core/camera.h"
#include "objmap/core/trajectory.h"

// A recording in one of the layouts of the field (docs/formats.md "Dataset layouts"), read as it
// is: its frames (colour, depth, timestamp), its camera where it has one, and its own camera poses
// where it carries them.
namespace objmap::io {

struct FramePair {
  double rgb_timestamp = 0;
  double depth_timestamp = 0;
  // The image files; for frames inside a container file (a ROS bag) names of the form
  // `<bag>:<topic>@<stamp>`, for messages only.
  std::filesystem::path rgb_file, depth_file;
  std::size_t source_index = 0;  // the frame's index in Dataset::source, where there is one
};

// The frames of a recording kept inside one container file (the rosbag layout), decoded on
// request by their FramePair::source_index. Safe to call from several threads.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual cv::Mat color(std::size_t index) const = 0;  // CV_8UC3, BGR
  virtual cv::Mat depth(std::size_t index) const = 0;  // CV_16UC1 in Dataset::depth_factor units
};

struct Dataset {
  std::filesystem::path root;
  std::string layout = "tum";                // the layout it was read as (kLayouts)
  std::vector<FramePair> frames;             // sorted by strictly increasing rgb timestamp
  std::size_t rgb_rows = 0, depth_rows = 0;  // colour and depth images listed or found
  std::string recorded_from;  // tum: rgb.txt's "# file: '<name>'" header; empty when there is none
  // The camera the layout describes (its intrinsics file, its image size, its depth scale), with
  // the file it came from; nullopt where the layout has none (tum: camera.json, presets).
  std::optional<Camera> camera;
  std::string camera_source;
  // Depth units per metre that the layout fixes (7scenes, scannet, open3d: 1000; replica: 6553.5;
  // generic: depth_scale); 0 where the camera's depth_factor decides (tum).
  double depth_factor = 0.0;
  // A raw depth value that means "no depth" besides 0 (7scenes: 65535); 0 for none.
  std::uint16_t depth_invalid = 0;
  // The layout's own camera poses (world_from_cam), one per frame that has a valid one, stamped
  // with the frame's rgb timestamp; empty where the layout carries none. poses.source names the
  // files.
  Trajectory poses;
  std::size_t lost_poses = 0;  // frames dropped because their pose marks lost tracking
  // Where depth comes from another camera than colour (scannet): that camera and the colour
  // camera's pose in it; read_frame_depth maps each depth pixel into the colour image.
  struct DepthCamera {
    Camera camera;
    Pose color_from_depth = Pose::Identity();
  };
  std::optional<DepthCamera> depth_camera;
  std::string topics;  // rosbag: the "COLOR,DEPTH" image topics read
  // Where the frames are not image files (rosbag): what reads them. Null for image files.
  std::shared_ptr<const FrameSource> source;
};

// The layouts read_dataset knows, in the order detect_layout tries them.
extern const std::vector<std::string> kLayouts;

struct DatasetOptions {
  std::string layout = "auto";  // auto (detected from the folder's contents) or one of kLayouts,
                                // or a path to an objmap_layout.json (the generic layout)
  double max_diff_s = 0.02;     // tum: rgb and depth stamps pair when closer than this
  double fps = 30.0;            // layouts without timestamps: frame i is at i / fps seconds
  std::string topics;           // rosbag: "COLOR,DEPTH" image topics; empty = chosen from the bag
  void check() const;           // throws InputError naming the bad field
};

// The layout of `dir` from its contents (rosbag: a file that starts as a ROS 1 bag does; tum:
// rgb.txt + depth.txt; 7scenes: frame-*.color.*; scannet: color/ depth/ pose/ intrinsic/; replica:
// results/frame*.jpg + traj.txt; open3d: color/ + depth/ + a .log trajectory; generic:
// objmap_layout.json). Throws InputError naming what was looked for when none matches.
std::string detect_layout(const std::filesystem::path& dir);

// True when `file` is a regular file that starts as a ROS 1 bag ("#ROSBAG V2.0"): the rosbag
// layout, which is a file where the others are folders.
bool is_rosbag_file(const std::filesystem::path& file);

// True when `dir` is read as the tum layout (options.layout auto or tum, and rgb.txt is there):
// detect and track then take every frame rgb.txt lists, with or without a depth image.
bool is_tum_listing(const std::filesystem::path& dir, const std::string& layout);

// Reads the recording in `dir` in options.layout (detected when "auto"). Throws InputError naming
// the file, line or field for anything that does not follow the layout.
Dataset read_dataset(const std::filesystem::path& dir, const DatasetOptions& options = {});

// The colour image of `frame` as CV_8UC3 BGR, from its file or the dataset's source; width/height
// > 0 are required sizes (0 = any). Throws InputError as read_rgb does.
cv::Mat read_frame_rgb(const Dataset& dataset, const FramePair& frame, int width, int height);

// The depth image of `frame` in the colour camera `color_camera` (its size, its depth_factor): raw
// CV_16UC1 values, 0 = no depth. The layout's invalid value becomes 0; depth from another camera
// (dataset.depth_camera) is registered: each depth pixel is back-projected with the depth camera,
// moved into the colour camera and splatted over the colour pixels it covers, the nearest depth
// winning. Throws InputError as read_depth does.
cv::Mat read_frame_depth(const Dataset& dataset, const FramePair& frame,
                         const Camera& color_camera);

}  // namespace objmap::io
