// The rosbag layout (io/rosbag.h): ROS 1 bags through Debian's rosbag_storage. Built only where
// librosbag-storage-dev is found (OBJMAP_HAVE_ROSBAG); otherwise a bag is exit 2 saying so.
#include "objmap/io/rosbag.h"

#include <fstream>

#include "objmap/core/error.h"

#if OBJMAP_HAVE_ROSBAG

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <set>

#include <geometry_msgs/Transform.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float32.h>
#include <std_msgs/Header.h>
#include <tf2_msgs/TFMessage.h>

#include "objmap/io/codecs.h"
#include "objmap/io/rosbag_messages.h"
#include "objmap/io/tum_dataset.h"

#endif  // OBJMAP_HAVE_ROSBAG

namespace objmap::io {

namespace fs = std::filesystem;

bool is_rosbag_file(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return false;
  std::ifstream in(file, std::ios::binary);
  char magic[13] = {};
  in.read(magic, sizeof magic);
  return in.gcount() == 13 && std::string(magic, 13) == "#ROSBAG V2.0\n";
}

#if !OBJMAP_HAVE_ROSBAG

Dataset read_rosbag(const fs::path& bag, const DatasetOptions&) {
  throw InputError(bag.string(),
                   "is a ROS bag, and this build of objmap reads none; install "
                   "librosbag-storage-dev (make deps) and build again");
}

#else

namespace {

constexpr double kFloatDepthFactor = 5000.0;  // 32FC1 metres are kept as TUM's 16-bit units

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}
std::string without_slash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

// One image topic of the bag: its messages in stamp order (duplicates of a stamp dropped).
struct Stream {
  std::string topic;
  bool compressed = false;
  std::string encoding;  // Image: its encoding; CompressedImage: its format
  bool depth = false;    // the encoding is a depth encoding
  std::vector<rosbag::MessageInstance> messages;
  std::vector<double> stamps;
};

bool is_depth_encoding(const std::string& encoding, bool compressed) {
  const std::string e = lower(encoding);
  if (compressed)
    return contains(e, "compresseddepth") || e.rfind("16uc1", 0) == 0 ||
           e.rfind("mono16", 0) == 0 || e.rfind("32fc1", 0) == 0;
  return e == "16uc1" || e == "mono16" || e == "32fc1";
}
bool is_color_encoding(const std::string& encoding, bool compressed) {
  if (compressed) return !is_depth_encoding(encoding, true);
  const std::string e = lower(encoding);
  return e == "rgb8" || e == "bgr8" || e == "rgba8" || e == "bgra8" || e == "8uc3" || e == "mono8";
}
// Infrared streams (RealSense Infrared_N, /camera/ir/...) are never chosen automatically.
bool is_infrared(const std::string& topic) {
  const std::string t = lower(topic);
  return contains(t, "infra") || contains(t, "/ir/");
}
// The topic of a stream without the image_transport suffix of its compressed copy.
std::string base_topic(const std::string& topic) {
  for (const std::string suffix : {"/compressedDepth", "/compressed"})
    if (topic.size() > suffix.size() &&
        topic.compare(topic.size() - suffix.size(), suffix.size(), suffix) == 0)
      return topic.substr(0, topic.size() - suffix.size());
  return topic;
}

// Everything rosbag_storage throws (BagException, ros::Exception, std::exception) becomes an
// InputError naming the bag; objmap's own InputError passes through.
template <typename F>
auto guarded(const std::string& where, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(where, std::string("not a readable ROS bag: ") + e.what());
  }
}

// The first message of `topic` as T, or null (no such topic, or another type).
template <typename T>
boost::shared_ptr<T> first_message(const rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view)
    if (auto message = m.instantiate<T>()) return message;
  return nullptr;
}

