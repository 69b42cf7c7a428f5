// objmap detect: milliseconds per frame of each shared model on fr1_desk_9's frames, with OpenCV
// running the network on 1 and on 2 threads (cv::setNumThreads).
//   build/bin/bench_detect [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <string>
#include <vector>

#include "bench_data.h"
#include "objmap/io/image.h"
#include "objmap/segmentation/detect.h"

namespace fs = std::filesystem;
using namespace objmap;

namespace {

using objmap::bench::data_dir;

// Arg 0: the model (0 Yolo-Fastest-1.1-xl 320x320, 1 YOLOv5n-seg 480x640, 2 YOLOv5n-seg 640x640
// letterboxed); Arg 1: OpenCV's threads.
void BM_DetectFrame(benchmark::State& state) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
  const fs::path models = data_dir() / ".." / "models";
  const fs::path files[] = {models / "yolo-fastest-1.1_coco" / "yolo-fastest-1.1-xl.weights",
                            models / "yolov5n-seg_coco" / "yolov5n-seg_480x640.onnx",
                            models / "yolov5n-seg_coco" / "yolov5n-seg_640x640.onnx"};
  const fs::path dataset = data_dir() / "tum" / "fr1_desk_9";
  const fs::path model = files[state.range(0)];
  if (!fs::exists(model) || !fs::exists(dataset)) {
    state.SkipWithError("models or data missing (OBJMAP_DATA)");
    return;
  }
  cv::setNumThreads(static_cast<int>(state.range(1)));
  segmentation::DetectOptions options;
  options.model = model;
  segmentation::Detector detector(options);
  std::vector<cv::Mat> images;
  for (const auto& frame : segmentation::list_rgb_frames(dataset))
    images.push_back(io::read_rgb(frame.rgb_file, 640, 480));
  std::size_t instances = 0;
  for (auto _ : state)
    for (const cv::Mat& image : images) instances += detector.detect(image).size();
  state.SetLabel(model.filename().string());
  state.counters["ms/frame"] =
      benchmark::Counter(static_cast<double>(images.size()) * state.iterations() * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["instances/frame"] =
      static_cast<double>(instances) / static_cast<double>(images.size() * state.iterations());
}
BENCHMARK(BM_DetectFrame)
    ->ArgsProduct({{0, 1, 2}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
