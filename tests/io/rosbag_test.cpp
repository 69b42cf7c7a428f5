// The rosbag layout (io/rosbag.h) on bags written with rosbag_storage from real frames, as
// RealSense's recorder, the ROS drivers (compressed streams) and the TUM benchmark write them, in
// both chunk compressions; bad bags named by file, topic and what was expected.
#include "objmap/io/rosbag.h"

#include <gtest/gtest.h>

#include <fstream>

#include "objmap/core/error.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/dataset.h"
#include "objmap/io/image.h"
#include "objmap/io/png_encode.h"
#include "support/test_support.h"
#if OBJMAP_TEST_BAGS
#include "support/bag_writer.h"
#endif

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

#if !OBJMAP_TEST_BAGS

TEST(Rosbag, ReadsBags) {
  GTEST_SKIP() << "objmap was built without librosbag-storage-dev: no bag can be written or read";
}

#else

using test::BagWriter;
using test::read_text;

// A copy of the bag `from` at `to` with `bytes` written over it at byte `at` (a damaged bag).
fs::path damaged_copy(const fs::path& from, const fs::path& to, std::size_t at,
                      const std::string& bytes) {
  std::string b = read_text(from);
  b.replace(at, bytes.size(), bytes);
  std::ofstream(to, std::ios::binary) << b;
  return to;
}

// Every pixel of two images equal.
::testing::AssertionResult same_pixels(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type())
    return ::testing::AssertionFailure() << "sizes or types differ";
  const cv::Mat diff = a != b;
  const int differing = cv::countNonZero(diff.reshape(1));
  if (differing == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << differing << " values differ";
}

using test::error_of;

// ROS stamps start after 0 (a zero stamp means "not set"): the clip's frames from 0 s are
// recorded kOffset later.
constexpr double kOffset = 1000.0;

// A TUM folder's frames, pixels compared with those read back from `bag` (stamps `offset` later).
void expect_same_frames(const Dataset& tum, const Camera& camera, const Dataset& bag,
                        double offset = kOffset) {
  ASSERT_EQ(bag.frames.size(), tum.frames.size());
  for (std::size_t i = 0; i < tum.frames.size(); ++i) {
    EXPECT_NEAR(bag.frames[i].rgb_timestamp, tum.frames[i].rgb_timestamp + offset, 1e-6);
    EXPECT_TRUE(same_pixels(read_frame_rgb(bag, bag.frames[i], camera.width, camera.height),
                            read_rgb(tum.frames[i].rgb_file, camera.width, camera.height)))
        << i;
    EXPECT_TRUE(same_pixels(read_frame_depth(bag, bag.frames[i], *bag.camera),
                            read_depth(tum.frames[i].depth_file, camera.width, camera.height)))
        << i;
  }
}

TEST(Rosbag, RealSenseRecordingOfRealFramesGivesTheirPixelsCameraAndDepthUnits) {
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f");
  TempDir tmp;
  const Dataset tum = read_dataset(data);
  const Camera camera = read_camera_file(data / "camera.json");
  {
    // As the RealSense SDK records: one topic tree per stream, Z16 depth as mono16 in the
    // sensor's depth units (here the clip's 1/10000 m), bz2 chunks.
    BagWriter bag(tmp / "rs.bag", "bz2");
    bag.float32("/device_0/sensor_0/option/Depth Units/value", 0.0001f);
    bag.camera_info("/device_0/sensor_1/Color_0/info/camera_info", 0, camera);
    bag.camera_info("/device_0/sensor_0/Depth_0/info/camera_info", 0, camera);
    for (const FramePair& f : tum.frames) {
      bag.image("/device_0/sensor_1/Color_0/image/data", kOffset + f.rgb_timestamp,
                read_rgb(f.rgb_file, 0, 0), "rgb8");
      bag.image("/device_0/sensor_0/Depth_0/image/data", kOffset + f.depth_timestamp,
                read_depth(f.depth_file, 0, 0), "mono16");
    }
  }
  const Dataset d = read_dataset(tmp / "rs.bag");
  EXPECT_EQ(d.layout, "rosbag");
  EXPECT_EQ(d.topics,
            "/device_0/sensor_1/Color_0/image/data,/device_0/sensor_0/Depth_0/image/data");
  EXPECT_DOUBLE_EQ(d.depth_factor, 10000.0);
  ASSERT_TRUE(d.camera.has_value());
  EXPECT_DOUBLE_EQ(d.camera->fx, camera.fx);
  EXPECT_DOUBLE_EQ(d.camera->cy, camera.cy);
  EXPECT_FALSE(d.depth_camera.has_value()) << "the same camera: registered";
  expect_same_frames(tum, camera, d);
}