// Every image topic of the bag with its encoding (from its first message) and its messages.
std::map<std::string, Stream> image_streams(const rosbag::Bag& bag) {
  std::map<std::string, Stream> streams;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections()) {
    if (c->datatype != "sensor_msgs/Image" && c->datatype != "sensor_msgs/CompressedImage")
      continue;
    Stream& s = streams[c->topic];
    s.topic = c->topic;
    s.compressed = c->datatype == "sensor_msgs/CompressedImage";
  }
  for (auto& [topic, s] : streams) {
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    std::vector<std::pair<double, std::size_t> > order;
    std::vector<rosbag::MessageInstance> messages;
    for (const rosbag::MessageInstance& m : view) {
      const auto stamp = m.instantiate<objmap_rosbag::StampOnly>();
      const double t = stamp && !stamp->header.stamp.isZero() ? stamp->header.stamp.toSec()
                                                              : m.getTime().toSec();
      order.emplace_back(t, messages.size());
      messages.push_back(m);
    }
    if (messages.empty()) continue;
    if (s.compressed) {
      if (auto first = messages.front().instantiate<objmap_rosbag::CheckedCompressedImage>())
        s.encoding = first->format;
    } else if (auto first = messages.front().instantiate<objmap_rosbag::CheckedImage>()) {
      s.encoding = first->encoding;
    }
    s.depth = is_depth_encoding(s.encoding, s.compressed);
    std::stable_sort(order.begin(), order.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [t, i] : order) {
      if (!s.stamps.empty() && t <= s.stamps.back()) continue;
      s.stamps.push_back(t);
      s.messages.push_back(messages[i]);
    }
  }
  return streams;
}

std::string topic_list(const std::vector<const Stream*>& streams) {
  std::string out;
  for (const Stream* s : streams)
    out += (out.empty() ? "" : ", ") + s->topic + " (" + s->encoding + ")";
  return out.empty() ? "none" : out;
}

// The one stream of a kind: those whose encoding fits, without infrared; a registered depth
// (aligned_depth_to_color, depth_registered) before another; a raw stream before its compressed
// copy. More than one left is an InputError listing them.
const Stream& choose_stream(const std::map<std::string, Stream>& streams, bool depth,
                            const std::string& where) {
  std::vector<const Stream*> c;
  for (const auto& [topic, s] : streams)
    if (!s.messages.empty() && !is_infrared(topic) &&
        (depth ? s.depth
               : is_color_encoding(s.encoding, s.compressed) && lower(s.encoding) != "mono8"))
      c.push_back(&s);
  const char* kind = depth ? "depth" : "colour";
  if (c.empty()) {
    std::vector<const Stream*> all;
    for (const auto& [topic, s] : streams) all.push_back(&s);
    throw InputError(where, std::string("no ") + kind +
                                " image topic; image topics in the bag: " + topic_list(all) +
                                "; expected sensor_msgs/Image or CompressedImage with a " + kind +
                                " encoding (--topics COLOR,DEPTH names them)");
  }
  if (depth && c.size() > 1) {
    std::vector<const Stream*> aligned;
    for (const Stream* s : c)
      if (contains(s->topic, "aligned_depth_to_color") || contains(s->topic, "depth_registered"))
        aligned.push_back(s);
    if (!aligned.empty()) c = aligned;
  }
  if (c.size() > 1) {
    std::vector<const Stream*> raw;
    for (const Stream* s : c)
      if (!s->compressed || !streams.count(base_topic(s->topic))) raw.push_back(s);
    c = raw;
  }
  if (c.size() > 1)
    throw InputError(where, std::string("more than one ") + kind + " image topic: " +
                                topic_list(c) + "; expected one (--topics COLOR,DEPTH names them)");
  return *c.front();
}

// The stream named by --topics, checked to hold images of its kind.
const Stream& named_stream(const std::map<std::string, Stream>& streams, const std::string& topic,
                           bool depth, const std::string& where) {
  const auto it = streams.find(topic);
  require(it != streams.end() && !it->second.messages.empty(), where,
          "--topics names '" + topic +
              "', which is not an image topic with messages in the bag; expected one of its "
              "sensor_msgs/Image or CompressedImage topics");
  const Stream& s = it->second;
  require(depth ? s.depth : is_color_encoding(s.encoding, s.compressed), where,
          "topic " + topic + " has encoding '" + s.encoding + "'; expected a " +
              (depth ? "depth encoding (16UC1, mono16, 32FC1, compressedDepth)"
                     : "colour encoding (rgb8, bgr8, rgba8, bgra8, mono8, jpeg, png)"));
  return s;
}

