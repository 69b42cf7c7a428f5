#include "objmap/io/camera_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <system_error>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/io/library_errors.h"
#include "objmap/io/tum_dataset.h"

namespace objmap::io {

namespace fs = std::filesystem;

namespace {

const char* const kDistortionNames[5] = {"k1", "k2", "p1", "p2", "k3"};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string extension_of(const fs::path& file) { return lower(file.extension().string()); }

// ---- JSON ----

double json_number(const nlohmann::json& j, const std::string& key, const std::string& file) {
  const auto& v = j.at(key);
  if (!v.is_number()) throw InputError(file + ": " + key, "is " + v.dump() + "; expected a number");
  return v.get<double>();
}

int json_size(const nlohmann::json& j, const std::string& key, const std::string& file) {
  const auto& v = j.at(key);
  // The range before the cast: a double outside int's range (1e300) has no int value.
  const double d = v.is_number() ? v.get<double>() : 0.0;
  const bool whole = d > 0 && d <= 1e6 && d == std::floor(d);
  if (!whole)
    throw InputError(file + ": " + key,
                     "is " + v.dump() + "; expected a whole number of pixels > 0");
  return static_cast<int>(v.get<double>());
}

Camera read_camera_json(const fs::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(file, "cannot open the camera file for reading");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, std::string("not valid JSON (") + e.what() + ")");
  }
  if (!j.is_object()) throw InputError(file, "expected a JSON object {\"fx\": .., ...}");
  static const std::set<std::string> kKnown = {
      "fx", "fy", "cx", "cy", "width",        "height", "distortion", "k1",
      "k2", "p1", "p2", "k3", "depth_factor", "name",   "$schema"};
  for (const auto& item : j.items())
    if (!kKnown.count(item.key()))
      throw InputError(file + ": " + item.key(),
                       "unknown field; expected fx fy cx cy width height, optional distortion "
                       "(or k1 k2 p1 p2 k3), depth_factor, name");
  for (const char* key : {"fx", "fy", "cx", "cy", "width", "height"})
    if (!j.contains(key)) throw InputError(file + ": " + key, "missing; it is required");

  Camera camera;
  camera.name = file;
  camera.fx = json_number(j, "fx", file);
  camera.fy = json_number(j, "fy", file);
  camera.cx = json_number(j, "cx", file);
  camera.cy = json_number(j, "cy", file);
  camera.width = json_size(j, "width", file);
  camera.height = json_size(j, "height", file);
  if (j.contains("distortion")) {
    const auto& d = j.at("distortion");
    if (!d.is_array() || d.size() != 5)
      throw InputError(file + ": distortion",
                       "is " + d.dump() + "; expected an array of 5 numbers [k1, k2, p1, p2, k3]");
    for (std::size_t i = 0; i < 5; ++i) {
      if (!d[i].is_number())
        throw InputError(file + ": distortion", "element " + std::to_string(i) + " is " +
                                                    d[i].dump() + "; expected a number");
      camera.distortion[i] = d[i].get<double>();
    }
  }
  for (int i = 0; i < 5; ++i) {
    if (!j.contains(kDistortionNames[i])) continue;
    if (j.contains("distortion"))
      throw InputError(file + ": " + kDistortionNames[i],
                       "given together with \"distortion\"; expected one of the two");
    camera.distortion[i] = json_number(j, kDistortionNames[i], file);
  }
  if (j.contains("depth_factor")) camera.depth_factor = json_number(j, "depth_factor", file);
  if (j.contains("name")) {
    if (!j.at("name").is_string())
      throw InputError(file + ": name", "is " + j.at("name").dump() + "; expected a string");
    camera.name = j.at("name").get<std::string>();
  }
  return camera;
}

// ---- ORB-SLAM2 YAML ----

double yaml_number(const cv::FileStorage& fs, const std::string& key, const std::string& file,
                   bool required, double fallback) {
  const cv::FileNode node = fs[key];
  if (node.empty() || node.isNone()) {
    if (required) throw InputError(file + ": " + key, "missing; it is required");
    return fallback;
  }
  if (!node.isReal() && !node.isInt())
    throw InputError(file + ": " + key, "is not a number; expected a number");
  return node.real();
}

Camera camera_from_yaml(const cv::FileStorage& storage, const std::string& file) {
  Camera camera;
  camera.name = file;
  camera.fx = yaml_number(storage, "Camera.fx", file, true, 0);
  camera.fy = yaml_number(storage, "Camera.fy", file, true, 0);
  camera.cx = yaml_number(storage, "Camera.cx", file, true, 0);
  camera.cy = yaml_number(storage, "Camera.cy", file, true, 0);
  for (int i = 0; i < 5; ++i)
    camera.distortion[i] =
        yaml_number(storage, std::string("Camera.") + kDistortionNames[i], file, false, 0.0);
  for (auto [key, target] : {std::pair<const char*, int*>{"Camera.width", &camera.width},
                             std::pair<const char*, int*>{"Camera.height", &camera.height}}) {
    const double v = yaml_number(storage, key, file, false, *target);
    if (!(v > 0 && v <= 1e6 && v == static_cast<int>(v)))
      throw InputError(file + ": " + key,
                       "is " + std::to_string(v) + "; expected a whole number of pixels > 0");
    *target = static_cast<int>(v);
  }
  camera.depth_factor = yaml_number(storage, "DepthMapFactor", file, false, 5000.0);
  return camera;
}

