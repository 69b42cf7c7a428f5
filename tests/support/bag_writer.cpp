#include "support/bag_writer.h"

#include <cstring>

#include <geometry_msgs/Transform.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float32.h>
#include <tf2_msgs/TFMessage.h>

namespace objmap::test {

struct BagWriter::Impl {
  rosbag::Bag bag;
};

namespace {

ros::Time stamp_of(double t) { return ros::Time(t > 0 ? t : 1e-3); }

geometry_msgs::Transform transform_of(const Pose& pose) {
  geometry_msgs::Transform t;
  const Eigen::Quaterniond q(pose.linear());
  t.rotation.w = q.w();
  t.rotation.x = q.x();
  t.rotation.y = q.y();
  t.rotation.z = q.z();
  t.translation.x = pose.translation().x();
  t.translation.y = pose.translation().y();
  t.translation.z = pose.translation().z();
  return t;
}

}  // namespace

BagWriter::BagWriter(const std::filesystem::path& file, const std::string& compression)
    : impl_(std::make_unique<Impl>()) {
  impl_->bag.open(file.string(), rosbag::bagmode::Write);
  impl_->bag.setCompression(compression == "bz2"   ? rosbag::compression::BZ2
                            : compression == "lz4" ? rosbag::compression::LZ4
                                                   : rosbag::compression::Uncompressed);
  impl_->bag.setChunkThreshold(256 * 1024);  // several chunks even for a few frames
}

BagWriter::~BagWriter() { close(); }

void BagWriter::close() {
  if (impl_->bag.isOpen()) impl_->bag.close();
}

void BagWriter::image(const std::string& topic, double stamp, const cv::Mat& image,
                      const std::string& encoding, const std::string& frame_id) {
  sensor_msgs::Image m;
  m.header.stamp = stamp_of(stamp);
  m.header.frame_id = frame_id;
  m.width = static_cast<std::uint32_t>(image.cols);
  m.height = static_cast<std::uint32_t>(image.rows);
  m.encoding = encoding;
  m.step = static_cast<std::uint32_t>(image.cols * image.elemSize());
  m.data.resize(std::size_t{m.step} * m.height);
  for (int v = 0; v < image.rows; ++v) {
    std::uint8_t* row = m.data.data() + std::size_t{m.step} * v;
    std::memcpy(row, image.ptr(v), m.step);
    if (encoding == "rgb8")
      for (int u = 0; u < image.cols; ++u) std::swap(row[3 * u], row[3 * u + 2]);
  }
  impl_->bag.write(topic, stamp_of(stamp), m);
}

void BagWriter::raw_image(const std::string& topic, double stamp, std::uint32_t width,
                          std::uint32_t height, std::uint32_t step, const std::string& encoding,
                          std::vector<std::uint8_t> data) {
  sensor_msgs::Image m;
  m.header.stamp = stamp_of(stamp);
  m.width = width;
  m.height = height;
  m.step = step;
  m.encoding = encoding;
  m.data = std::move(data);
  impl_->bag.write(topic, stamp_of(stamp), m);
}

void BagWriter::compressed(const std::string& topic, double stamp,
                           const std::vector<std::uint8_t>& bytes, const std::string& format,
                           const std::string& frame_id) {
  sensor_msgs::CompressedImage m;
  m.header.stamp = stamp_of(stamp);
  m.header.frame_id = frame_id;
  m.format = format;
  m.data = bytes;
  impl_->bag.write(topic, stamp_of(stamp), m);
}

void BagWriter::camera_info(const std::string& topic, double stamp, const Camera& camera,
                            const std::string& frame_id) {
  sensor_msgs::CameraInfo m;
  m.header.stamp = stamp_of(stamp);
  m.header.frame_id = frame_id;
  m.width = static_cast<std::uint32_t>(camera.width);
  m.height = static_cast<std::uint32_t>(camera.height);
  m.distortion_model = "plumb_bob";
  m.D.assign(camera.distortion.begin(), camera.distortion.end());
  m.K = {camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1};
  impl_->bag.write(topic, stamp_of(stamp), m);
}

void BagWriter::float32(const std::string& topic, float value) {
  std_msgs::Float32 m;
  m.data = value;
  impl_->bag.write(topic, stamp_of(0), m);
}

void BagWriter::transform(const std::string& topic, const Pose& pose) {
  impl_->bag.write(topic, stamp_of(0), transform_of(pose));
}

void BagWriter::static_transform(const std::string& parent, const std::string& child,
                                 const Pose& parent_from_child) {
  tf2_msgs::TFMessage m;
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp_of(0);
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform = transform_of(parent_from_child);
  m.transforms.push_back(t);
  impl_->bag.write("/tf_static", stamp_of(0), m);
}

}  // namespace objmap::test
