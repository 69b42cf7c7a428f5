#include "objmap/io/trajectory.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iterator>
#include <limits>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/io/text_lines.h"

namespace objmap::io {

namespace {

constexpr const char* kLayout = "timestamp tx ty tz qx qy qz qw";

// Shortest fixed-notation text that reads back to the same double (C++17 to_chars): never
// scientific, so TUM tools read "1700000000" rather than "1.7e+09".
void append_number(std::string& out, double value) {
  char buffer[64];
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed);
  out.append(buffer, result.ptr);
}

std::string shortest(double value) {
  std::string s;
  append_number(s, value);
  return s;
}

using Vec4 = Eigen::Vector4d;  // a quaternion as x y z w

// Radius of the exhaustive search in quaternion_of, in ulps per component: 1 is 81 candidates; 2
// (625) makes ~30% of the remaining misses exact but multiplies the cost of writing rotations that
// did not come from a quaternion by ~10.
constexpr int kSearchRadius = 1;

// A unit double quaternion: q itself when it is unit to double precision already (so that what the
// writer wrote is taken as is), else q / |q| computed in extended precision.
Vec4 normalised(const Vec4& q) {
  if (std::abs(q.squaredNorm() - 1.0) <= 8 * std::numeric_limits<double>::epsilon()) return q;
  Eigen::Quaternion<long double> q_ext(q[3], q[0], q[1], q[2]);
  q_ext.normalize();
  return q_ext.coeffs().cast<double>();
}

// The rotation matrix of a unit quaternion, computed in extended precision and rounded.
Eigen::Matrix3d rotation_of(const Vec4& q) {
  const Eigen::Quaternion<long double> q_ext(q[3], q[0], q[1], q[2]);
  return q_ext.toRotationMatrix().cast<double>();
}

// q moved by `ulps` units in the last place in component i.
Vec4 step(Vec4 q, int i, int ulps) {
  for (int k = 0; k < std::abs(ulps); ++k) q[i] = std::nextafter(q[i], ulps < 0 ? -2.0 : 2.0);
  return q;
}

}  // namespace

Pose pose_from_tum(double tx, double ty, double tz, double qx, double qy, double qz, double qw) {
  Pose pose = Pose::Identity();
  pose.linear() = rotation_of(normalised(Vec4(qx, qy, qz, qw)));
  pose.translation() = Vec3(tx, ty, tz);
  return pose;
}

Eigen::Quaterniond quaternion_of(const Pose& pose) {
  const Eigen::Matrix3d rotation = pose.linear();
  Eigen::Quaternion<long double> q_ext(
      Eigen::Matrix<long double, 3, 3>(rotation.cast<long double>()));
  q_ext.normalize();
  if (q_ext.w() < 0) q_ext.coeffs() = -q_ext.coeffs();
  Vec4 q = q_ext.coeffs().cast<double>();  // the nearest doubles
  // A rotation read from a file is rotation_of(some double unit quaternion), which is near q but
  // not always q itself. Look for it so that write -> read gives back the same matrix, bit for
  // bit: first a descent one ulp at a time on the distance between the matrices, then every
  // quaternion within kSearchRadius ulps per component. A rotation that no double quaternion gives
  // exactly is written as the best quaternion found (within ~1e-16 of it).
  auto distance = [&rotation](const Vec4& c) {
    return (rotation_of(c) - rotation).cwiseAbs().sum();
  };
  double best = distance(q);
  for (int round = 0; round < 32 && best > 0.0; ++round) {
    Vec4 best_q = q;
    for (int i = 0; i < 4; ++i)
      for (int ulps : {-1, 1}) {
        const Vec4 c = step(q, i, ulps);
        if (const double d = distance(c); d < best) {
          best = d;
          best_q = c;
        }
      }
    if (best_q == q) break;  // local minimum
    q = best_q;
  }
  for (int radius = 1; radius <= kSearchRadius && best > 0.0; ++radius) {
    const int side = 2 * radius + 1;
    for (int code = 0; code < side * side * side * side; ++code) {
      Vec4 c = q;
      for (int i = 0, k = code; i < 4; ++i, k /= side) c = step(c, i, k % side - radius);
      if (rotation_of(c) == rotation) return Eigen::Quaterniond(c[3], c[0], c[1], c[2]);
    }
  }
  return Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
}