// The camera_info topic of an image topic: <ns>/camera_info or <ns>/info/camera_info (RealSense
// SDK bags) for each namespace up from the topic.
std::string camera_info_topic(const std::set<std::string>& infos, const std::string& image_topic) {
  std::string ns = base_topic(image_topic);
  while (!ns.empty()) {
    ns = ns.substr(0, ns.find_last_of('/'));
    for (const std::string& candidate : {ns + "/camera_info", ns + "/info/camera_info"})
      if (infos.count(candidate)) return candidate;
  }
  return "";
}

Camera camera_from_info(const sensor_msgs::CameraInfo& info, const std::string& where,
                        double depth_factor) {
  Camera c;
  c.name = where;
  c.width = static_cast<int>(std::min<std::uint32_t>(info.width, 1u << 20));
  c.height = static_cast<int>(std::min<std::uint32_t>(info.height, 1u << 20));
  c.fx = info.K[0];
  c.fy = info.K[4];
  c.cx = info.K[2];
  c.cy = info.K[5];
  c.depth_factor = depth_factor;
  const std::string model = lower(info.distortion_model);
  const bool any = std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0.0; });
  if (any) {
    const bool five = model == "plumb_bob" ||
                      (model == "rational_polynomial" &&
                       std::all_of(info.D.begin() + std::min<std::size_t>(5, info.D.size()),
                                   info.D.end(), [](double d) { return d == 0.0; }));
    require(five, where + " distortion_model",
            "'" + info.distortion_model +
                "' with non-zero coefficients; expected plumb_bob (k1 k2 p1 p2 k3), or zeros");
    for (std::size_t k = 0; k < 5 && k < info.D.size(); ++k) c.distortion[k] = info.D[k];
  }
  c.check(where);
  return c;
}

// Depth units per metre: RealSense SDK bags record the sensor's "Depth Units" option (metres per
// unit); ROS (REP 118) 16-bit depth is millimetres; 32FC1 metres are stored as kFloatDepthFactor.
double depth_factor(const rosbag::Bag& bag, const Stream& depth, const std::string& where) {
  const std::string e = lower(depth.encoding);
  if (e.rfind("32fc1", 0) == 0) return kFloatDepthFactor;
  const std::size_t sensor = depth.topic.find("/sensor_");
  if (depth.topic.rfind("/device_", 0) == 0 && sensor != std::string::npos) {
    const std::string prefix = depth.topic.substr(0, depth.topic.find('/', sensor + 1));
    if (auto units = first_message<std_msgs::Float32>(bag, prefix + "/option/Depth Units/value")) {
      require(std::isfinite(units->data) && units->data > 1e-7 && units->data < 1.0,
              where + ":" + prefix + "/option/Depth Units/value",
              "is " + std::to_string(units->data) + "; expected metres per unit in (0, 1)");
      // A float32 of metres per unit: 1 / 0.001f is 999.99995; a whole number of units per metre
      // within float precision is that number.
      const double factor = 1.0 / units->data;
      return std::abs(factor - std::round(factor)) < 1e-6 * factor ? std::round(factor) : factor;
    }
  }
  return 1000.0;
}

Pose pose_of(const geometry_msgs::Transform& t) {
  Pose p = Pose::Identity();
  Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  if (!(q.norm() > 1e-9) || !std::isfinite(q.norm())) q = Eigen::Quaterniond::Identity();
  p.linear() = q.normalized().toRotationMatrix();
  p.translation() = Vec3(t.translation.x, t.translation.y, t.translation.z);
  return p;
}

