// Writes the seeds of the rosbag fuzz target into OUT/rosbag/: tiny bags written with
// rosbag_storage at test time (tests/support/bag_writer.h), one per way the layout is recorded —
// RealSense SDK topics, a driver's compressed streams, float depth with a transform tree — in each
// chunk compression, so that the target has seeds without the real data and no bag is kept in the
// repository. Usage: fuzz_make_bag_seeds OUT.
#include <cstdio>
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

#include "objmap/io/png_encode.h"
#include "support/bag_writer.h"

namespace fs = std::filesystem;
using objmap::Camera;
using objmap::Pose;
using objmap::test::BagWriter;

namespace {

Camera tiny_camera(int width, int height) {
  Camera c;
  c.width = width, c.height = height, c.fx = c.fy = 8, c.cx = width / 2.0, c.cy = height / 2.0;
  return c;
}

void realsense(const fs::path& file, const char* compression) {
  BagWriter bag(file, compression);
  bag.float32("/device_0/sensor_0/option/Depth Units/value", 0.001f);
  bag.camera_info("/device_0/sensor_1/Color_0/info/camera_info", 0, tiny_camera(8, 6));
  bag.camera_info("/device_0/sensor_0/Depth_0/info/camera_info", 0, tiny_camera(8, 6));
  bag.image("/device_0/sensor_1/Color_0/image/data", 1.0,
            cv::Mat(6, 8, CV_8UC3, cv::Scalar(9, 8, 7)), "rgb8");
  bag.image("/device_0/sensor_0/Depth_0/image/data", 1.0, cv::Mat(6, 8, CV_16UC1, cv::Scalar(900)),
            "mono16");
}

void compressed(const fs::path& file, const char* compression) {
  BagWriter bag(file, compression);
  bag.camera_info("/camera/color/camera_info", 0, tiny_camera(8, 6), "color");
  std::vector<std::uint8_t> color, depth;
  objmap::io::encode_png(cv::Mat(6, 8, CV_8UC3, cv::Scalar(1, 2, 3)), &color);
  objmap::io::encode_png(cv::Mat(6, 8, CV_16UC1, cv::Scalar(1200)), &depth);
  depth.insert(depth.begin(), 12, 0);
  bag.compressed("/camera/color/image_raw/compressed", 1.0, color, "rgb8; png compressed bgr8");
  bag.compressed("/camera/aligned_depth_to_color/image_raw/compressedDepth", 1.0, depth,
                 "16UC1; compressedDepth png");
}

void two_cameras(const fs::path& file, const char* compression) {
  BagWriter bag(file, compression);
  bag.camera_info("/cam/color/camera_info", 0, tiny_camera(8, 6), "color");
  bag.camera_info("/cam/depth/camera_info", 0, tiny_camera(4, 3), "depth");
  Pose link_from_depth = Pose::Identity();
  link_from_depth.translation().x() = 0.02;
  bag.static_transform("link", "color", Pose::Identity());
  bag.static_transform("link", "depth", link_from_depth);
  bag.image("/cam/color/image_raw", 1.0, cv::Mat(6, 8, CV_8UC3, cv::Scalar(5)), "bgr8");
  bag.image("/cam/depth/image", 1.0, cv::Mat(3, 4, CV_32FC1, cv::Scalar(1.5)), "32FC1");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_bag_seeds OUT\n");
    return 2;
  }
  const fs::path out = fs::path(argv[1]) / "rosbag";
  fs::create_directories(out);
  for (const char* compression : {"none", "bz2", "lz4"}) {
    const std::string c = compression;
    realsense(out / ("realsense_" + c + ".bag"), compression);
    compressed(out / ("compressed_" + c + ".bag"), compression);
    two_cameras(out / ("two_cameras_" + c + ".bag"), compression);
  }
  return 0;
}
