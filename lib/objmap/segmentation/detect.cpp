#include "objmap/segmentation/detect.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <future>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "objmap/io/text_lines.h"
#include "objmap/segmentation/coco_classes.h"
#include "objmap/segmentation/detect_internal.h"
#include "objmap/segmentation/ort_session.h"
#include "objmap/segmentation/yolo_seg.h"

namespace objmap::segmentation {

namespace fs = std::filesystem;

namespace {

std::string lower_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// OpenCV's own message on one line (its `err` part, blanks collapsed).
std::string one_line(const std::string& text) {
  std::string out;
  bool space = false;
  for (char c : text) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      space = !out.empty();
      continue;
    }
    if (space) out.push_back(' ');
    space = false;
    out.push_back(c);
  }
  return out;
}

// A model file must exist and be readable before OpenCV sees it (OpenCV's messages about a missing
// file are long and name no file).
void require_readable(const fs::path& file, const std::string& expected) {
  require(!file.empty(), "model", "no file given; expected " + expected);
  require(fs::exists(file), file.string(), "no such file; expected " + expected);
  require(fs::is_regular_file(file), file.string(), "not a file; expected " + expected);
  std::ifstream in(file, std::ios::binary);
  require(static_cast<bool>(in), file.string(), "cannot be read; expected " + expected);
  require(fs::file_size(file) > 0, file.string(), "empty file; expected " + expected);
}

const char* const kDarknetExpected = "a Darknet YOLO model: .weights with its .cfg";
const char* const kOnnxExpected =
    "an Ultralytics instance-segmentation export (YOLOv5-seg or YOLOv8-seg .onnx)";
const char* const kTfExpected =
    "a TensorFlow Mask R-CNN frozen_inference_graph.pb with its .pbtxt text graph (--config)";

// The parameters a Darknet .weights file holds after its header (major, minor, revision: int32;
// images seen: int64 from version 0.2 on, else int32), in float32; -1 when the header is short or
// the rest is not whole floats.
long long darknet_weight_count(const fs::path& weights) {
  std::ifstream in(weights, std::ios::binary);
  std::int32_t version[3] = {0, 0, 0};
  if (!in.read(reinterpret_cast<char*>(version), sizeof version)) return -1;
  const std::uintmax_t header = 12 + (version[0] * 10 + version[1] >= 2 ? 8 : 4);
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(weights, ec);
  if (ec || size < header || (size - header) % 4 != 0) return -1;
  return static_cast<long long>((size - header) / 4);
}

// The parameters of a loaded Darknet network that come from its .weights file: the elements of the
// layers' blobs (convolution weights and biases; batch-norm scales, biases, means and variances),
// before any fusion, without the [yolo]/[region] layers' anchors (from the cfg).
long long network_weight_count(cv::dnn::Net& net) {
  long long n = 0;
  for (const std::string& name : net.getLayerNames()) {
    const cv::Ptr<cv::dnn::Layer> layer = net.getLayer(net.getLayerId(name));
    if (layer->type == "Region") continue;
    for (const cv::Mat& blob : layer->blobs) n += static_cast<long long>(blob.total());
  }
  return n;
}

// width= and height= of the [net] section of a Darknet cfg; 0 when absent.
void darknet_input_size(const fs::path& cfg, int& width, int& height) {
  std::ifstream in(cfg);
  std::string line;
  bool in_net = false;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::string text;
    for (char c : line)
      if (!std::isspace(static_cast<unsigned char>(c))) text.push_back(c);
    if (text.empty() || text[0] == '#' || text[0] == ';') continue;
    if (text[0] == '[') {
      in_net = text == "[net]" || text == "[network]";
      continue;
    }
    if (!in_net) continue;
    const auto eq = text.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = text.substr(0, eq);
    if (key != "width" && key != "height") continue;
    const std::string where = cfg.string() + ":" + std::to_string(line_number);
    const auto value = io::parse_int(text.substr(eq + 1), where, key);
    require(value > 0 && value <= 4096, where,
            key + " is " + std::to_string(value) + "; expected a size in pixels in 1..4096");
    (key == "width" ? width : height) = static_cast<int>(value);
  }
}

// Class names of a file: one per line, line i = id i, canonical spelling.
std::vector<std::string> read_class_names(const fs::path& file) {
  require(fs::exists(file), file.string(), "no such file; expected class names, one per line");
  std::ifstream in(file);
  require(static_cast<bool>(in), file.string(), "cannot be read; expected class names");
  std::vector<std::string> names;
  std::vector<int> lines;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    names.push_back(canonical_class(line));
    lines.push_back(line_number);
  }
  while (!names.empty() && names.back().empty()) {
    names.pop_back();
    lines.pop_back();
  }
  require(!names.empty(), file.string(), "no class name; expected one name per line");
  for (std::size_t i = 0; i < names.size(); ++i)
    require(!names[i].empty(), file.string() + ":" + std::to_string(lines[i]),
            "empty class name; expected one name per line (line i = class id i - 1)");
  return names;
}