// color_from_depth through the bag's transform tree (/tf_static, then /tf: the first transform of
// each parent-child pair), or nullopt where the two frames are not connected.
std::optional<Pose> transform_from_tree(const rosbag::Bag& bag, const std::string& color_frame,
                                        const std::string& depth_frame) {
  std::map<std::string, std::vector<std::pair<std::string, Pose> > > edges;  // frame -> (frame, T)
  std::set<std::pair<std::string, std::string> > seen;
  for (const std::string topic : {"/tf_static", "/tf"}) {
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& m : view) {
      const auto message = m.instantiate<objmap_rosbag::CheckedTFMessage>();
      if (!message) break;
      for (const auto& t : message->transforms) {
        const std::string parent = without_slash(t.header.frame_id),
                          child = without_slash(t.child_frame_id);
        if (!seen.insert({parent, child}).second) continue;
        const Pose parent_from_child = pose_of(t.transform);
        edges[parent].push_back({child, parent_from_child});
        edges[child].push_back({parent, parent_from_child.inverse()});
      }
    }
  }
  // Breadth first from the colour frame: color_from[f] maps points of frame f into colour.
  std::map<std::string, Pose> color_from = {{color_frame, Pose::Identity()}};
  std::deque<std::string> queue = {color_frame};
  while (!queue.empty()) {
    const std::string f = queue.front();
    queue.pop_front();
    for (const auto& [next, f_from_next] : edges[f])
      if (!color_from.count(next)) {
        color_from[next] = color_from[f] * f_from_next;
        queue.push_back(next);
      }
  }
  const auto it = color_from.find(depth_frame);
  if (it == color_from.end()) return std::nullopt;
  return it->second;
}

// color_from_depth from a RealSense SDK bag's stream extrinsics (<stream>/tf/0: the stream's pose
// from the device's reference, stream_from_reference), or nullopt.
std::optional<Pose> transform_from_realsense(const rosbag::Bag& bag, const Stream& color,
                                             const Stream& depth) {
  const auto root = [](const std::string& topic) {
    const std::string suffix = "/image/data";
    return topic.size() > suffix.size() &&
                   topic.compare(topic.size() - suffix.size(), suffix.size(), suffix) == 0
               ? topic.substr(0, topic.size() - suffix.size())
               : std::string();
  };
  const std::string c = root(color.topic), d = root(depth.topic);
  if (c.empty() || d.empty()) return std::nullopt;
  const auto color_from_ref = first_message<geometry_msgs::Transform>(bag, c + "/tf/0");
  const auto depth_from_ref = first_message<geometry_msgs::Transform>(bag, d + "/tf/0");
  if (!color_from_ref || !depth_from_ref) return std::nullopt;
  return pose_of(*color_from_ref) * pose_of(*depth_from_ref).inverse();
}

// A raw image's size, row step and data agree: at most 16384 x 16384, `bytes` per pixel.
void require_pixels(const sensor_msgs::Image& msg, std::size_t bytes, const char* what,
                    const std::string& where) {
  require(
      msg.width > 0 && msg.height > 0 && msg.width <= 16384 && msg.height <= 16384 &&
          msg.step >= msg.width * bytes && msg.data.size() >= std::size_t{msg.step} * msg.height,
      where,
      std::string(what) + " of " + std::to_string(msg.width) + "x" + std::to_string(msg.height) +
          " with step " + std::to_string(msg.step) + " and " + std::to_string(msg.data.size()) +
          " bytes; expected step >= width x " + std::to_string(bytes) + " and step x height bytes");
}