Trajectory read_trajectory(const std::filesystem::path& file) {
  Trajectory trajectory;
  trajectory.source = file.string();
  LineReader in(file);
  std::size_t previous_line = 0;
  while (in.next()) {
    in.expect_fields(8, kLayout);
    static const char* kNames[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
    double v[8];
    for (int i = 0; i < 8; ++i) v[i] = in.number(i, kNames[i]);
    const double norm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
    if (!(std::abs(norm - 1.0) <= kMaxQuaternionNormError))
      throw InputError(in.where(), "quaternion (qx qy qz qw) has norm " + shortest(norm) +
                                       "; expected a unit quaternion (norm within " +
                                       shortest(kMaxQuaternionNormError) + " of 1)");
    if (!trajectory.poses.empty()) {
      const double before = trajectory.poses.back().timestamp;
      if (v[0] == before) {
        // TUM's own tools read a trajectory into a dictionary: a later line with the same stamp
        // replaces the earlier one (freiburg2_desk's groundtruth has one such pair).
        trajectory.warnings.push_back(in.where() + ": timestamp " + in.field(0) + " repeats line " +
                                      std::to_string(previous_line) +
                                      "; this later pose is used, as the TUM benchmark's tools do");
        trajectory.poses.back().world_from_cam =
            pose_from_tum(v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
        trajectory.poses.back().line = in.line_number();
        previous_line = in.line_number();
        continue;
      }
      if (v[0] < before)
        throw InputError(in.where(), "timestamp " + in.field(0) + " is before " + shortest(before) +
                                         " of line " + std::to_string(previous_line) +
                                         "; expected strictly increasing timestamps");
    }
    previous_line = in.line_number();
    trajectory.poses.push_back(
        {v[0], pose_from_tum(v[1], v[2], v[3], v[4], v[5], v[6], v[7]), in.line_number()});
  }
  if (trajectory.poses.empty())
    throw InputError(file.string(),
                     "no pose in the file; expected lines '" + std::string(kLayout) + "'");
  return trajectory;
}

std::string format_trajectory(const Trajectory& trajectory, const std::string& header_comment) {
  std::string out;
  out.reserve(trajectory.size() * 120 + header_comment.size() + 64);
  if (!header_comment.empty()) {
    std::istringstream lines(header_comment);
    std::string line;
    while (std::getline(lines, line)) out += line.empty() ? "#\n" : "# " + line + "\n";
  }
  out += "# " + std::string(kLayout) + "\n";
  for (const StampedPose& p : trajectory.poses) {
    const Vec3 t = p.world_from_cam.translation();
    const Eigen::Quaterniond q = quaternion_of(p.world_from_cam);
    const double values[8] = {p.timestamp, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
    for (int i = 0; i < 8; ++i) {
      if (i > 0) out += ' ';
      append_number(out, values[i]);
    }
    out += '\n';
  }
  return out;
}

void write_trajectory(const std::filesystem::path& file, const Trajectory& trajectory,
                      const std::string& header_comment) {
  write_file_atomic(file, format_trajectory(trajectory, header_comment));
}

void PoseLookupOptions::check() const {
  require(std::isfinite(max_diff_s) && max_diff_s >= 0.0, "PoseLookupOptions.max_diff_s",
          "is " + shortest(max_diff_s) + "; expected a finite number of seconds >= 0");
}

std::optional<Pose> lookup_pose(const Trajectory& trajectory, double timestamp,
                                const PoseLookupOptions& options) {
  options.check();
  require(std::isfinite(timestamp), "lookup_pose", "timestamp is not finite");
  const auto& poses = trajectory.poses;
  if (poses.empty()) return std::nullopt;
  // First pose at or after t, and the one before it.
  const auto after =
      std::lower_bound(poses.begin(), poses.end(), timestamp,
                       [](const StampedPose& p, double t) { return p.timestamp < t; });
  if (after != poses.end() && after->timestamp == timestamp) return after->world_from_cam;
  const StampedPose* next = after != poses.end() ? &*after : nullptr;
  const StampedPose* prev = after != poses.begin() ? &*std::prev(after) : nullptr;
  const bool prev_ok = prev && timestamp - prev->timestamp <= options.max_diff_s;
  const bool next_ok = next && next->timestamp - timestamp <= options.max_diff_s;
  if (options.interpolate && prev_ok && next_ok) {
    const double s = (timestamp - prev->timestamp) / (next->timestamp - prev->timestamp);
    const Eigen::Quaterniond qa(prev->world_from_cam.linear());
    const Eigen::Quaterniond qb(next->world_from_cam.linear());
    Pose pose = Pose::Identity();
    pose.linear() = qa.slerp(s, qb).normalized().toRotationMatrix();  // slerp takes the short arc
    pose.translation() =
        (1.0 - s) * prev->world_from_cam.translation() + s * next->world_from_cam.translation();
    return pose;
  }
  if (prev_ok && next_ok)  // nearest; the earlier one on a tie
    return (timestamp - prev->timestamp <= next->timestamp - timestamp) ? prev->world_from_cam
                                                                        : next->world_from_cam;
  if (prev_ok) return prev->world_from_cam;
  if (next_ok) return next->world_from_cam;
  return std::nullopt;
}

}  // namespace objmap::io
