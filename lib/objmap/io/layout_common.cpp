#include "objmap/io/layout_common.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <system_error>

#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "objmap/io/text_lines.h"

namespace objmap::io::layout {

namespace fs = std::filesystem;

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string fixed(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

}  // namespace

std::vector<NumberedFile> numbered_files(const fs::path& dir, const std::string& prefix,
                                         const std::vector<std::string>& suffixes) {
  std::vector<NumberedFile> files;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return files;
  std::map<std::int64_t, fs::path> by_number;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    for (const std::string& suffix : suffixes) {
      if (!ends_with(name, suffix) || name.size() <= prefix.size() + suffix.size()) continue;
      const std::string digits =
          name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
      if (digits.size() > 12 || !std::all_of(digits.begin(), digits.end(),
                                             [](unsigned char c) { return std::isdigit(c); }))
        continue;
      const std::int64_t number = std::stoll(digits);
      const auto [it, fresh] = by_number.emplace(number, entry.path());
      if (!fresh)
        throw InputError(entry.path().string(), "has the frame number of " + it->second.string() +
                                                    "; expected one file per frame number");
      break;
    }
  }
  for (auto& [number, file] : by_number) files.push_back({number, file});
  return files;
}

std::optional<std::int64_t> number_in_name(const std::string& name) {
  const std::string stem = fs::path(name).stem().string();
  std::size_t end = stem.size();
  while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
  std::size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  if (begin == end || end - begin > 12) return std::nullopt;
  return std::stoll(stem.substr(begin, end - begin));
}

std::vector<double> read_numbers(const fs::path& file) {
  LineReader in(file);
  std::vector<double> numbers;
  while (in.next()) {
    for (std::size_t i = 0; i < in.size(); ++i) {
      std::string f = in.field(i);
      std::transform(f.begin(), f.end(), f.begin(),
                     [](unsigned char c) { return std::tolower(c); });
      if (f == "inf" || f == "+inf")
        numbers.push_back(std::numeric_limits<double>::infinity());
      else if (f == "-inf")
        numbers.push_back(-std::numeric_limits<double>::infinity());
      else if (f == "nan" || f == "-nan")
        numbers.push_back(std::numeric_limits<double>::quiet_NaN());
      else
        numbers.push_back(in.number(i, "value " + std::to_string(numbers.size() + 1)));
    }
  }
  return numbers;
}

std::optional<Pose> pose_from_numbers(const std::vector<double>& numbers,
                                      const std::string& where) {
  if (numbers.size() != 16 && numbers.size() != 12)
    throw InputError(where, std::to_string(numbers.size()) +
                                " numbers; expected a 4x4 matrix (16 numbers, row-major) or its "
                                "first three rows (12)");
  if (!std::all_of(numbers.begin(), numbers.end(), [](double v) { return std::isfinite(v); }))
    return std::nullopt;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  for (int i = 0; i < static_cast<int>(numbers.size()); ++i) m(i / 4, i % 4) = numbers[i];
  if (numbers.size() == 16 &&
      (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
    throw InputError(where, "last row is not 0 0 0 1; expected a rigid 4x4 pose matrix");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d nearest = svd.matrixU() * svd.matrixV().transpose();
  const double off = (r - nearest).cwiseAbs().maxCoeff();
  if (nearest.determinant() < 0 || off > 1e-2)
    throw InputError(where, "rotation part is not a rotation (off by " + fixed(off) +
                                (nearest.determinant() < 0 ? ", a reflection" : "") +
                                "); expected a rigid world_from_camera matrix");
  Pose pose = Pose::Identity();
  pose.linear() = nearest;
  pose.translation() = m.topRightCorner<3, 1>();
  return pose;
}

Camera camera_from_k_file(const fs::path& file, int width, int height, double depth_factor) {
  const std::vector<double> k = read_numbers(file);
  const int n = k.size() == 9 ? 3 : k.size() == 16 ? 4 : 0;
  if (n == 0)
    throw InputError(file.string(), std::to_string(k.size()) +
                                        " numbers; expected a 3x3 intrinsic matrix (or 4x4)");
  Camera camera;
  camera.name = file.string();
  camera.fx = k[0];
  camera.cx = k[2];
  camera.fy = k[n + 1];
  camera.cy = k[n + 2];
  camera.width = width;
  camera.height = height;
  camera.depth_factor = depth_factor;
  camera.check(file.string());
  return camera;
}

std::pair<int, int> image_size(const fs::path& file) {
  const cv::Mat image = read_image(file, /*allow_jpeg=*/true);
  return {image.cols, image.rows};
}

std::vector<FramePair> pair_by_number(const std::vector<NumberedFile>& color,
                                      const std::vector<NumberedFile>& depth, double fps) {
  std::vector<FramePair> frames;
  std::size_t j = 0;
  for (const NumberedFile& c : color) {
    while (j < depth.size() && depth[j].number < c.number) ++j;
    if (j == depth.size() || depth[j].number != c.number)
      throw InputError(c.file.string(), "has no depth image of frame number " +
                                            std::to_string(c.number) +
                                            "; expected one depth image per colour image");
    const double t = static_cast<double>(c.number) / fps;
    frames.push_back({t, t, c.file, depth[j].file});
  }
  return frames;
}

std::vector<FramePair> pair_in_order(const std::vector<NumberedFile>& color,
                                     const std::vector<NumberedFile>& depth,
                                     const std::function<double(const NumberedFile&)>& time_of) {
  if (color.size() != depth.size()) {
    const std::size_t n = std::min(color.size(), depth.size());
    const fs::path& lone = color.size() > n ? color[n].file : depth[n].file;
    throw InputError(lone.string(), std::to_string(color.size()) + " colour and " +
                                        std::to_string(depth.size()) +
                                        " depth images; expected one depth image per colour "
                                        "image (this one has no partner)");
  }
  std::vector<FramePair> frames;
  for (std::size_t i = 0; i < color.size(); ++i) {
    const double t = time_of(color[i]);
    if (!frames.empty() && t <= frames.back().rgb_timestamp)
      throw InputError(color[i].file.string(), "timestamp not after the previous frame's");
    frames.push_back({t, t, color[i].file, depth[i].file});
  }
  return frames;
}

void attach_poses(Dataset& dataset, const std::vector<std::optional<Pose>>& poses,
                  const std::string& source) {
  std::vector<FramePair> kept;
  dataset.poses = {};
  dataset.poses.source = source;
  for (std::size_t i = 0; i < dataset.frames.size(); ++i) {
    if (!poses[i]) {
      ++dataset.lost_poses;
      continue;
    }
    kept.push_back(dataset.frames[i]);
    dataset.poses.poses.push_back({dataset.frames[i].rgb_timestamp, *poses[i], 0});
  }
  if (kept.empty())
    throw InputError(source, "no frame has a valid pose (" + std::to_string(dataset.lost_poses) +
                                 " marked lost); expected finite 4x4 matrices");
  dataset.frames = std::move(kept);
}

}  // namespace objmap::io::layout