// The files a model of that kind needs, for messages.
std::string expected_files(ModelKind kind) {
  return kind == ModelKind::kDarknetYolo   ? kDarknetExpected
         : kind == ModelKind::kOnnxYoloSeg ? kOnnxExpected
                                           : kTfExpected;
}

// Step 1 of loading: the kind, from the extensions, and the model's files (info.kind, model,
// config), which must be readable.
void model_kind_and_files(const DetectOptions& options, ModelInfo& info) {
  const std::string ext = lower_extension(options.model);
  if (ext == ".weights" || ext == ".cfg") {
    info.kind = ModelKind::kDarknetYolo;
    fs::path weights = options.model, cfg = options.config;
    if (ext == ".cfg") std::swap(weights, cfg);
    if (weights.empty()) weights = fs::path(options.model).replace_extension(".weights");
    if (cfg.empty()) cfg = fs::path(options.model).replace_extension(".cfg");
    require(lower_extension(cfg) == ".cfg", cfg.string(),
            "a Darknet model's network description must be a .cfg file; expected " +
                std::string(kDarknetExpected));
    require(lower_extension(weights) == ".weights", weights.string(),
            "a Darknet model's weights must be a .weights file; expected " +
                std::string(kDarknetExpected));
    info.model = weights;
    info.config = cfg;
  } else if (ext == ".pb") {
    info.kind = ModelKind::kTensorflowMaskRcnn;
    info.config = options.config;
    require(!info.config.empty(), options.model.string(),
            "a TensorFlow .pb model needs its text graph; expected --config <graph>.pbtxt (made "
            "by OpenCV's tf_text_graph_mask_rcnn.py)");
    require(lower_extension(info.config) == ".pbtxt", info.config.string(),
            "a TensorFlow model's text graph must be a .pbtxt file; expected " +
                std::string(kTfExpected));
  } else if (ext == ".onnx") {
    info.kind = ModelKind::kOnnxYoloSeg;  // the whole network is the one file
    info.config = options.model;
  } else {
    throw InputError(options.model.string(),
                     "unsupported model kind '" +
                         (ext.empty() ? std::string("(no extension)") : ext) + "'; expected " +
                         kDarknetExpected + ", " + kTfExpected + ", or " + kOnnxExpected);
  }
  const std::string expected = expected_files(info.kind);
  require_readable(info.model, expected);
  require_readable(info.config, expected);
}

// Step 2 of loading: the network, on OpenCV's CPU backend; OpenCV's parser errors become one line
// naming the file. A Darknet network must hold as many weights as its cfg asks for.
cv::dnn::Net load_network(const ModelInfo& info) {
  const std::string expected = expected_files(info.kind);
  cv::dnn::Net net;
  try {
    if (info.kind == ModelKind::kDarknetYolo) {
      net = cv::dnn::readNetFromDarknet(info.config.string(), info.model.string());
    } else if (info.kind == ModelKind::kOnnxYoloSeg) {
      net = cv::dnn::readNetFromONNX(info.model.string());
    } else {
      net = cv::dnn::readNetFromTensorflow(info.model.string(), info.config.string());
    }
  } catch (const cv::Exception& e) {
    const std::string with =
        info.config == info.model ? std::string() : " with " + info.config.string();
    throw InputError(info.model.string(), "OpenCV cannot load it" + with + " (" + one_line(e.err) +
                                              "); expected " + expected);
  }
  require(!net.empty(), info.model.string(),
          "OpenCV loaded an empty network; expected " + expected);
  if (info.kind == ModelKind::kDarknetYolo) {
    // OpenCV reads as many weights as the cfg asks for and says nothing of a file that holds fewer
    // (truncated) or more (another cfg): either detects nothing. The counts must agree.
    const long long in_file = darknet_weight_count(info.model);
    const long long in_net = network_weight_count(net);
    require(in_file >= 0, info.model.string(),
            "not a Darknet weights file (a header of 3 or 4 integers, then float32 values); "
            "expected " +
                expected);
    require(in_file == in_net, info.model.string(),
            "holds " + std::to_string(in_file) + " weights, " +
                (in_file < in_net ? "fewer" : "more") + " than the " + std::to_string(in_net) +
                " that " + info.config.filename().string() + " asks for (" +
                (in_file < in_net ? "truncated, or made for another cfg" : "made for another cfg") +
                "); expected the .weights trained with this .cfg");
  }
  net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return net;
}