// compressed_depth_image_transport's 12-byte header, then the PNG.
std::vector<std::uint8_t> compressed_depth(const cv::Mat& depth) {
  std::vector<std::uint8_t> png;
  encode_png(depth, &png);
  std::vector<std::uint8_t> out(12 + png.size(), 0);
  std::copy(png.begin(), png.end(), out.begin() + 12);
  return out;
}

TEST(Rosbag, DriverRecordingWithCompressedStreamsInLz4ChoosesColourAndAlignedDepth) {
  OBJMAP_DATA_OR_SKIP(data, "ycbv_0000_10f");
  TempDir tmp;
  const Dataset tum = read_dataset(data);
  Camera camera = read_camera_file(data / "camera.json");
  {
    // As realsense2_camera with image_transport: a raw colour stream and its compressed copy, an
    // aligned depth (compressedDepth only), a depth in the depth camera, an infrared stream.
    BagWriter bag(tmp / "driver.bag", "lz4");
    Camera depth_camera = camera;
    depth_camera.fx = depth_camera.fy = 600;
    bag.camera_info("/camera/color/camera_info", 0, camera, "camera_color_optical_frame");
    bag.camera_info("/camera/aligned_depth_to_color/camera_info", 0, camera,
                    "camera_color_optical_frame");
    bag.camera_info("/camera/depth/camera_info", 0, depth_camera, "camera_depth_optical_frame");
    for (const FramePair& f : tum.frames) {
      const cv::Mat bgr = read_rgb(f.rgb_file, 0, 0), depth = read_depth(f.depth_file, 0, 0);
      std::vector<std::uint8_t> png;
      encode_png(bgr, &png);
      const double t = kOffset + f.rgb_timestamp, t_depth = kOffset + f.depth_timestamp;
      bag.image("/camera/color/image_raw", t, bgr, "bgr8");
      bag.compressed("/camera/color/image_raw/compressed", t, png, "rgb8; png compressed bgr8");
      bag.compressed("/camera/aligned_depth_to_color/image_raw/compressedDepth", t_depth,
                     compressed_depth(depth), "16UC1; compressedDepth png");
      bag.image("/camera/depth/image_rect_raw", t_depth, depth, "16UC1");
      cv::Mat ir(8, 8, CV_8UC1, cv::Scalar(7));
      bag.image("/camera/infra1/image_rect_raw", t, ir, "mono8");
    }
  }
  const Dataset d = read_dataset(tmp / "driver.bag");
  EXPECT_EQ(d.topics,
            "/camera/color/image_raw,/camera/aligned_depth_to_color/image_raw/compressedDepth");
  EXPECT_DOUBLE_EQ(d.depth_factor, 1000.0) << "ROS 16-bit depth is millimetres";
  EXPECT_FALSE(d.depth_camera.has_value());
  camera.depth_factor = 1000.0;
  expect_same_frames(tum, camera, d);

  // The compressed colour copy, named: the same pixels (PNG is lossless).
  DatasetOptions named;
  named.topics =
      "/camera/color/image_raw/compressed,/camera/aligned_depth_to_color/image_raw/compressedDepth";
  expect_same_frames(tum, camera, read_dataset(tmp / "driver.bag", named));
}

