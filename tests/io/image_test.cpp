#include "objmap/io/image.h"

#include <gtest/gtest.h>

#include <fstream>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "io/image_checks.h"
#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::read_text;
using test::TempDir;
using test::write_text;

std::string rgb_error(const fs::path& file, int w = 640, int h = 480) {
  return image_checks::error_reason(file, [&] { read_rgb(file, w, h); });
}

std::string depth_error(const fs::path& file, int w = 640, int h = 480) {
  return image_checks::error_reason(file, [&] { read_depth(file, w, h); });
}

TEST(ReadImage, RealFr1Desk9) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_desk_9");
  const cv::Mat depth = read_depth(dir / "depth/1305031453.374112.png", 640, 480);
  EXPECT_EQ(depth.type(), CV_16UC1);
  EXPECT_EQ(depth.cols, 640);
  EXPECT_EQ(depth.rows, 480);
  double max_value = 0;
  cv::minMaxLoc(depth, nullptr, &max_value);
  EXPECT_GT(max_value, 5000);  // > 1 m at factor 5000: raw 16-bit values, not scaled to 8 bits
  const cv::Mat rgb = read_rgb(dir / "rgb/1305031453.359684.png", 640, 480);
  EXPECT_EQ(rgb.type(), CV_8UC3);
  // 0 = any size.
  EXPECT_EQ(read_rgb(dir / "rgb/1305031453.359684.png", 0, 0).size(), rgb.size());
}

TEST(ReadImage, RealJpegRgb) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr3_cabinet_58kf");
  const cv::Mat rgb = read_rgb(dir / "rgb/1341841278.8427.jpg", 640, 480);
  EXPECT_EQ(rgb.type(), CV_8UC3);
  // A JPEG is not a depth image.
  EXPECT_EQ(depth_error(dir / "rgb/1341841278.8427.jpg"), "not a PNG image");
}

TEST(ReadImage, MissingOrNotAnImage) {
  TempDir dir;
  EXPECT_EQ(rgb_error(dir / "none.png"), "image file not found");
  EXPECT_EQ(depth_error(dir / "none.png"), "image file not found");
  write_text(dir / "text.png", "hello, not an image");
  EXPECT_EQ(rgb_error(dir / "text.png"), "not a PNG or JPEG image");
  write_text(dir / "empty.png", "");
  EXPECT_EQ(rgb_error(dir / "empty.png"), "empty file; expected an image");
  EXPECT_EQ(rgb_error(dir.path()), "is not a file");
}

TEST(ReadImage, WrongSize) {
  TempDir dir;
  cv::imwrite((dir / "small.png").string(), cv::Mat(240, 320, CV_16UC1, cv::Scalar(1000)));
  EXPECT_EQ(depth_error(dir / "small.png"),
            "image is 320x240; expected 640x480 (the camera's width x height)");
  cv::imwrite((dir / "small_rgb.png").string(), cv::Mat(240, 320, CV_8UC3, cv::Scalar(1, 2, 3)));
  EXPECT_EQ(rgb_error(dir / "small_rgb.png"),
            "image is 320x240; expected 640x480 (the camera's width x height)");
  EXPECT_EQ(read_depth(dir / "small.png", 320, 240).at<std::uint16_t>(10, 10), 1000);
}

TEST(ReadImage, AJpegOfTheWrongSizeIsRefusedBeforeDecoding) {
  // Seen with tests/fuzz/fuzz_jpeg (8 runs/s): a JPEG of a few dozen bytes whose header claims a
  // huge image was decoded in full (up to 2^30 pixels, gigabytes) before its size was compared with
  // the camera's. Its header is read first now, as a PNG's is: 60000x60000 names the size, where
  // decoding would have refused the pixel count.
  TempDir dir;
  std::vector<unsigned char> bytes;
  cv::imencode(".jpg", cv::Mat(8, 8, CV_8UC3, cv::Scalar(10, 20, 30)), bytes);
  std::size_t sof = 2;
  while (sof + 9 < bytes.size() && !(bytes[sof] == 0xFF && bytes[sof + 1] == 0xC0)) ++sof;
  ASSERT_LT(sof + 9, bytes.size()) << "no SOF0 marker";
  for (std::size_t at : {sof + 5, sof + 7}) {  // height, then width: 60000 = 0xEA60
    bytes[at] = 0xEA;
    bytes[at + 1] = 0x60;
  }
  std::ofstream(dir / "huge.jpg", std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  EXPECT_EQ(rgb_error(dir / "huge.jpg"),
            "image is 60000x60000; expected 640x480 (the camera's width x height)");
}

TEST(ReadImage, EightBitOrColourDepth) {
  TempDir dir;
  cv::imwrite((dir / "d8.png").string(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(7)));
  EXPECT_EQ(depth_error(dir / "d8.png"),
            "8-bit image; expected a 16-bit single-channel depth PNG (metres x depth_factor)");
  cv::imwrite((dir / "colour.png").string(), cv::Mat(480, 640, CV_16UC3, cv::Scalar(1, 2, 3)));
  EXPECT_EQ(depth_error(dir / "colour.png"),
            "3-channel (colour) image; expected a 16-bit single-channel depth PNG");
  // A 16-bit colour image is not an rgb image either.
  EXPECT_EQ(rgb_error(dir / "colour.png"), "16-bit colour image; expected 8 bits per channel");
}

TEST(ReadImage, GreyAndAlphaRgbBecomeBgr) {
  TempDir dir;
  cv::imwrite((dir / "grey.png").string(), cv::Mat(4, 6, CV_8UC1, cv::Scalar(9)));
  const cv::Mat grey = read_rgb(dir / "grey.png", 6, 4);
  EXPECT_EQ(grey.type(), CV_8UC3);
  EXPECT_EQ(grey.at<cv::Vec3b>(1, 1), cv::Vec3b(9, 9, 9));
  cv::imwrite((dir / "bgra.png").string(), cv::Mat(4, 6, CV_8UC4, cv::Scalar(1, 2, 3, 200)));
  const cv::Mat bgra = read_rgb(dir / "bgra.png", 6, 4);
  EXPECT_EQ(bgra.type(), CV_8UC3);
  EXPECT_EQ(bgra.at<cv::Vec3b>(2, 3), cv::Vec3b(1, 2, 3));
}

TEST(ReadImage, TruncatedAndCorruptFiles) {
  OBJMAP_DATA_OR_SKIP(data, "tum");
  TempDir dir;
  const std::string png = read_text(data / "fr1_desk_9/depth/1305031453.374112.png");
  write_text(dir / "half.png", png.substr(0, png.size() / 2));
  EXPECT_EQ(depth_error(dir / "half.png"),
            "truncated PNG (no IEND chunk at the end); expected a PNG image");
  // Complete structure, garbage image data: decoding fails.
  std::string garbled = png;
  for (std::size_t i = 100; i < garbled.size() - 100; ++i) garbled[i] = static_cast<char>(i * 7);
  write_text(dir / "garbled.png", garbled);
  EXPECT_NE(depth_error(dir / "garbled.png").find("cannot decode the image"), std::string::npos);
  const std::string jpg = read_text(data / "fr3_cabinet_58kf/rgb/1341841278.8427.jpg");
  write_text(dir / "half.jpg", jpg.substr(0, jpg.size() / 2));
  EXPECT_EQ(rgb_error(dir / "half.jpg"),
            "truncated JPEG (no end marker); expected a PNG or JPEG image");
}

}  // namespace
}  // namespace objmap::io