// An instance-segmentation export has two outputs: the detections and the mask prototypes.
void require_two_outputs(std::size_t outputs, const ModelInfo& info) {
  require(outputs == 2, info.model.string(),
          "has " + std::to_string(outputs) +
              " output(s); expected 2, the detections and the mask prototypes of " + kOnnxExpected +
              " (a detector without masks cannot give instance masks)");
}

// Step 3 of loading: the outputs to read, YOLO region layers or Mask R-CNN's two outputs (the
// network must be a detector of its kind), and the input size (info.input_width/height).
std::vector<std::string> detector_outputs(cv::dnn::Net& net, const DetectOptions& options,
                                          ModelInfo& info) {
  std::vector<std::string> output_names;
  if (info.kind == ModelKind::kDarknetYolo) {
    for (const auto& name : net.getUnconnectedOutLayersNames()) {
      const auto layer = net.getLayer(net.getLayerId(name));
      if (layer && layer->type == "Region") output_names.push_back(name);
    }
    require(!output_names.empty(), info.config.string(),
            "the network has no [yolo] or [region] output layer; expected a Darknet YOLO "
            "detector");
    int width = 0, height = 0;
    darknet_input_size(info.config, width, height);
    info.input_width = options.input_width > 0 ? options.input_width : width;
    info.input_height = options.input_height > 0 ? options.input_height : height;
    require(info.input_width > 0 && info.input_height > 0, info.config.string(),
            "no width/height in its [net] section; expected them, or an input size option");
  } else if (info.kind == ModelKind::kOnnxYoloSeg) {
    // An instance-segmentation export has two outputs (the detections, the mask prototypes); its
    // input is [1, 3, H, W] (or the size asked for).
    output_names = net.getUnconnectedOutLayersNames();
    require_two_outputs(output_names.size(), info);
    const std::vector<std::int64_t> shape = onnx_input_shape(info.model);
    const bool known = shape.size() == 4 && shape[2] > 0 && shape[3] > 0;
    info.input_width =
        options.input_width > 0 ? options.input_width : (known ? static_cast<int>(shape[3]) : 640);
    info.input_height = options.input_height > 0 ? options.input_height
                                                 : (known ? static_cast<int>(shape[2]) : 640);
  } else {
    for (const char* name : {"detection_out_final", "detection_masks"}) {
      require(net.getLayerId(name) >= 0, info.config.string(),
              std::string("the graph has no layer '") + name +
                  "'; expected a Mask R-CNN text graph made by OpenCV's "
                  "tf_text_graph_mask_rcnn.py");
      output_names.push_back(name);
    }
    info.input_width = options.input_width > 0 ? options.input_width : 800;
    info.input_height = options.input_height > 0 ? options.input_height : 800;
  }
  return output_names;
}

// Steps 2-3 of loading with ONNX Runtime: two outputs (detections, prototypes); the input size is
// the model's unless it takes any (a symbolic dimension).
void onnx_runtime_outputs(const OnnxRuntimeSession& session, const DetectOptions& options,
                          ModelInfo& info) {
  require_two_outputs(session.output_count(), info);
  const std::vector<std::int64_t>& shape = session.input_shape();
  require(shape.size() == 4, info.model.string(),
          "its input has " + std::to_string(shape.size()) + " dimensions; expected [1, 3, H, W]");
  const auto size = [&](int asked, std::int64_t model, const char* what) {
    require(asked == 0 || model <= 0 || asked == model, "DetectOptions.input_width/input_height",
            std::string("the model's input ") + what + " is fixed at " + std::to_string(model) +
                " in ONNX Runtime; expected 0 (the model's size)");
    return asked > 0 ? asked : model > 0 ? static_cast<int>(model) : 640;
  };
  info.input_width = size(options.input_width, shape[3], "width");
  info.input_height = size(options.input_height, shape[2], "height");
  info.backend = "onnxruntime " + onnxruntime_status().version;
}