// The colour image of a message: CV_8UC3 BGR.
cv::Mat decode_color(const rosbag::MessageInstance& m, const Stream& s, const std::string& where) {
  if (s.compressed) {
    const auto msg = m.instantiate<objmap_rosbag::CheckedCompressedImage>();
    require(msg != nullptr, where, "not a sensor_msgs/CompressedImage");
    std::string error;
    const std::string f = lower(msg->format);
    cv::Mat img = contains(f, "png") ? decode_png(msg->data.data(), msg->data.size(), error)
                                     : decode_jpeg(msg->data.data(), msg->data.size(), error);
    require(!img.empty(), where, "undecodable compressed image (" + msg->format + "): " + error);
    require(img.depth() == CV_8U, where, "a 16-bit colour image; expected 8-bit colour");
    if (img.channels() == 3) return img;
    cv::Mat bgr(img.rows, img.cols, CV_8UC3);
    const int from = img.channels();
    for (int v = 0; v < img.rows; ++v)
      for (int u = 0; u < img.cols; ++u) {
        const std::uint8_t* p = img.ptr<std::uint8_t>(v) + u * from;
        bgr.at<cv::Vec3b>(v, u) =
            from == 1 ? cv::Vec3b(p[0], p[0], p[0]) : cv::Vec3b(p[0], p[1], p[2]);
      }
    return bgr;
  }
  const auto msg = m.instantiate<objmap_rosbag::CheckedImage>();
  require(msg != nullptr, where, "not a sensor_msgs/Image");
  const std::string e = lower(msg->encoding);
  const std::size_t channels = e == "mono8" ? 1 : (e == "rgba8" || e == "bgra8") ? 4 : 3;
  require(is_color_encoding(msg->encoding, false), where,
          "encoding '" + msg->encoding + "'; expected rgb8, bgr8, rgba8, bgra8 or mono8");
  require_pixels(*msg, channels, "image", where);
  const bool rgb = e == "rgb8" || e == "rgba8";
  cv::Mat bgr(static_cast<int>(msg->height), static_cast<int>(msg->width), CV_8UC3);
  for (int v = 0; v < bgr.rows; ++v) {
    const std::uint8_t* row = msg->data.data() + std::size_t{msg->step} * v;
    auto* out = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < bgr.cols; ++u) {
      const std::uint8_t* p = row + std::size_t(u) * channels;
      out[u] = channels == 1 ? cv::Vec3b(p[0], p[0], p[0])
               : rgb         ? cv::Vec3b(p[2], p[1], p[0])
                             : cv::Vec3b(p[0], p[1], p[2]);
    }
  }
  return bgr;
}

// 32-bit float metres as 16-bit units (0 for no depth, NaN, or beyond the 16-bit range).
std::uint16_t float_depth(float metres) {
  const double v = std::round(static_cast<double>(metres) * kFloatDepthFactor);
  return std::isfinite(v) && v >= 1.0 && v <= 65535.0 ? static_cast<std::uint16_t>(v) : 0;
}

cv::Mat decode_compressed_depth(const sensor_msgs::CompressedImage& msg, const std::string& where) {
  const std::string f = lower(msg.format);
  require(!contains(f, "32fc1"), where,
          "compressedDepth of 32FC1 (inverse-depth quantised); expected 16UC1 compressedDepth or "
          "raw 32FC1");
  // compressed_depth_image_transport puts a 12-byte header (format, two quantisation
  // parameters) before the PNG; a plain PNG has none.
  const std::size_t skip = contains(f, "compresseddepth") && msg.data.size() > 12 ? 12 : 0;
  std::string error;
  cv::Mat img = decode_png(msg.data.data() + skip, msg.data.size() - skip, error);
  require(!img.empty(), where, "undecodable compressed depth (" + msg.format + "): " + error);
  require(img.type() == CV_16UC1, where,
          "compressed depth is not a 16-bit one-channel PNG; expected 16UC1 values");
  return img;
}