TEST(Rosbag, TumBenchmarkBagWithFloatDepthKeepsTheSixteenBitValues) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  TempDir tmp;
  const Dataset tum = read_dataset(data);
  const Camera camera = camera_preset("fr1");
  {
    // As the TUM RGB-D bags: rgb8 colour, 32FC1 depth in metres, both cameras' info with the same
    // intrinsics (the Kinect registers depth to colour), different frame ids.
    BagWriter bag(tmp / "tum.bag", "none");
    for (const FramePair& f : tum.frames) {
      bag.camera_info("/camera/rgb/camera_info", f.rgb_timestamp, camera,
                      "/openni_rgb_optical_frame");
      bag.camera_info("/camera/depth/camera_info", f.depth_timestamp, camera,
                      "/openni_depth_optical_frame");
      bag.image("/camera/rgb/image_color", f.rgb_timestamp, read_rgb(f.rgb_file, 0, 0), "rgb8");
      cv::Mat metres;
      read_depth(f.depth_file, 0, 0).convertTo(metres, CV_32F, 1.0 / 5000.0);
      metres.setTo(std::numeric_limits<float>::quiet_NaN(), metres == 0);
      bag.image("/camera/depth/image", f.depth_timestamp, metres, "32FC1");
    }
  }
  const Dataset d = read_dataset(tmp / "tum.bag");
  EXPECT_DOUBLE_EQ(d.depth_factor, 5000.0);
  EXPECT_FALSE(d.depth_camera.has_value());
  expect_same_frames(tum, camera, d, 0.0);
}

// A small synthetic frame pair: colour 64x48, depth 32x24 of another camera.
void write_two_camera_bag(const fs::path& file, bool with_transform) {
  BagWriter bag(file, "lz4");
  Camera color;
  color.width = 64, color.height = 48, color.fx = color.fy = 60, color.cx = 32, color.cy = 24;
  Camera depth = color;
  depth.width = 32, depth.height = 24, depth.fx = depth.fy = 28, depth.cx = 16, depth.cy = 12;
  bag.camera_info("/cam/color/camera_info", 0, color, "color_optical");
  bag.camera_info("/cam/depth/camera_info", 0, depth, "depth_optical");
  if (with_transform) {
    Pose link_from_color = Pose::Identity(), link_from_depth = Pose::Identity();
    link_from_color.translation() = Vec3(0.0, 0.015, 0.0);
    link_from_depth.linear() = Eigen::AngleAxisd(0.1, Vec3::UnitY()).toRotationMatrix();
    link_from_depth.translation() = Vec3(0.0, -0.01, 0.002);
    bag.static_transform("cam_link", "color_optical", link_from_color);
    bag.static_transform("/cam_link", "depth_optical", link_from_depth);
  }
  for (int i = 0; i < 3; ++i) {
    bag.image("/cam/color/image_raw", 1.0 + i / 30.0, cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)),
              "bgr8");
    bag.image("/cam/depth/image_rect_raw", 1.0 + i / 30.0 + 0.004,
              cv::Mat(24, 32, CV_16UC1, cv::Scalar(1000)), "16UC1");
  }
}

TEST(Rosbag, DepthOfAnotherCameraIsRegisteredThroughTheBagsTransformTree) {
  TempDir tmp;
  write_two_camera_bag(tmp / "two.bag", true);
  const Dataset d = read_dataset(tmp / "two.bag");
  ASSERT_EQ(d.frames.size(), 3u);
  ASSERT_TRUE(d.depth_camera.has_value());
  EXPECT_EQ(d.depth_camera->camera.width, 32);
  // color_from_depth = (link_from_color)^-1 * link_from_depth.
  Pose link_from_color = Pose::Identity(), link_from_depth = Pose::Identity();
  link_from_color.translation() = Vec3(0.0, 0.015, 0.0);
  link_from_depth.linear() = Eigen::AngleAxisd(0.1, Vec3::UnitY()).toRotationMatrix();
  link_from_depth.translation() = Vec3(0.0, -0.01, 0.002);
  const Pose expected = link_from_color.inverse() * link_from_depth;
  EXPECT_LT((d.depth_camera->color_from_depth.matrix() - expected.matrix()).norm(), 1e-9);
  // The depth lands in the colour image: a colour pixel's point, moved back into the depth
  // camera, lies on the depth camera's plane at 1 m.
  const cv::Mat depth = read_frame_depth(d, d.frames[0], *d.camera);
  EXPECT_EQ(depth.cols, 64);
  for (const auto& [u, v] : {std::pair{32, 24}, {20, 30}, {45, 15}}) {
    const double z = depth.at<std::uint16_t>(v, u) / 1000.0;
    ASSERT_GT(z, 0.5) << u << "," << v;
    const Vec3 point_in_depth = expected.inverse() * d.camera->unproject(u, v, z);
    EXPECT_NEAR(point_in_depth.z(), 1.0, 0.01) << u << "," << v;
  }

  write_two_camera_bag(tmp / "no_tf.bag", false);
  const std::string e = error_of([&] { read_dataset(tmp / "no_tf.bag"); });
  EXPECT_NE(e.find("no_tf.bag: depth topic /cam/depth/image_rect_raw (frame 'depth_optical') is "
                   "not registered to colour topic /cam/color/image_raw"),
            std::string::npos)
      << e;
}