// Step 4 of loading: the class names (info.class_names: the classes file's, else the built-in
// names of the kind) and the filter (info.kept_class_ids); returns where the names come from.
std::string class_names_and_filter(const DetectOptions& options, ModelInfo& info) {
  std::string class_source;  // for messages: the classes file or "the built-in COCO-80 names"
  if (!options.classes_file.empty()) {
    info.class_names = read_class_names(options.classes_file);
    class_source = options.classes_file.string();
  } else if (info.kind != ModelKind::kTensorflowMaskRcnn) {
    info.class_names = coco80_names();
    class_source = "the built-in COCO-80 names";
  } else {
    info.class_names = coco90_names();
    class_source = "the built-in COCO-90 names of the TensorFlow models";
  }
  std::vector<bool> kept(info.class_names.size(), options.classes.empty());
  for (const auto& wanted : options.classes) {
    const std::string name = canonical_class(wanted);
    const auto it = std::find(info.class_names.begin(), info.class_names.end(), name);
    require(it != info.class_names.end(), "DetectOptions.classes",
            "'" + wanted + "' is not a class of the model (" + class_source + ", " +
                std::to_string(info.class_names.size()) +
                " names); expected names such as 'chair', 'cup', 'tv monitor', 'keyboard'");
    kept[static_cast<std::size_t>(it - info.class_names.begin())] = true;
  }
  for (std::size_t i = 0; i < kept.size(); ++i)
    if (kept[i]) info.kept_class_ids.push_back(static_cast<int>(i));
  return class_source;
}

double round_to(double value, double step) { return std::round(value / step) * step; }

using detail::Candidate;
using detail::suppress_non_maxima;

// What the decoding steps share: the image size and the classes of the model that are kept.
struct DecodeContext {
  DecodeContext(const ModelInfo& info_, const DetectOptions& options_, int width_, int height_)
      : info(info_),
        options(options_),
        width(width_),
        height(height_),
        class_count(info_.class_names.size()),
        classes_where(options_.classes_file.empty() ? info_.model.string()
                                                    : options_.classes_file.string()),
        kept_class(class_count, false) {
    for (int id : info.kept_class_ids)
      if (id >= 0 && static_cast<std::size_t>(id) < class_count) kept_class[id] = true;
  }

  // The box with corners (x1, y1), (x2, y2) clamped to the image.
  cv::Rect2d clamp_box(double x1, double y1, double x2, double y2) const {
    x1 = std::clamp(x1, 0.0, static_cast<double>(width));
    x2 = std::clamp(x2, 0.0, static_cast<double>(width));
    y1 = std::clamp(y1, 0.0, static_cast<double>(height));
    y2 = std::clamp(y2, 0.0, static_cast<double>(height));
    return cv::Rect2d(x1, y1, x2 - x1, y2 - y1);
  }

  const ModelInfo& info;
  const DetectOptions& options;
  const int width, height;          // the image, pixels
  const std::size_t class_count;    // of the model
  const std::string classes_where;  // where the class names come from, for messages
  std::vector<bool> kept_class;     // per class id
};

// Step 2, YOLO: each row of an output is centre x, centre y, width, height (fractions of the
// image), objectness, then one score per class (objectness already multiplied in). The class is
// the best-scored one (OpenCV's object_detection sample), then the class filter applies.
std::vector<Candidate> yolo_candidates(const DecodeContext& c,
                                       const std::vector<cv::Mat>& outputs) {
  std::vector<Candidate> candidates;
  for (const cv::Mat& out : outputs) {
    require(out.dims == 2 && out.cols == static_cast<int>(c.class_count) + 5, c.classes_where,
            std::to_string(c.class_count) + " class names but the model outputs " +
                std::to_string(out.cols - 5) + " classes; expected a classes file that fits");
    for (int r = 0; r < out.rows; ++r) {
      const float* row = out.ptr<float>(r);
      const float* best = std::max_element(row + 5, row + out.cols);
      const int class_id = static_cast<int>(best - (row + 5));
      if (*best < c.options.score_threshold || *best <= 0.f || !c.kept_class[class_id]) continue;
      const double cx = row[0] * c.width, cy = row[1] * c.height;
      const double w = row[2] * c.width, h = row[3] * c.height;
      const cv::Rect2d box = c.clamp_box(cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2);
      if (box.width <= 0 || box.height <= 0) continue;
      candidates.push_back({class_id, *best, box, r});
    }
  }
  return candidates;
}