// The depth image of a message: CV_16UC1 in the stream's units (32FC1: kFloatDepthFactor).
cv::Mat decode_depth(const rosbag::MessageInstance& m, const Stream& s, const std::string& where) {
  if (s.compressed) {
    const auto msg = m.instantiate<objmap_rosbag::CheckedCompressedImage>();
    require(msg != nullptr, where, "not a sensor_msgs/CompressedImage");
    return decode_compressed_depth(*msg, where);
  }
  const auto msg = m.instantiate<objmap_rosbag::CheckedImage>();
  require(msg != nullptr, where, "not a sensor_msgs/Image");
  const std::string e = lower(msg->encoding);
  require(is_depth_encoding(msg->encoding, false), where,
          "encoding '" + msg->encoding + "'; expected 16UC1, mono16 or 32FC1");
  const std::size_t bytes = e == "32fc1" ? 4 : 2;
  require_pixels(*msg, bytes, "depth image", where);
  cv::Mat depth(static_cast<int>(msg->height), static_cast<int>(msg->width), CV_16UC1);
  for (int v = 0; v < depth.rows; ++v) {
    const std::uint8_t* row = msg->data.data() + std::size_t{msg->step} * v;
    auto* out = depth.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth.cols; ++u) {
      std::uint8_t b[4];
      std::memcpy(b, row + u * bytes, bytes);
      if (msg->is_bigendian) std::reverse(b, b + bytes);  // the hosts objmap runs on are little
      if (bytes == 2) {
        std::memcpy(&out[u], b, 2);
      } else {
        float metres;
        std::memcpy(&metres, b, 4);
        out[u] = float_depth(metres);
      }
    }
  }
  return depth;
}

// The bag's records (ROS bag 2.0: <header_len><header><data_len><data> from byte 13 to the end,
// and the same inside an uncompressed chunk's data) checked before rosbag_storage reads them: it
// allocates whatever a length field says, so a damaged or hostile file would claim gigabytes, and
// its header parser (ros::Header::parse) reads each field's <len><name>=<value> without checking
// that it lies inside the header. Each header and data must lie inside the file (or its chunk;
// headers at most 16 MiB), each header field inside its header, and a chunk's uncompressed size be
// at most 1 GiB. Records inside a compressed chunk are checked by its compression's checksums.
std::uint32_t little_u32(const unsigned char* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
         std::uint32_t{p[3]} << 24;
}

// The value of the field `name` of a record header (fields: <len><name>=<value>), if it has one.
std::optional<std::string> header_field(const std::string& header, const std::string& name) {
  for (std::size_t at = 0; at + 4 <= header.size();) {
    const std::uint32_t len = little_u32(reinterpret_cast<const unsigned char*>(&header[at]));
    if (len > header.size() - at - 4) break;
    const std::string field = header.substr(at + 4, len);
    if (field.size() > name.size() && field.compare(0, name.size() + 1, name + "=") == 0)
      return field.substr(name.size() + 1);
    at += 4 + std::size_t{len};
  }
  return std::nullopt;
}

// Why the fields of `header` (`what`: "header", or a connection record's "connection header") do
// not fill it exactly with <len><field> pairs, or empty.
std::string header_fields_problem(const std::string& header, const std::string& what) {
  for (std::size_t at = 0; at < header.size();) {
    if (header.size() - at < 4)
      return "has a " + what + " field length cut short at " + what + " byte " + std::to_string(at);
    const std::uint32_t len = little_u32(reinterpret_cast<const unsigned char*>(&header[at]));
    if (len > header.size() - at - 4)
      return "has a " + what + " field of " + std::to_string(len) + " bytes beyond its " +
             std::to_string(header.size()) + "-byte " + what;
    at += 4 + std::size_t{len};
  }
  return {};
}

