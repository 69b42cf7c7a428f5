// objmap detect: milliseconds per frame of each shared model on fr1_desk_9's frames, run by
// OpenCV's dnn (cv::setNumThreads) or ONNX Runtime (its intra-op threads) on 1 and on 2 threads.
// scripts/bench_detect.sh (make bench-detect) measures the whole command per backend.
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
#include "objmap/segmentation/ort_session.h"

namespace fs = std::filesystem;
using namespace objmap;

namespace {

using objmap::bench::data_dir;

// Arg 0: the model (0 Yolo-Fastest-1.1-xl 320x320, 1 YOLOv5n-seg 480x640, 2 YOLOv5n-seg 640x640
// letterboxed, 3 YOLOv8n-seg 640x640 letterboxed); Arg 1: threads; Arg 2: the backend (0 OpenCV's
// dnn, 1 ONNX Runtime: ONNX models only, skipped when it is not installed).
void BM_DetectFrame(benchmark::State& state) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
  const fs::path models = data_dir() / ".." / "models";
  const fs::path files[] = {models / "yolo-fastest-1.1_coco" / "yolo-fastest-1.1-xl.weights",
                            models / "yolov5n-seg_coco" / "yolov5n-seg_480x640.onnx",
                            models / "yolov5n-seg_coco" / "yolov5n-seg_640x640.onnx",
                            models / "yolov8n-seg_coco" / "yolov8n-seg_640x640.onnx"};
  const fs::path dataset = data_dir() / "tum" / "fr1_desk_9";
  const fs::path model = files[state.range(0)];
  if (!fs::exists(model) || !fs::exists(dataset)) {
    state.SkipWithError("models or data missing (OBJMAP_DATA)");
    return;
  }
  const bool ort = state.range(2) == 1;
  if (ort && (state.range(0) == 0 || !segmentation::onnxruntime_status().available)) {
    state.SkipWithError("ONNX Runtime: ONNX models only, when installed");
    return;
  }
  cv::setNumThreads(static_cast<int>(state.range(1)));
  segmentation::DetectOptions options;
  options.model = model;
  options.backend = ort ? "onnxruntime" : "opencv";
  options.threads = static_cast<int>(state.range(1));
  segmentation::Detector detector(options);
  std::vector<cv::Mat> images;
  for (const auto& frame : segmentation::list_rgb_frames(dataset))
    images.push_back(io::read_rgb(frame.rgb_file, 640, 480));
  std::size_t instances = 0;
  for (auto _ : state)
    for (const cv::Mat& image : images) instances += detector.detect(image).size();
  state.SetLabel(model.filename().string() + (ort ? " onnxruntime" : " opencv"));
  state.counters["ms/frame"] =
      benchmark::Counter(static_cast<double>(images.size()) * state.iterations() * 1e-3,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["instances/frame"] =
      static_cast<double>(instances) / static_cast<double>(images.size() * state.iterations());
}
BENCHMARK(BM_DetectFrame)
    ->ArgsProduct({{0, 1, 2, 3}, {1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