// Step 2, Mask R-CNN: "detection_out_final", 1 x 1 x N x 7 rows [batch, class id, score, x1, y1,
// x2, y2] in fractions of the image; "detection_masks", N x classes x 15 x 15 (OpenCV's mask_rcnn
// sample).
std::vector<Candidate> mask_rcnn_candidates(const DecodeContext& c,
                                            const std::vector<cv::Mat>& outputs) {
  const ModelInfo& info = c.info;
  require(outputs.size() == 2, info.config.string(),
          "expected two outputs (detection_out_final, detection_masks)");
  const cv::Mat& boxes = outputs[0];
  const cv::Mat& masks = outputs[1];
  require(
      boxes.dims == 4 && boxes.size[3] == 7 && masks.dims == 4 && masks.size[0] >= boxes.size[2],
      info.config.string(),
      "unexpected output shapes; expected a Mask R-CNN graph (detection_out_final N x 7, "
      "detection_masks N x classes x h x w)");
  require(masks.size[1] == static_cast<int>(c.class_count), c.classes_where,
          std::to_string(c.class_count) + " class names but the model outputs " +
              std::to_string(masks.size[1]) + " classes; expected a classes file that fits");
  std::vector<Candidate> candidates;
  const int count = boxes.size[2];
  const float* rows = boxes.ptr<float>();
  for (int i = 0; i < count; ++i) {
    const float* row = rows + 7 * i;
    const int class_id = static_cast<int>(row[1]);
    const float score = row[2];
    if (class_id < 0 || class_id >= static_cast<int>(c.class_count)) continue;
    if (score < c.options.score_threshold || score <= 0.f || !c.kept_class[class_id]) continue;
    const cv::Rect2d box =
        c.clamp_box(row[3] * c.width, row[4] * c.height, row[5] * c.width, row[6] * c.height);
    if (box.width < 1 || box.height < 1) continue;
    candidates.push_back({class_id, score, box, i});
  }
  return candidates;
}

// Step 4, Mask R-CNN: the candidate's class mask resized to its box and thresholded (the sample's
// way), placed in a full-image mask; its area (0: nothing of the object survives the threshold).
std::size_t mask_rcnn_mask(const DecodeContext& c, const Candidate& candidate, const cv::Mat& masks,
                           Mask& mask) {
  const int width = c.width, height = c.height;
  const cv::Rect2d& box = candidate.box;
  const int left = std::clamp(static_cast<int>(box.x), 0, width - 1);
  const int top = std::clamp(static_cast<int>(box.y), 0, height - 1);
  const int right = std::clamp(static_cast<int>(box.x + box.width), left, width - 1);
  const int bottom = std::clamp(static_cast<int>(box.y + box.height), top, height - 1);
  const int mask_h = masks.size[2], mask_w = masks.size[3];
  const cv::Mat class_mask(
      mask_h, mask_w, CV_32F,
      const_cast<float*>(masks.ptr<float>(candidate.source, candidate.class_id)));
  cv::Mat resized;
  cv::resize(class_mask, resized, cv::Size(right - left + 1, bottom - top + 1));
  mask.width = width;
  mask.height = height;
  mask.data.assign(static_cast<std::size_t>(width) * height, 0);
  std::size_t area = 0;
  for (int v = 0; v < resized.rows; ++v) {
    const float* src = resized.ptr<float>(v);
    for (int u = 0; u < resized.cols; ++u)
      if (src[u] > c.options.mask_threshold) {
        mask.data[static_cast<std::size_t>(top + v) * width + left + u] = 1;
        ++area;
      }
  }
  return area;
}

// Step 4: instances: boxes (x, y, w, h) to 1/100 px, scores to 1e-6; with Mask R-CNN's `masks`
// (nullptr for YOLO), the instance's mask, and no instance when nothing of it survives.
std::vector<Instance> to_instances(const DecodeContext& c, const std::vector<Candidate>& kept,
                                   const cv::Mat* masks) {
  std::vector<Instance> instances;
  for (const auto& candidate : kept) {
    Instance instance;
    instance.class_name = c.info.class_names[static_cast<std::size_t>(candidate.class_id)];
    instance.score = round_to(candidate.score, 1e-6);
    const cv::Rect2d& box = candidate.box;
    instance.bbox = {round_to(box.x, 0.01), round_to(box.y, 0.01), round_to(box.width, 0.01),
                     round_to(box.height, 0.01)};
    if (masks != nullptr) {
      Mask mask;
      if (mask_rcnn_mask(c, candidate, *masks, mask) == 0) continue;
      instance.mask = std::move(mask);
    }
    instances.push_back(std::move(instance));
  }
  return instances;
}

}  // namespace