// The records from byte `at` to `end` of `in` (a file of `where`); `in_chunk`: inside a chunk.
void check_records_in(std::ifstream& in, const std::string& where, std::uint64_t at,
                      std::uint64_t end, bool in_chunk) {
  while (at < end) {
    unsigned char len[4];
    auto fail = [&](const std::string& what) {
      throw InputError(where, "damaged ROS bag: the record at byte " + std::to_string(at) +
                                  (in_chunk ? " (in a chunk) " : " ") + what +
                                  "; expected a complete bag (rosbag reindex repairs one)");
    };
    if (end - at < 4 ||
        !in.seekg(static_cast<std::streamoff>(at)).read(reinterpret_cast<char*>(len), 4))
      fail("is cut short");
    const std::uint32_t header_len = little_u32(len);
    if (header_len > (16u << 20) || header_len > end - at - 4)
      fail("claims a header of " + std::to_string(header_len) + " bytes");
    std::string header(header_len, '\0');
    if (end - at - 4 - header_len < 4 || !in.read(header.data(), header_len) ||
        !in.read(reinterpret_cast<char*>(len), 4))
      fail("is cut short");
    const std::string problem = header_fields_problem(header, "header");
    if (!problem.empty()) fail(problem);
    const std::uint32_t data_len = little_u32(len);
    if (data_len > end - at - 8 - header_len)
      fail("claims " + std::to_string(data_len) + " bytes of data beyond the end of the " +
           (in_chunk ? "chunk" : "file"));
    const auto op = header_field(header, "op");
    const std::uint64_t data_at = at + 8 + header_len;
    if (op && *op == std::string(1, '\x07')) {  // a connection: its data is a header as well
      if (data_len > (16u << 20))
        fail("claims a connection header of " + std::to_string(data_len) + " bytes");
      std::string connection(data_len, '\0');
      if (!in.read(connection.data(), data_len)) fail("is cut short");
      const std::string bad = header_fields_problem(connection, "connection header");
      if (!bad.empty()) fail(bad);
    }
    if (op && *op == std::string(1, '\x05')) {
      const auto uncompressed = header_field(header, "size");
      if (uncompressed && uncompressed->size() == 4 &&
          little_u32(reinterpret_cast<const unsigned char*>(uncompressed->data())) > (1u << 30))
        fail("is a chunk of more than 1 GiB uncompressed");
      if (!in_chunk && header_field(header, "compression") == std::optional<std::string>("none"))
        check_records_in(in, where, data_at, data_at + data_len, true);
    }
    at = data_at + data_len;
  }
}

void check_records(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::error_code ec;
  const std::uint64_t size = fs::file_size(file, ec);
  check_records_in(in, file.string(), 13, size, false);
}

class BagSource : public FrameSource {
 public:
  BagSource(std::string name, std::unique_ptr<rosbag::Bag> bag, Stream color, Stream depth)
      : name_(std::move(name)),
        bag_(std::move(bag)),
        color_(std::move(color)),
        depth_(std::move(depth)) {}
  std::vector<std::pair<std::size_t, std::size_t> > pairs;  // (colour, depth) message per frame

  cv::Mat color(std::size_t index) const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    const std::size_t i = pairs.at(index).first;
    const std::string where = frame_name(color_, i);
    return guarded(where, [&] { return decode_color(color_.messages[i], color_, where); });
  }
  cv::Mat depth(std::size_t index) const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    const std::size_t i = pairs.at(index).second;
    const std::string where = frame_name(depth_, i);
    return guarded(where, [&] { return decode_depth(depth_.messages[i], depth_, where); });
  }
  std::string frame_name(const Stream& s, std::size_t i) const {
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%.6f", s.stamps[i]);
    return name_ + ":" + s.topic + "@" + stamp;
  }
  const Stream& color_stream() const { return color_; }
  const Stream& depth_stream() const { return depth_; }

 private:
  std::string name_;
  std::unique_ptr<rosbag::Bag> bag_;
  Stream color_, depth_;
  mutable std::mutex mutex_;
};

// The colour and the depth stream: named by --topics, or chosen.
std::pair<Stream, Stream> chosen_streams(const std::map<std::string, Stream>& streams,
                                         const std::string& topics, const std::string& where) {
  if (topics.empty())
    return {choose_stream(streams, false, where), choose_stream(streams, true, where)};
  const std::size_t comma = topics.find(',');
  require(comma != std::string::npos && topics.find(',', comma + 1) == std::string::npos,
          "--topics", "is '" + topics + "'; expected COLOR,DEPTH (two image topics)");
  return {named_stream(streams, topics.substr(0, comma), false, where),
          named_stream(streams, topics.substr(comma + 1), true, where)};
}

