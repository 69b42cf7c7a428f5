// The fast path of `objmap detect` against the reference path on real frames: ONNX Runtime and the
// masks computed on the box alone (MaskDecode::kInBox) against OpenCV's dnn and the masks computed
// over the whole prototype image (kWholeImage), YOLOv8n-seg of ../shared/models.
#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/dnn.hpp>
#include <string>

#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "objmap/segmentation/detect.h"
#include "objmap/segmentation/detect_compare.h"
#include "objmap/segmentation/ort_session.h"
#include "objmap/segmentation/yolo_seg.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

using test::fs::path;

const char* const kYoloV8 = "../models/yolov8n-seg_coco/yolov8n-seg_640x640.onnx";

// The reference path on one image: OpenCV's dnn, masks over the whole prototype image.
std::vector<Instance> reference_instances(const Detector& detector, const cv::Mat& image) {
  const ModelInfo& info = detector.info();
  cv::dnn::Net net = cv::dnn::readNetFromONNX(info.model.string());
  const Letterbox lb = make_letterbox(image.cols, image.rows, info.input_width, info.input_height);
  net.setInput(letterbox_blob(image, lb));
  std::vector<cv::Mat> outputs;
  net.forward(outputs, net.getUnconnectedOutLayersNames());
  const bool first_is_protos = outputs[0].dims == 4;
  return decode_yolo_seg(info, detector.options(), outputs[first_is_protos ? 1 : 0],
                         outputs[first_is_protos ? 0 : 1], lb, MaskDecode::kWholeImage);
}

// Every instance of the reference found again, same class, mask IoU >= 0.95, none added.
void expect_same_masks(const std::vector<Instance>& reference, const std::vector<Instance>& fast,
                       const std::string& where) {
  const MaskAgreement a = compare_masks(reference, fast);
  EXPECT_GT(a.reference, 0u) << where;
  EXPECT_EQ(a.unmatched_reference, 0u) << where;
  EXPECT_EQ(a.unmatched_other, 0u) << where;
  EXPECT_GE(a.min_iou(), 0.95) << where;
}

// The first frame of each shared sequence through `backend` and through the reference path.
void check_backend(const std::string& backend) {
  OBJMAP_DATA_OR_SKIP(model, kYoloV8);
  for (const char* sequence : {"tum/fr1_desk_9", "tum/fr1_rpy_every4"}) {
    OBJMAP_DATA_OR_SKIP(data, sequence);
    DetectOptions options;
    options.model = model;
    options.backend = backend;
    Detector detector(options);
    EXPECT_EQ(detector.info().backend.rfind(backend, 0), 0u) << detector.info().backend;
    const cv::Mat image = io::read_rgb(list_rgb_frames(data)[0].rgb_file, 640, 480);
    expect_same_masks(reference_instances(detector, image), detector.detect(image, sequence),
                      std::string(sequence) + " through " + backend);
  }
}

TEST(DetectBackend, OpenCvInBoxMasksMatchTheWholeImageMasks) { check_backend("opencv"); }

TEST(DetectBackend, OnnxRuntimeMasksMatchOpenCvsOnRealFrames) {
  if (!onnxruntime_status().available)
    GTEST_SKIP() << "ONNX Runtime is not installed (scripts/install-deps.sh installs it): "
                 << onnxruntime_status().reason;
  check_backend("onnxruntime");
}

TEST(DetectBackend, BadBackendAndThreadsAreNamed) {
  DetectOptions options;
  options.backend = "cuda";
  EXPECT_EQ(test::error_of([&] { options.check(); }),
            "DetectOptions.backend: 'cuda'; expected auto, onnxruntime or opencv");
  options.backend = "opencv";
  options.threads = -1;
  EXPECT_NE(test::error_of([&] { options.check(); }).find("DetectOptions.threads"),
            std::string::npos);
}

}  // namespace
}  // namespace objmap::segmentation