namespace detail {

// Non-maximum suppression (step 3 of decoding), over all kept classes at once (default) or per
// class; the kept candidates sorted by class id, then score.
std::vector<Candidate> suppress_non_maxima(const std::vector<Candidate>& candidates,
                                           const DetectOptions& options) {
  std::vector<Candidate> kept;
  std::set<int> classes;
  for (const auto& c : candidates) classes.insert(options.nms_across_classes ? -1 : c.class_id);
  for (int class_id : classes) {
    std::vector<cv::Rect2d> boxes;
    std::vector<float> scores;
    std::vector<const Candidate*> members;
    for (const auto& c : candidates)
      if (class_id == -1 || c.class_id == class_id) {
        boxes.push_back(c.box);
        scores.push_back(c.score);
        members.push_back(&c);
      }
    std::vector<int> indices;
    cv::dnn::NMSBoxes(boxes, scores, static_cast<float>(options.score_threshold),
                      static_cast<float>(options.nms_threshold), indices);
    for (int i : indices) kept.push_back(*members[static_cast<std::size_t>(i)]);
  }
  std::sort(kept.begin(), kept.end(), [](const Candidate& a, const Candidate& b) {
    if (a.class_id != b.class_id) return a.class_id < b.class_id;
    if (a.score != b.score) return a.score > b.score;
    if (a.box.x != b.box.x) return a.box.x < b.box.x;
    return a.box.y < b.box.y;
  });
  return kept;
}

}  // namespace detail

std::string model_kind_name(ModelKind kind) {
  switch (kind) {
    case ModelKind::kDarknetYolo:
      return "darknet-yolo";
    case ModelKind::kTensorflowMaskRcnn:
      return "tensorflow-mask-rcnn";
    case ModelKind::kOnnxYoloSeg:
      return "onnx-yolo-seg";
  }
  return "unknown";
}

const std::vector<std::string>& paper_detect_classes() {
  static const std::vector<std::string> names{"chair",  "cup",  "tv monitor", "teddy bear",
                                              "bottle", "book", "keyboard",   "mouse"};
  return names;
}

const std::vector<std::string>& coco90_names() {
  static const std::vector<std::string> names = [] {
    const std::vector<std::string> raw = {
        "person",       "bicycle",      "car",           "motorcycle",    "airplane",
        "bus",          "train",        "truck",         "boat",          "traffic light",
        "fire hydrant", "street sign",  "stop sign",     "parking meter", "bench",
        "bird",         "cat",          "dog",           "horse",         "sheep",
        "cow",          "elephant",     "bear",          "zebra",         "giraffe",
        "hat",          "backpack",     "umbrella",      "shoe",          "eye glasses",
        "handbag",      "tie",          "suitcase",      "frisbee",       "skis",
        "snowboard",    "sports ball",  "kite",          "baseball bat",  "baseball glove",
        "skateboard",   "surfboard",    "tennis racket", "bottle",        "plate",
        "wine glass",   "cup",          "fork",          "knife",         "spoon",
        "bowl",         "banana",       "apple",         "sandwich",      "orange",
        "broccoli",     "carrot",       "hot dog",       "pizza",         "donut",
        "cake",         "chair",        "couch",         "potted plant",  "bed",
        "mirror",       "dining table", "window",        "desk",          "toilet",
        "door",         "tv",           "laptop",        "mouse",         "remote",
        "keyboard",     "cell phone",   "microwave",     "oven",          "toaster",
        "sink",         "refrigerator", "blender",       "book",          "clock",
        "vase",         "scissors",     "teddy bear",    "hair drier",    "toothbrush"};
    std::vector<std::string> out;
    for (const auto& n : raw) out.push_back(canonical_class(n));
    return out;
  }();
  return names;
}

void DetectOptions::check() const {
  require(std::isfinite(score_threshold) && score_threshold >= 0 && score_threshold <= 1,
          "DetectOptions.score_threshold",
          "is " + std::to_string(score_threshold) + "; expected a score in [0, 1]");
  require(std::isfinite(nms_threshold) && nms_threshold > 0 && nms_threshold <= 1,
          "DetectOptions.nms_threshold",
          "is " + std::to_string(nms_threshold) + "; expected an IoU in (0, 1]");
  require(std::isfinite(mask_threshold) && mask_threshold >= 0 && mask_threshold < 1,
          "DetectOptions.mask_threshold",
          "is " + std::to_string(mask_threshold) + "; expected a value in [0, 1)");
  require(input_width >= 0 && input_width <= 4096 && input_height >= 0 && input_height <= 4096,
          "DetectOptions.input_width/input_height",
          "are " + std::to_string(input_width) + " x " + std::to_string(input_height) +
              "; expected 0 (the model's size) or a size in pixels up to 4096");
  require((input_width == 0) == (input_height == 0), "DetectOptions.input_width/input_height",
          "only one is set; expected both or neither");
  for (const auto& name : classes)
    require(!canonical_class(name).empty(), "DetectOptions.classes",
            "an empty class name; expected names");
  require(backend == "auto" || backend == "onnxruntime" || backend == "opencv",
          "DetectOptions.backend", "'" + backend + "'; expected auto, onnxruntime or opencv");
  require(threads >= 0 && threads <= 64, "DetectOptions.threads",
          "is " + std::to_string(threads) + "; expected 0 (the cores) to 64");
}

