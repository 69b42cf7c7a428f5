#pragma once
#include <filesystem>
#include <string>

#include "objmap/core/camera.h"
#include "objmap/io/dataset.h"

// Camera files: objmap's JSON (schemas/camera.schema.json) and ORB-SLAM2 settings YAML.
namespace objmap::io {

// Reads a camera by the file's extension:
//  - .json: {"fx","fy","cx","cy","width","height"} required; optional "distortion":
//  [k1,k2,p1,p2,k3]
//    or any of "k1","k2","p1","p2","k3" (not both), "depth_factor" (default 5000), "name" (default:
//    the file path), "$schema". Any other field is an error (catches typos).
//  - .yaml/.yml: ORB-SLAM2 settings (read with cv::FileStorage; "%YAML:1.0" first line):
//    Camera.fx/fy/cx/cy required; Camera.k1 k2 p1 p2 (k3) default 0; Camera.width/height default
//    640x480; DepthMapFactor default 5000 (metres = value / DepthMapFactor, as ORB-SLAM2 does).
// Throws InputError("<file>: <field>", ...) for a missing or non-numeric field, and when the result
// fails Camera::check (non-positive focal length, size or depth factor).
Camera read_camera_file(const std::filesystem::path& file);

// Writes `camera` as JSON (the format read above, distortion as an array), atomically.
void write_camera_json(const std::filesystem::path& file, const Camera& camera);
// The JSON text written by write_camera_json.
std::string camera_json(const Camera& camera);

struct CameraChoice {
  Camera camera;
  std::string reason;  // e.g. "preset fr1 from the folder name 'fr1_desk_9'"
};

// The camera of a run. `camera_arg` (the --camera option) is empty, a preset name (fr1, fr2, fr3,
// freiburg1..3) or a camera file. When it is empty, in order: <dataset_dir>/camera.json if present;
// else the preset named by the dataset folder's name (freiburg1..3 or fr1..fr3); else the preset
// named by rgb.txt's "# file: 'rgbd_dataset_freiburgN_...'" header; else InputError asking for
// --camera.
CameraChoice choose_camera(const std::filesystem::path& dataset_dir, const std::string& camera_arg);

// The camera of a run on `dataset`: `camera_arg` when given; else the layout's own camera where it
// has one (7scenes, scannet, replica, open3d, generic); else as above on the folder. A layout that
// fixes its depth units sets the depth factor whatever the camera's source.
CameraChoice choose_camera(const Dataset& dataset, const std::string& camera_arg);

// "fr1".."fr3" when `name` contains freiburg1..3 or fr1..fr3 as a word part (case-insensitive;
// "fr1_desk_9", "rgbd_dataset_freiburg3_cabinet"), else "".
std::string preset_from_name(const std::string& name);

}  // namespace objmap::io
