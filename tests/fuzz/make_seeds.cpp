// Writes the image seeds of the fuzz targets that read images (png, jpeg, image) into
// OUT/<target>/: small frames made at test time with objmap's own PNG encoder (io/png_encode.h)
// and libjpeg, so that those targets have seeds without the real data and none is kept in the
// repository. Usage: fuzz_make_seeds OUT. The ctest fixture fuzz/make_seeds runs it before the
// fuzz/<target> tests; scripts/fuzz.sh adds OUT/<target> to each corpus.
#include <cstdio>  // before jpeglib.h, which uses FILE
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <jpeglib.h>

#include <opencv2/core.hpp>

#include "objmap/io/png_encode.h"

namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 64, kHeight = 48;  // the size fuzz_image requires of a frame

// A colour frame (CV_8UC3): smooth ramps and a few sharp squares, so that every PNG filter and
// JPEG block type has something to do.
cv::Mat colour_frame() {
  cv::Mat image(kHeight, kWidth, CV_8UC3);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      image.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<unsigned char>(4 * x), static_cast<unsigned char>(5 * y),
                    static_cast<unsigned char>((x / 8 + y / 8) % 2 * 200));
  return image;
}

// A depth frame (CV_16UC1, TUM's factor 5000): a slanted plane from 1 to 2 m with a hole (0).
cv::Mat depth_frame() {
  cv::Mat image(kHeight, kWidth, CV_16UC1);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      image.at<std::uint16_t>(y, x) =
          (x > 20 && x < 30 && y > 10 && y < 20) ? 0 : static_cast<std::uint16_t>(5000 + 80 * x);
  return image;
}

// A label frame (CV_8UC1): background 0 and two instances, 1 and 2.
cv::Mat label_frame() {
  cv::Mat image(kHeight, kWidth, CV_8UC1, cv::Scalar(0));
  image(cv::Rect(5, 5, 20, 15)).setTo(1);
  image(cv::Rect(30, 20, 25, 20)).setTo(2);
  return image;
}

std::vector<std::uint8_t> png_of(const cv::Mat& image) {
  std::vector<std::uint8_t> png;
  objmap::io::encode_png(image, &png);
  return png;
}

// JPEG bytes of a CV_8UC3 (BGR) or CV_8UC1 image, written by libjpeg at quality 90.
std::vector<std::uint8_t> jpeg_of(const cv::Mat& image) {
  jpeg_compress_struct info{};
  jpeg_error_mgr errors{};
  info.err = jpeg_std_error(&errors);  // (exits on an error: these images are valid)
  jpeg_create_compress(&info);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = static_cast<JDIMENSION>(image.cols);
  info.image_height = static_cast<JDIMENSION>(image.rows);
  info.input_components = image.channels();
  info.in_color_space = image.channels() == 3 ? JCS_EXT_BGR : JCS_GRAYSCALE;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, 90, TRUE);
  jpeg_start_compress(&info, TRUE);
  while (info.next_scanline < info.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(image.ptr(static_cast<int>(info.next_scanline)));
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::vector<std::uint8_t> bytes(buffer, buffer + size);
  std::free(buffer);
  return bytes;
}

void write(const fs::path& file, const std::vector<std::uint8_t>& bytes) {
  fs::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT\n", argv[0]);
    return 2;
  }
  const fs::path out = argv[1];
  try {
    const auto rgb = png_of(colour_frame()), depth = png_of(depth_frame());
    const auto labels = png_of(label_frame());
    const auto colour_jpeg = jpeg_of(colour_frame());
    cv::Mat grey;
    cv::extractChannel(colour_frame(), grey, 1);
    const auto grey_jpeg = jpeg_of(grey);
    write(out / "png" / "rgb.png", rgb);
    write(out / "png" / "depth.png", depth);
    write(out / "png" / "labels.png", labels);
    write(out / "jpeg" / "colour.jpg", colour_jpeg);
    write(out / "jpeg" / "grey.jpg", grey_jpeg);
    write(out / "image" / "rgb.png", rgb);
    write(out / "image" / "depth.png", depth);
    write(out / "image" / "labels.png", labels);
    write(out / "image" / "colour.jpg", colour_jpeg);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
    return 1;
  }
  std::printf("%s: image seeds of png, jpeg and image written to %s\n", argv[0],
              out.string().c_str());
  return 0;
}