// OpenCV's FileStorage throws cv::Exception on a malformed file, in its parser and in the
// assertions of its lookups; read_camera_file names the file of any that this does not.
Camera read_camera_yaml(const fs::path& path) {
  const std::string file = path.string();
  cv::FileStorage storage;
  try {
    if (!storage.open(file, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML))
      throw InputError(file, "cannot open the camera file for reading");
  } catch (const cv::Exception& e) {
    // OpenCV's own message (its `err` part: "Incorrect indentation" and where), on one line.
    std::string reason = e.err;
    std::replace(reason.begin(), reason.end(), '\n', ' ');
    while (!reason.empty() && reason.back() == ' ') reason.pop_back();
    throw InputError(file, "not a readable OpenCV YAML file (" + reason +
                               "); expected ORB-SLAM2 settings starting with %YAML:1.0");
  }
  // A top level that is a sequence or a single value has no keys (a lookup asserts); an empty
  // file is a mapping without any (Camera.fx is missing).
  const cv::FileNode root = storage.root();
  if (!root.isNone() && !root.isMap())
    throw InputError(file, std::string("the top level is ") +
                               (root.isSeq() ? "a sequence" : "a single value") +
                               ", not a mapping; expected ORB-SLAM2 settings (Camera.fx: ...)");
  return camera_from_yaml(storage, file);
}

}  // namespace

Camera read_camera_file(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw InputError(file.string(), "camera file not found");
  if (!fs::is_regular_file(file, ec)) throw InputError(file.string(), "is not a file");
  const std::string ext = extension_of(file);
  Camera camera;
  try {
    if (ext == ".json")
      camera = read_camera_json(file);
    else if (ext == ".yaml" || ext == ".yml")
      camera = read_camera_yaml(file);
    else
      throw InputError(file.string(), "unknown camera file type '" + ext +
                                          "'; expected .json or ORB-SLAM2 settings .yaml/.yml");
  } catch (...) {
    rethrow_naming_file(file.string());
  }
  camera.check(file.string());
  return camera;
}

std::string camera_json(const Camera& camera) {
  nlohmann::ordered_json j;
  j["name"] = camera.name;
  j["width"] = camera.width;
  j["height"] = camera.height;
  j["fx"] = camera.fx;
  j["fy"] = camera.fy;
  j["cx"] = camera.cx;
  j["cy"] = camera.cy;
  j["distortion"] = camera.distortion;
  j["depth_factor"] = camera.depth_factor;
  return j.dump(2) + "\n";
}

void write_camera_json(const fs::path& file, const Camera& camera) {
  camera.check(file.string());
  write_file_atomic(file, camera_json(camera));
}

std::string preset_from_name(const std::string& name) {
  static const std::regex kFreiburg("freiburg([123])");
  static const std::regex kFr("(^|[^a-z0-9])fr([123])($|[^0-9])");
  const std::string s = lower(name);
  std::smatch m;
  if (std::regex_search(s, m, kFreiburg)) return "fr" + m[1].str();
  if (std::regex_search(s, m, kFr)) return "fr" + m[2].str();
  return "";
}

CameraChoice choose_camera(const fs::path& dataset_dir, const std::string& camera_arg) {
  std::error_code ec;
  if (!camera_arg.empty()) {
    static const std::set<std::string> kPresets = {"fr1",       "fr2",       "fr3",
                                                   "freiburg1", "freiburg2", "freiburg3"};
    if (kPresets.count(camera_arg))
      return {camera_preset(camera_arg),
              "preset " + camera_preset(camera_arg).name + " (--camera)"};
    if (!fs::exists(camera_arg, ec))
      throw InputError("--camera", "'" + camera_arg +
                                       "' is neither a preset (fr1, fr2, fr3, freiburg1..3) nor "
                                       "an existing camera file (.json, .yaml)");
    return {read_camera_file(camera_arg), "file " + camera_arg + " (--camera)"};
  }
  const fs::path in_dataset = dataset_dir / "camera.json";
  if (fs::exists(in_dataset, ec))
    return {read_camera_file(in_dataset), "file " + in_dataset.string() + " in the dataset"};

  fs::path dir = dataset_dir;
  if (!dir.has_filename()) dir = dir.parent_path();  // "fr1_desk_9/"
  if (dir.filename() == "." || dir.filename() == ".." || dir.empty())
    dir = fs::weakly_canonical(fs::absolute(dir), ec);
  const std::string folder = dir.filename().string();
  if (const std::string preset = preset_from_name(folder); !preset.empty())
    return {camera_preset(preset), "preset " + preset + " from the folder name '" + folder + "'"};

  const std::string recorded = recorded_from_header(dataset_dir / "rgb.txt");
  if (const std::string preset = preset_from_name(recorded); !preset.empty())
    return {camera_preset(preset),
            "preset " + preset + " from rgb.txt's header \"# file: '" + recorded + "'\""};

  throw InputError(dataset_dir.string(),
                   "cannot tell the camera: no camera.json, and neither the folder name nor "
                   "rgb.txt's '# file:' header names freiburg1..3; pass --camera fr1|fr2|fr3 or a "
                   "camera file (.json, ORB-SLAM2 .yaml)");
}

CameraChoice choose_camera(const Dataset& dataset, const std::string& camera_arg) {
  CameraChoice choice;
  if (camera_arg.empty() && dataset.camera) {
    choice = {*dataset.camera,
              "the " + dataset.layout + " layout's camera (" + dataset.camera_source + ")"};
  } else {
    choice = choose_camera(dataset.root, camera_arg);
  }
  // The layout fixes the depth units (7-Scenes millimetres, Replica 1/6553.5 m, ...).
  if (dataset.depth_factor > 0 && choice.camera.depth_factor != dataset.depth_factor) {
    choice.camera.depth_factor = dataset.depth_factor;
    choice.reason += "; depth factor " + nlohmann::json(dataset.depth_factor).dump() + " of the " +
                     dataset.layout + " layout";
  }
  return choice;
}

}  // namespace objmap::io
