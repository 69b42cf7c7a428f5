#pragma once
#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/segmentation/types.h"

// Object detection with OpenCV's dnn module: the instances of an rgb image, from a model on disk
// (nothing is downloaded). Two kinds of model, told apart by the file extensions:
//   - Darknet YOLO (.cfg + .weights, e.g. Yolo-Fastest 1.1 COCO-80): boxes only; fuse turns boxes
//     into masks with the depth image (box_mask.h).
//   - TensorFlow Object Detection API Mask R-CNN (frozen_inference_graph.pb + the .pbtxt text graph
//     made by OpenCV's tf_text_graph_mask_rcnn.py), run as OpenCV's samples/dnn/mask_rcnn.py does:
//     outputs "detection_out_final" (boxes) and "detection_masks" (a 15 x 15 mask per class);
//     real instance masks.
//   - Ultralytics instance-segmentation exports as ONNX (.onnx: YOLOv5-seg, YOLOv8-seg; the layout
//     told from the output shapes, the input size read from the model, frames letterboxed into
//     it): real instance masks (yolo_seg.h).
// Everything the user can get wrong (missing or unreadable file, a model of another kind, a class
// name the model does not know, no detection at all) is an InputError naming the file or field.
namespace objmap::segmentation {

enum class ModelKind { kDarknetYolo, kTensorflowMaskRcnn, kOnnxYoloSeg };

// "darknet-yolo" | "tensorflow-mask-rcnn" | "onnx-yolo-seg".
std::string model_kind_name(ModelKind kind);

// The paper's eight classes, canonical spelling: chair, cup, tv monitor, teddy bear, bottle, book,
// keyboard, mouse.
const std::vector<std::string>& paper_detect_classes();

// The 90 class names of the TensorFlow Object Detection API COCO models (OpenCV's
// samples/data/dnn/object_detection_classes_coco.txt), canonical spelling; index = class id of
// "detection_out_final" (COCO category id - 1; the 10 ids COCO never used keep their names, e.g.
// "street sign", and are simply never predicted).
const std::vector<std::string>& coco90_names();

struct DetectOptions {
  // The weights: Darknet .weights, TensorFlow .pb or ONNX .onnx. Required.
  std::filesystem::path model;
  // The network description: Darknet .cfg (default: the model path with extension .cfg) or the
  // TensorFlow .pbtxt text graph (required for a .pb model).
  std::filesystem::path config;
  // Class names, one per line, line i = class id i ('_' and spellings such as "tvmonitor" are made
  // canonical). Default (empty): built-in COCO-80 (Darknet, coco.names order) or COCO-90 (Mask
  // R-CNN). The model's class count must match.
  std::filesystem::path classes_file;
  // Only these classes are kept (any spelling canonical_class accepts; each must be a class of
  // the model). Empty (the default): every class the model knows; paper_detect_classes() is the
  // paper's eight (`--classes paper`, the preset of the benchmark tables).
  std::vector<std::string> classes;
  // A detection is kept when its class score is >= this. 0.25: Darknet's default threshold (the
  // shared Yolo-Fastest detections go down to 0.28). Mask R-CNN's sample uses 0.5.
  double score_threshold = 0.25;
  // Non-maximum suppression: of two kept boxes overlapping with IoU > this, the lower-scored one
  // goes. 0.45: Darknet's and OpenCV's sample value. (Mask R-CNN's graph has its own per-class NMS;
  // this one runs on its output as well.)
  double nms_threshold = 0.45;
  // true: NMS across classes (one box per object, whatever its class: a monitor seen as both "tv
  // monitor" and "laptop" stays one detection; the shared detections_yolofastest were made so).
  // false: per class, as OpenCV's object_detection sample. The class filter applies before NMS.
  bool nms_across_classes = true;
  // Network input size in pixels; 0 = the model's own: the cfg's width/height for Darknet (320 x
  // 320 for Yolo-Fastest), 800 x 800 for Mask R-CNN (OpenCV's sample), the graph input's for ONNX.
  // Multiples of 32 for YOLO.
  int input_width = 0, input_height = 0;
  // Mask R-CNN and ONNX segmentation: a pixel of the box belongs to the object when its resized
  // mask value is > this (0.5 as the OpenCV sample and Ultralytics).
  double mask_threshold = 0.5;
  // What runs an ONNX model: "auto" (the default: ONNX Runtime when its library is installed,
  // else OpenCV's dnn; docs/benchmarks.md, "Speed of detect": ONNX Runtime runs YOLOv8n-seg about
  // 3x faster), "onnxruntime" (required; an InputError saying how to install it when absent) or
  // "opencv". Darknet and TensorFlow models always run in OpenCV's dnn.
  std::string backend = "auto";
  // Threads of the network: ONNX Runtime's intra-op threads (OpenCV's dnn takes
  // cv::setNumThreads, set by the caller); 0: the backend's default (the cores).
  int threads = 0;
  // Throws InputError naming the bad field.
  void check() const;
};

// What the loaded model is.
struct ModelInfo {
  ModelKind kind = ModelKind::kDarknetYolo;
  std::filesystem::path model, config;
  int input_width = 0, input_height = 0;  // the input size actually used
  std::vector<std::string> class_names;   // canonical, index = class id
  std::vector<int> kept_class_ids;        // the class filter as ids (all ids when no filter)
  std::string backend = "opencv";         // what runs it: "opencv" or "onnxruntime 1.29.0"
};

// A loaded network (state: OpenCV's net), run frame by frame. Not copyable; one per thread.
class Detector {
 public:
  // Loads the model. Throws InputError for a missing or unreadable file, an unsupported kind, a
  // network that is not a detector of that kind (no YOLO output layer, no "detection_out_final"),
  // a class file that does not fit the model, a class name the model does not know.
  explicit Detector(const DetectOptions& options);
  ~Detector();
  Detector(const Detector&) = delete;
  Detector& operator=(const Detector&) = delete;

