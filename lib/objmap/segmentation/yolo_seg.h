#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/segmentation/detect.h"

// Ultralytics instance-segmentation exports (YOLOv5-seg, YOLOv8-seg) as ONNX, run through OpenCV's
// dnn module: the pieces of `objmap detect --model X.onnx` that need no network, so that each can
// be tested on tensors made in the test.
//   output0, YOLOv5-seg: [1, N, 5 + C + 32]  rows cx, cy, w, h (input pixels), objectness, C class
//                                            scores (sigmoid applied), 32 mask coefficients;
//   output0, YOLOv8-seg: [1, 4 + C + 32, N]  the same columns without objectness, transposed;
//   output1:             [1, 32, H/4, W/4]   the mask prototypes.
// An instance's mask = sigmoid(coefficients · prototypes), cropped to its box at the prototypes'
// resolution, upsampled to the input size (bilinear), the letterbox undone, thresholded.
namespace objmap::segmentation {

enum class YoloSegLayout { kV5, kV8 };
const char* to_string(YoloSegLayout layout);

// How a frame is fitted into the network's input: scaled by `scale` (the same on both axes, never
// up past the input) and padded by pad_x / pad_y pixels on the left / top with grey 114 (the rest
// on the right / bottom), as Ultralytics' letterbox does. A frame of the input's size is neither.
struct Letterbox {
  int input_width = 0, input_height = 0;
  int image_width = 0, image_height = 0;
  double scale = 1.0;
  int pad_x = 0, pad_y = 0;
};
Letterbox make_letterbox(int image_width, int image_height, int input_width, int input_height);

// The network's input blob (1 × 3 × input_height × input_width, RGB / 255) of a BGR image.
cv::Mat letterbox_blob(const cv::Mat& image_bgr, const Letterbox& letterbox);
// The same into `blob`, with `canvas` for the letterboxed image: both keep their memory from frame
// to frame when the sizes stay.
void letterbox_blob(const cv::Mat& image_bgr, const Letterbox& letterbox, cv::Mat& canvas,
                    cv::Mat& blob);

// The layout of `detections` (output0) for `class_count` classes, told from its shape. Throws
// InputError(where, ...) naming both shapes when it is neither layout, or when `protos` (output1)
// is not [1, 32, h, w].
YoloSegLayout yolo_seg_layout(const cv::Mat& detections, const cv::Mat& protos,
                              std::size_t class_count, const std::string& where);

// The instances of one frame from the two outputs: score = objectness × class score (v5) or the
// class score (v8), the best class, score threshold and class filter, NMS (across classes or per
// class, as options say), boxes in the frame's pixels, masks in the frame (empty masks dropped).
// Sorted as Detector::detect sorts.
// How the masks are computed: kInBox (what detect does) on the box alone where the frame is not
// scaled into the input and the input is a whole multiple of the prototypes (else as
// kWholeImage); kWholeImage, the reference: sigmoid and upsampling over the whole prototype image,
// then cropped (Ultralytics' process_mask), for the tests and docs/benchmarks.md's figures.
enum class MaskDecode { kInBox, kWholeImage };
std::vector<Instance> decode_yolo_seg(const ModelInfo& model, const DetectOptions& options,
                                      const cv::Mat& detections, const cv::Mat& protos,
                                      const Letterbox& letterbox,
                                      MaskDecode decode = MaskDecode::kInBox);

// The shape of the first graph input of an ONNX file (ModelProto.graph.input[0], dims as written:
// -1 for a symbolic one), read from the protobuf without an ONNX library. Throws InputError naming
// the file when it is not an ONNX model or has no input.
std::vector<std::int64_t> onnx_input_shape(const std::filesystem::path& model);

}  // namespace objmap::segmentation