struct Detector::Impl {
  ModelInfo info;
  DetectOptions options;
  cv::dnn::Net net;                         // OpenCV's dnn, or
  std::unique_ptr<OnnxRuntimeSession> ort;  // ONNX Runtime (ONNX models)
  std::vector<std::string> output_names;
  std::string class_source;  // for messages: the classes file or "the built-in COCO-80 names"
  cv::Mat canvas, blob;      // ONNX: the letterboxed frame and the network input, reused
  std::vector<Instance> detect_onnx_seg(const cv::Mat& image_bgr, const std::string& where);
};

Detector::Detector(const DetectOptions& options) : impl_(std::make_unique<Impl>()) {
  options.check();
  Impl& d = *impl_;
  d.options = options;
  ModelInfo& info = d.info;
  info.model = options.model;
  require(!options.model.empty(), "model", "no model given; expected a .weights or .pb file");
  require(fs::exists(options.model), options.model.string(),
          "no such file; expected " + std::string(kDarknetExpected) + ", " + kTfExpected + ", or " +
              kOnnxExpected);

  // 1. The kind, from the extensions.
  model_kind_and_files(options, info);

  // 2. The network; OpenCV's parser errors become one line naming the file. An ONNX model runs in
  // ONNX Runtime when asked or (auto) when its library is there.
  const bool onnx = info.kind == ModelKind::kOnnxYoloSeg;
  require(
      onnx || options.backend != "onnxruntime", "DetectOptions.backend",
      "onnxruntime runs ONNX models only; expected auto or opencv for " + options.model.string());
  if (onnx && (options.backend == "onnxruntime" ||
               (options.backend == "auto" && onnxruntime_status().available))) {
    d.ort = std::make_unique<OnnxRuntimeSession>(info.model, options.threads);
    onnx_runtime_outputs(*d.ort, options, info);
  } else {
    d.net = load_network(info);
    // 3. It must be a detector of that kind: YOLO region outputs, or Mask R-CNN's two outputs.
    d.output_names = detector_outputs(d.net, options, info);
  }

  // 4. Class names and the filter.
  d.class_source = class_names_and_filter(options, info);
}

Detector::~Detector() = default;

const ModelInfo& Detector::info() const { return impl_->info; }

const DetectOptions& Detector::options() const { return impl_->options; }

// An Ultralytics segmentation export on one image: letterboxed into the input (buffers reused),
// run (ONNX Runtime or OpenCV), decoded (yolo_seg.h); the output with 4 dimensions is the
// prototypes, the other the detections.
std::vector<Instance> Detector::Impl::detect_onnx_seg(const cv::Mat& image_bgr,
                                                      const std::string& where) {
  const Letterbox lb =
      make_letterbox(image_bgr.cols, image_bgr.rows, info.input_width, info.input_height);
  std::vector<cv::Mat> outputs;
  try {
    letterbox_blob(image_bgr, lb, canvas, blob);
    if (ort) {
      outputs = ort->run(blob, where);
    } else {
      net.setInput(blob);
      net.forward(outputs, output_names);
    }
  } catch (const cv::Exception& e) {
    throw InputError(info.model.string(),
                     "OpenCV cannot run the network on " + where + " (" + one_line(e.err) + ")");
  }
  const bool first_is_protos = outputs[0].dims == 4;
  return decode_yolo_seg(info, options, outputs[first_is_protos ? 1 : 0],
                         outputs[first_is_protos ? 0 : 1], lb);
}

std::vector<Instance> Detector::detect(const cv::Mat& image_bgr, const std::string& where) {
  Impl& d = *impl_;
  const ModelInfo& info = d.info;
  require(!image_bgr.empty() && image_bgr.type() == CV_8UC3, where,
          "not a colour image; expected 8-bit BGR");
  if (info.kind == ModelKind::kOnnxYoloSeg) return d.detect_onnx_seg(image_bgr, where);
  const bool yolo = info.kind == ModelKind::kDarknetYolo;

  // 1. The blob: resized to the network's input (no crop), RGB; YOLO wants pixels in [0, 1].
  const cv::Mat blob =
      cv::dnn::blobFromImage(image_bgr, yolo ? 1.0 / 255.0 : 1.0,
                             cv::Size(info.input_width, info.input_height), cv::Scalar(),
                             /*swapRB=*/true, /*crop=*/false);
  std::vector<cv::Mat> outputs;
  try {
    d.net.setInput(blob);
    d.net.forward(outputs, d.output_names);
  } catch (const cv::Exception& e) {
    throw InputError(info.model.string(),
                     "OpenCV cannot run the network on " + where + " (" + one_line(e.err) + ")");
  }
  return decode_outputs(info, d.options, outputs, image_bgr.cols, image_bgr.rows);
}