  const ModelInfo& info() const;
  const DetectOptions& options() const;

  // The instances of one BGR image (CV_8UC3, any size): boxes in the image's pixels (clamped to
  // it), class names canonical, scores rounded to 1e-6, sorted by class id then decreasing score
  // (deterministic). Mask R-CNN instances carry a full-image mask. `where` names the image in
  // messages.
  std::vector<Instance> detect(const cv::Mat& image_bgr, const std::string& where = "image");

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The post-processing alone, the network's outputs for one image of width x height pixels ->
// instances as Detector::detect returns them (score threshold, class filter, NMS, boxes in pixels,
// Mask R-CNN masks). Exposed so that it can be tested without model weights. `outputs`:
//   YOLO: the [yolo] layers' outputs, rows [cx, cy, w, h, objectness, one score per class] with
//         positions in fractions of the image;
//   Mask R-CNN: {detection_out_final 1 x 1 x N x 7 rows [batch, class id, score, x1, y1, x2, y2]
//         (fractions of the image), detection_masks N x classes x h x w (15 x 15 for the TF
//         models)}.
// Throws InputError when the class count of the outputs is not that of model.class_names.
std::vector<Instance> decode_outputs(const ModelInfo& model, const DetectOptions& options,
                                     const std::vector<cv::Mat>& outputs, int image_width,
                                     int image_height);

// One frame to detect on: rgb timestamp and image file.
struct DetectFrame {
  double timestamp = 0;
  std::filesystem::path rgb_file;
  // Reads the frame's colour image (CV_8UC3 BGR) where it is not an image file (a frame of a ROS
  // bag); empty: rgb_file is read.
  std::function<cv::Mat()> read;
};

// The frames of a TUM folder: every row of `dataset`/rgb.txt (strict `timestamp filename` lines,
// increasing timestamps). Depth is not needed. Throws InputError for a missing folder or rgb.txt,
// a bad line, no row.
std::vector<DetectFrame> list_rgb_frames(const std::filesystem::path& dataset);

struct DetectResult {
  Segmentation segmentation;  // format "json", one frame per input frame (possibly empty)
  ModelInfo model;
  std::size_t frames = 0, frames_with_detections = 0, instances = 0;
  std::map<std::string, std::size_t> instances_per_class;  // canonical name -> count
  double seconds = 0;  // wall time of loading the network (when detect_frames loads it), reading
                       // the images and running the network on all frames
};

// Runs the detector on every frame (images read strictly with io::read_rgb, or DetectFrame::read;
// the next frame's on a second thread while the network runs, one call at a time). `progress(done,
// total)` is called after each frame when given. Throws InputError as Detector does, for an
// unreadable image, and when no frame has any detection ("no detections in any of the N frames").
DetectResult detect_frames(const std::vector<DetectFrame>& frames, const DetectOptions& options,
                           const std::string& where,
                           const std::function<void(std::size_t, std::size_t)>& progress = {});
// The same with a detector already loaded (seconds then count the frames only).
DetectResult detect_frames(Detector& detector, const std::vector<DetectFrame>& frames,
                           const std::string& where,
                           const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace objmap::segmentation
