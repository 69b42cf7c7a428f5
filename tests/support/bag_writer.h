#pragma once
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/core/camera.h"
#include "objmap/core/types.h"

// ROS 1 bags written with rosbag_storage for the tests of the rosbag layout: images (raw and
// compressed), camera_info, options and transforms as RealSense and the ROS drivers record them.
// No ROS header here: the messages stay in bag_writer.cpp.
namespace objmap::test {

class BagWriter {
 public:
  // compression: "none", "bz2" or "lz4".
  BagWriter(const std::filesystem::path& file, const std::string& compression);
  ~BagWriter();
  // A sensor_msgs/Image of `image` (CV_8UC3 BGR, CV_16UC1 or CV_32FC1) with `encoding` (bgr8,
  // rgb8, 16UC1, mono16, 32FC1): rgb8 swaps the channels, the others copy the pixels.
  void image(const std::string& topic, double stamp, const cv::Mat& image,
             const std::string& encoding, const std::string& frame_id = "");
  // A sensor_msgs/Image with the given fields as they are (for bad-input tests).
  void raw_image(const std::string& topic, double stamp, std::uint32_t width, std::uint32_t height,
                 std::uint32_t step, const std::string& encoding, std::vector<std::uint8_t> data);
  // A sensor_msgs/CompressedImage holding `bytes` with `format`.
  void compressed(const std::string& topic, double stamp, const std::vector<std::uint8_t>& bytes,
                  const std::string& format, const std::string& frame_id = "");
  void camera_info(const std::string& topic, double stamp, const Camera& camera,
                   const std::string& frame_id = "");
  void float32(const std::string& topic, float value);         // std_msgs/Float32
  void transform(const std::string& topic, const Pose& pose);  // geometry_msgs/Transform
  void static_transform(const std::string& parent, const std::string& child,
                        const Pose& parent_from_child);  // on /tf_static
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap::test