// The cameras: colour from its camera_info; where depth is not registered to it (another
// camera_info frame, size or K, and not an aligned topic), the depth camera and color_from_depth.
void read_cameras(const rosbag::Bag& bag, const Stream& color, const Stream& depth,
                  const std::string& where, Dataset& d) {
  std::set<std::string> infos;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections())
    if (c->datatype == "sensor_msgs/CameraInfo") infos.insert(c->topic);
  const std::string color_topic = camera_info_topic(infos, color.topic);
  const std::string depth_topic = camera_info_topic(infos, depth.topic);
  const auto color_info = color_topic.empty()
                              ? nullptr
                              : first_message<objmap_rosbag::CheckedCameraInfo>(bag, color_topic);
  if (!color_info) return;  // the camera comes from --camera
  d.camera = camera_from_info(*color_info, where + ":" + color_topic, d.depth_factor);
  d.camera_source = where + ":" + color_topic;
  const auto depth_info = depth_topic.empty()
                              ? nullptr
                              : first_message<objmap_rosbag::CheckedCameraInfo>(bag, depth_topic);
  if (!depth_info || contains(depth.topic, "aligned_depth_to_color") ||
      contains(depth.topic, "depth_registered"))
    return;
  const std::string cf = without_slash(color_info->header.frame_id),
                    df = without_slash(depth_info->header.frame_id);
  const bool same_camera = depth_info->width == color_info->width &&
                           depth_info->height == color_info->height &&
                           depth_info->K == color_info->K;
  if (same_camera || (!cf.empty() && cf == df)) return;
  std::optional<Pose> color_from_depth = transform_from_tree(bag, cf, df);
  if (!color_from_depth) color_from_depth = transform_from_realsense(bag, color, depth);
  require(color_from_depth.has_value(), where,
          "depth topic " + depth.topic + " (frame '" + df +
              "') is not registered to colour topic " + color.topic + " (frame '" + cf +
              "') and the bag holds no transform between the two (looked in /tf_static, /tf and "
              "RealSense <stream>/tf/0); expected an aligned depth topic or that transform");
  d.depth_camera = Dataset::DepthCamera{
      camera_from_info(*depth_info, where + ":" + depth_topic, d.depth_factor), *color_from_depth};
}

Dataset read_bag(const fs::path& file, const DatasetOptions& options) {
  const std::string where = file.string();
  check_records(file);
  // Opened after construction: when open() throws on a damaged file, ~Bag (close) still frees
  // what it had read; a Bag whose constructor throws leaks its connections (make fuzz, LSan).
  auto bag = std::make_unique<rosbag::Bag>();
  bag->open(file.string(), rosbag::bagmode::Read);
  const std::map<std::string, Stream> streams = image_streams(*bag);
  auto [color, depth] = chosen_streams(streams, options.topics, where);
  Dataset d;
  d.root = file;
  d.layout = "rosbag";
  d.topics = color.topic + "," + depth.topic;
  d.rgb_rows = color.messages.size();
  d.depth_rows = depth.messages.size();
  d.depth_factor = depth_factor(*bag, depth, where);
  read_cameras(*bag, color, depth, where, d);
  auto source =
      std::make_shared<BagSource>(where, std::move(bag), std::move(color), std::move(depth));
  const Stream& c = source->color_stream();
  const Stream& z = source->depth_stream();
  for (const auto& [i, j] : associate_stamps(c.stamps, z.stamps, options.max_diff_s)) {
    FramePair f{c.stamps[i], z.stamps[j], source->frame_name(c, i), source->frame_name(z, j),
                source->pairs.size()};
    source->pairs.emplace_back(i, j);
    d.frames.push_back(std::move(f));
  }
  require(!d.frames.empty(), where,
          "no colour message of " + c.topic + " has a depth message of " + z.topic +
              " within max_diff " + std::to_string(options.max_diff_s) +
              " s; expected the two streams of one recording");
  d.source = std::move(source);
  return d;
}

}  // namespace

Dataset read_rosbag(const fs::path& bag, const DatasetOptions& options) {
  options.check();
  require(is_rosbag_file(bag), bag.string(),
          "not a ROS 1 bag; expected a file that starts with #ROSBAG V2.0");
  return guarded(bag.string(), [&] { return read_bag(bag, options); });
}

#endif  // OBJMAP_HAVE_ROSBAG

}  // namespace objmap::io