TEST(Rosbag, BadBagsAreNamedWithTheTopicAndWhatWasExpected) {
  TempDir tmp;
  {
    BagWriter bag(tmp / "info_only.bag", "none");
    bag.camera_info("/cam/camera_info", 0, Camera{});
  }
  std::string e = error_of([&] { read_dataset(tmp / "info_only.bag"); });
  EXPECT_NE(e.find("info_only.bag: no colour image topic; image topics in the bag: none"),
            std::string::npos)
      << e;
  {
    BagWriter bag(tmp / "two_colour.bag", "none");
    for (const char* topic : {"/a/image_raw", "/b/image_raw"})
      bag.image(topic, 1.0, cv::Mat(4, 4, CV_8UC3, cv::Scalar(0)), "rgb8");
    bag.image("/d/image_raw", 1.0, cv::Mat(4, 4, CV_16UC1, cv::Scalar(0)), "16UC1");
  }
  e = error_of([&] { read_dataset(tmp / "two_colour.bag"); });
  EXPECT_NE(e.find("more than one colour image topic: /a/image_raw (rgb8), /b/image_raw (rgb8); "
                   "expected one (--topics COLOR,DEPTH names them)"),
            std::string::npos)
      << e;
  DatasetOptions named;
  named.topics = "/b/image_raw,/c/image_raw";
  e = error_of([&] { read_dataset(tmp / "two_colour.bag", named); });
  EXPECT_NE(e.find("--topics names '/c/image_raw', which is not an image topic"), std::string::npos)
      << e;
  named.topics = "/b/image_raw,/a/image_raw";
  e = error_of([&] { read_dataset(tmp / "two_colour.bag", named); });
  EXPECT_NE(e.find("topic /a/image_raw has encoding 'rgb8'; expected a depth encoding"),
            std::string::npos)
      << e;
  named.topics = "/b/image_raw";
  e = error_of([&] { read_dataset(tmp / "two_colour.bag", named); });
  EXPECT_NE(e.find("--topics: is '/b/image_raw'; expected COLOR,DEPTH"), std::string::npos) << e;
  {
    // A depth message whose data is shorter than step x height.
    BagWriter bag(tmp / "short.bag", "bz2");
    bag.image("/c/image_raw", 1.0, cv::Mat(4, 4, CV_8UC3, cv::Scalar(0)), "bgr8");
    bag.raw_image("/d/image_raw", 1.0, 4, 4, 8, "16UC1", std::vector<std::uint8_t>(20, 0));
  }
  const Dataset d = read_dataset(tmp / "short.bag");
  e = error_of([&] { read_frame_depth(d, d.frames[0], Camera{}); });
  EXPECT_NE(e.find("short.bag:/d/image_raw@1.000000: depth image of 4x4 with step 8 and 20 bytes; "
                   "expected step >= width x 2 and step x height bytes"),
            std::string::npos)
      << e;
  // A bag cut in half: its index is gone.
  {
    std::ifstream in(tmp / "short.bag", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(tmp / "cut.bag", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  e = error_of([&] { read_dataset(tmp / "cut.bag"); });
  EXPECT_NE(e.find("cut.bag: "), std::string::npos) << e;
  // A record that claims 2.3 GB (rosbag_storage would allocate it): refused before it is read.
  damaged_copy(tmp / "short.bag", tmp / "huge.bag", 13, std::string("\x00\x00\x00\x8a", 4));
  e = error_of([&] { read_dataset(tmp / "huge.bag"); });
  EXPECT_NE(e.find("huge.bag: damaged ROS bag: the record at byte 13 claims a header of 2315255808 "
                   "bytes; expected a complete bag"),
            std::string::npos)
      << e;
  // A header field that claims more than its header (ros::Header::parse would read past it): the
  // file header record's first field, and a connection record's inside an uncompressed chunk.
  damaged_copy(tmp / "short.bag", tmp / "field.bag", 17, std::string("\x00\x21\x00\x00", 4));
  e = error_of([&] { read_dataset(tmp / "field.bag"); });
  EXPECT_NE(e.find("field.bag: damaged ROS bag: the record at byte 13 has a header field of 8448 "
                   "bytes beyond its "),
            std::string::npos)
      << e;
  {
    BagWriter bag(tmp / "plain.bag", "none");
    bag.image("/c/image_raw", 1.0, cv::Mat(4, 4, CV_8UC3, cv::Scalar(0)), "bgr8");
    bag.image("/d/image_raw", 1.0, cv::Mat(4, 4, CV_16UC1, cv::Scalar(0)), "16UC1");
  }
  ASSERT_NO_THROW(read_dataset(tmp / "plain.bag"));
  const std::string plain = read_text(tmp / "plain.bag");
  const std::string long_field("\x00\x00\x01\x00", 4);
  const std::size_t op = plain.find(std::string("op=\x07", 4));  // the chunk's first connection
  ASSERT_NE(op, std::string::npos);
  damaged_copy(tmp / "plain.bag", tmp / "inner.bag", op - 4, long_field);
  e = error_of([&] { read_dataset(tmp / "inner.bag"); });
  EXPECT_NE(e.find("inner.bag: damaged ROS bag: the record at byte "), std::string::npos) << e;
  EXPECT_NE(e.find(" (in a chunk) has a header field of 65536 bytes beyond its "),
            std::string::npos)
      << e;
  // A connection record's data is the connection's header, parsed the same way (a field claiming
  // more than that header).
  const std::size_t def = plain.find("message_definition=");
  ASSERT_NE(def, std::string::npos);
  damaged_copy(tmp / "plain.bag", tmp / "connection.bag", def - 4, long_field);
  e = error_of([&] { read_dataset(tmp / "connection.bag"); });
  EXPECT_NE(e.find("connection.bag: damaged ROS bag: the record at byte "), std::string::npos) << e;
  EXPECT_NE(e.find(" has a connection header field of 65536 bytes beyond its "), std::string::npos)
      << e;
  // Not a bag at all, named as one.
  std::ofstream(tmp / "text.bag") << "hello\n";
  DatasetOptions as_bag;
  as_bag.layout = "rosbag";
  e = error_of([&] { read_dataset(tmp / "text.bag", as_bag); });
  EXPECT_NE(e.find("text.bag: not a ROS 1 bag; expected a file that starts with #ROSBAG V2.0"),
            std::string::npos)
      << e;
  e = error_of([&] { read_dataset(tmp / "text.bag"); });
  EXPECT_NE(e.find("text.bag: is a file and not a ROS 1 bag"), std::string::npos) << e;
}

// An array whose message claims more than the message holds (a damaged bag; ROS's own reader
// would first size the array: here a gigabyte of pixels): named, before anything is allocated.
TEST(Rosbag, AnArrayClaimingMoreThanItsMessageHoldsIsADamagedBag) {
  TempDir tmp;
  {
    BagWriter bag(tmp / "plain.bag", "none");
    bag.image("/c/image_raw", 1.0, cv::Mat(4, 4, CV_8UC3, cv::Scalar(0)), "bgr8");
    bag.image("/d/image_raw", 1.0, cv::Mat(4, 4, CV_16UC1, cv::Scalar(0)), "16UC1");
  }
  // The depth image's 32 bytes of pixels (after its encoding, is_bigendian 0 and step 8) made 1 GB.
  const std::string before("16UC1\x00\x08\x00\x00\x00", 10);
  const std::size_t length = read_text(tmp / "plain.bag").find(before);
  ASSERT_NE(length, std::string::npos);
  const fs::path pixels = damaged_copy(tmp / "plain.bag", tmp / "pixels.bag",
                                       length + before.size(), std::string("\x00\x00\x00\x40", 4));
  std::string e = error_of([&] { read_dataset(pixels); });
  EXPECT_NE(e.find("pixels.bag: not a readable ROS bag: damaged message: its image data claims "
                   "1073741824 bytes with 32 bytes left in the message; expected a complete "
                   "message"),
            std::string::npos)
      << e;
}

#endif  // OBJMAP_TEST_BAGS

}  // namespace
}  // namespace objmap::io