std::vector<Instance> decode_outputs(const ModelInfo& info, const DetectOptions& options,
                                     const std::vector<cv::Mat>& outputs, int width, int height) {
  require(width > 0 && height > 0, "image", "empty image; expected a size > 0");
  const DecodeContext context(info, options, width, height);
  const bool yolo = info.kind == ModelKind::kDarknetYolo;

  // 2. Candidates above the score threshold, of a kept class.
  const std::vector<Candidate> candidates =
      yolo ? yolo_candidates(context, outputs) : mask_rcnn_candidates(context, outputs);

  // 3. Non-maximum suppression, over all kept classes at once (default) or per class.
  const std::vector<Candidate> kept = suppress_non_maxima(candidates, options);

  // 4. Instances: boxes to 1/100 px, scores to 1e-6; Mask R-CNN's masks in full-image masks.
  return to_instances(context, kept, yolo ? nullptr : &outputs[1]);
}

std::vector<DetectFrame> list_rgb_frames(const fs::path& dataset) {
  require(fs::is_directory(dataset), dataset.string(),
          "no such folder; expected a TUM RGB-D folder with rgb.txt");
  const fs::path list = dataset / "rgb.txt";
  require(fs::exists(list), list.string(), "missing; expected 'timestamp filename' lines");
  std::vector<DetectFrame> frames;
  io::LineReader in(list);
  while (in.next()) {
    in.expect_fields(2, "timestamp filename");
    const double t = in.number(0, "timestamp");
    require(frames.empty() || t > frames.back().timestamp, in.where(),
            "timestamp not after the previous one; expected increasing timestamps");
    frames.push_back({t, dataset / in.field(1), {}});
  }
  require(!frames.empty(), list.string(), "no image listed; expected lines 'timestamp filename'");
  return frames;
}

DetectResult detect_frames(const std::vector<DetectFrame>& frames, const DetectOptions& options,
                           const std::string& where,
                           const std::function<void(std::size_t, std::size_t)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  Detector detector(options);
  DetectResult result = detect_frames(detector, frames, where, progress);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

DetectResult detect_frames(Detector& detector, const std::vector<DetectFrame>& frames,
                           const std::string& where,
                           const std::function<void(std::size_t, std::size_t)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const DetectOptions& options = detector.options();
  DetectResult result;
  result.model = detector.info();
  result.segmentation.format = "json";
  result.segmentation.source = where;
  // The next frame's image is read (decoded) on a second thread while the network runs on this
  // one's: reading overlaps the inference, one image ahead at most.
  const auto read = [&frames](std::size_t i) {
    return frames[i].read ? frames[i].read() : io::read_rgb(frames[i].rgb_file, 0, 0);
  };
  std::future<cv::Mat> next;
  if (!frames.empty()) next = std::async(std::launch::async, read, 0);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const DetectFrame& frame = frames[i];
    const cv::Mat image = next.get();
    if (i + 1 < frames.size()) next = std::async(std::launch::async, read, i + 1);
    FrameSegmentation out;
    out.timestamp = frame.timestamp;
    out.source = frame.rgb_file.string();
    out.instances = detector.detect(image, frame.rgb_file.string());
    ++result.frames;
    if (!out.instances.empty()) ++result.frames_with_detections;
    result.instances += out.instances.size();
    for (const auto& instance : out.instances) ++result.instances_per_class[instance.class_name];
    result.segmentation.frames.push_back(std::move(out));
    if (progress) progress(i + 1, frames.size());
  }
  std::sort(result.segmentation.frames.begin(), result.segmentation.frames.end(),
            [](const FrameSegmentation& a, const FrameSegmentation& b) {
              return a.timestamp < b.timestamp;
            });
  if (result.instances == 0) {
    std::ostringstream classes;
    if (options.classes.empty()) classes << "all";
    for (std::size_t i = 0; i < options.classes.size(); ++i)
      classes << (i ? "," : "") << canonical_class(options.classes[i]);
    std::ostringstream threshold;
    threshold << options.score_threshold;
    throw InputError(where, "no detections in any of the " + std::to_string(frames.size()) +
                                " frames (classes " + classes.str() + ", score threshold " +
                                threshold.str() +
                                "); expected at least one detection to write a segmentation");
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace objmap::segmentation
