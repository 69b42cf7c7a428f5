#include "objmap/segmentation/yolo_seg.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include "objmap/core/error.h"
#include "objmap/segmentation/detect_internal.h"

namespace objmap::segmentation {

namespace fs = std::filesystem;

namespace {

constexpr int kMaskCoefficients = 32;

std::string shape_text(const cv::Mat& m) {
  std::string s = "[";
  for (int i = 0; i < m.dims; ++i) s += (i ? ", " : "") + std::to_string(m.size[i]);
  return s + "]";
}

using detail::Candidate;

// Reads output0 row by row in either layout: value(row, column).
struct Rows {
  const float* data;
  int count, width;
  bool transposed;
  float at(int row, int column) const {
    return transposed ? data[static_cast<std::size_t>(column) * count + row]
                      : data[static_cast<std::size_t>(row) * width + column];
  }
};

// Each row's best class and its score: row by row (v5), or class by class over the contiguous
// columns of the transposed v8 layout (one pass through memory instead of a stride per value).
void best_classes(const Rows& rows, int first_class, int classes, std::vector<int>& best,
                  std::vector<float>& best_score) {
  best.assign(static_cast<std::size_t>(rows.count), 0);
  best_score.assign(static_cast<std::size_t>(rows.count), 0.f);
  if (!rows.transposed) {
    for (int r = 0; r < rows.count; ++r) {
      const float* row = rows.data + static_cast<std::size_t>(r) * rows.width + first_class;
      const float* top = std::max_element(row, row + classes);
      best[r] = static_cast<int>(top - row);
      best_score[r] = *top;
    }
    return;
  }
  const float* first = rows.data + static_cast<std::size_t>(first_class) * rows.count;
  std::copy(first, first + rows.count, best_score.begin());
  for (int c = 1; c < classes; ++c) {
    const float* column = rows.data + static_cast<std::size_t>(first_class + c) * rows.count;
    for (int r = 0; r < rows.count; ++r)
      if (column[r] > best_score[r]) best_score[r] = column[r], best[r] = c;
  }
}

// Step 1: the rows above the score threshold, of a kept class, boxes in the frame.
std::vector<Candidate> seg_candidates(const ModelInfo& model, const DetectOptions& options,
                                      const Rows& rows, bool objectness, const Letterbox& lb) {
  const int classes = static_cast<int>(model.class_names.size());
  std::vector<bool> kept_class(static_cast<std::size_t>(classes), false);
  for (int id : model.kept_class_ids)
    if (id >= 0 && id < classes) kept_class[static_cast<std::size_t>(id)] = true;
  std::vector<int> best_class;
  std::vector<float> best_score;
  best_classes(rows, objectness ? 5 : 4, classes, best_class, best_score);
  std::vector<Candidate> out;
  for (int r = 0; r < rows.count; ++r) {
    const int best = best_class[r];
    const float score = objectness ? rows.at(r, 4) * best_score[r] : best_score[r];
    if (score < options.score_threshold || score <= 0.f || !kept_class[best]) continue;
    const double cx = rows.at(r, 0), cy = rows.at(r, 1), w = rows.at(r, 2), h = rows.at(r, 3);
    const auto to_x = [&](double x) {
      return std::clamp((x - lb.pad_x) / lb.scale, 0.0, static_cast<double>(lb.image_width));
    };
    const auto to_y = [&](double y) {
      return std::clamp((y - lb.pad_y) / lb.scale, 0.0, static_cast<double>(lb.image_height));
    };
    const double x1 = to_x(cx - w / 2), x2 = to_x(cx + w / 2);
    const double y1 = to_y(cy - h / 2), y2 = to_y(cy + h / 2);
    if (x2 - x1 < 1 || y2 - y1 < 1) continue;
    out.push_back({best, score, cv::Rect2d(x1, y1, x2 - x1, y2 - y1), r});
  }
  return out;
}

// The box of candidate `c` at the prototypes' resolution: [x1, x2) × [y1, y2) in prototype pixels.
struct ProtoBox {
  double x1, x2, y1, y2;
};
ProtoBox proto_box(const Candidate& c, const Letterbox& lb, int pw, int ph) {
  const double sx = static_cast<double>(pw) / lb.input_width;
  const double sy = static_cast<double>(ph) / lb.input_height;
  return {
      (c.box.x * lb.scale + lb.pad_x) * sx, ((c.box.x + c.box.width) * lb.scale + lb.pad_x) * sx,
      (c.box.y * lb.scale + lb.pad_y) * sy, ((c.box.y + c.box.height) * lb.scale + lb.pad_y) * sy};
}

// The mask's pixels inside the box (the frame's pixels u0..u1 × v0..v1) above the threshold, read
// from `at(u, v)`; an empty mask when none.
template <typename At>
Mask threshold_in_box(const Candidate& c, const Letterbox& lb, double threshold, At at) {
  Mask mask;
  mask.width = lb.image_width;
  mask.height = lb.image_height;
  mask.data.assign(static_cast<std::size_t>(mask.width) * mask.height, 0);
  const int u0 = std::max(0, static_cast<int>(std::floor(c.box.x)));
  const int v0 = std::max(0, static_cast<int>(std::floor(c.box.y)));
  const int u1 = std::min(mask.width, static_cast<int>(std::ceil(c.box.x + c.box.width)));
  const int v1 = std::min(mask.height, static_cast<int>(std::ceil(c.box.y + c.box.height)));
  std::size_t area = 0;
  for (int v = v0; v < v1; ++v) {
    const float* src = at(v);
    std::uint8_t* dst = mask.data.data() + static_cast<std::size_t>(v) * mask.width;
    for (int u = u0; u < u1; ++u)
      if (src[u] > threshold) dst[u] = 1, ++area;
  }
  if (area == 0) mask.data.clear();
  return mask;
}

// Step 3 when the frame is not scaled into the input (scale 1) and the input is a whole multiple
// s of the prototypes on both axes (640 × 480 frames in 640 × 640 or 640 × 480 inputs, 160 × 160
// or 160 × 120 prototypes): the same mask as instance_mask's, computed on the box alone. The
// prototypes are combined, passed through the sigmoid and upsampled ×s (bilinear) on a patch of
// the box plus 2 prototype pixels: the patch's border is outside the box (0, as in the whole
// image), so its upsampled pixels are those of the whole image's.
Mask instance_mask_in_box(const Rows& rows, int first_coefficient, const cv::Mat& protos,
                          const Candidate& c, const Letterbox& lb, double threshold) {
  const int ph = protos.size[2], pw = protos.size[3], s = lb.input_width / pw;
  const ProtoBox b = proto_box(c, lb, pw, ph);
  const int x0 = std::max(0, static_cast<int>(std::floor(b.x1)) - 2);
  const int x1 = std::min(pw, static_cast<int>(std::ceil(b.x2)) + 2);
  const int y0 = std::max(0, static_cast<int>(std::floor(b.y1)) - 2);
  const int y1 = std::min(ph, static_cast<int>(std::ceil(b.y2)) + 2);
  cv::Mat patch(y1 - y0, x1 - x0, CV_32F, cv::Scalar(0));
  for (int k = 0; k < kMaskCoefficients; ++k) {
    const float coefficient = rows.at(c.source, first_coefficient + k);
    const float* plane = protos.ptr<float>() + static_cast<std::size_t>(k) * ph * pw;
    for (int v = y0; v < y1; ++v) {
      float* dst = patch.ptr<float>(v - y0);
      const float* src = plane + static_cast<std::size_t>(v) * pw;
      for (int u = x0; u < x1; ++u) dst[u - x0] += coefficient * src[u];
    }
  }
  for (int v = y0; v < y1; ++v) {
    float* row = patch.ptr<float>(v - y0);
    for (int u = x0; u < x1; ++u) {
      const bool inside = u >= b.x1 && u < b.x2 && v >= b.y1 && v < b.y2;
      row[u - x0] = inside ? 1.f / (1.f + std::exp(-row[u - x0])) : 0.f;
    }
  }
  cv::Mat up;
  cv::resize(patch, up, cv::Size(patch.cols * s, patch.rows * s), 0, 0, cv::INTER_LINEAR);
  // Frame pixel (u, v) = input pixel (u + pad_x, v + pad_y) = patch pixel (u + pad_x - x0 s, ...).
  const int du = lb.pad_x - x0 * s, dv = lb.pad_y - y0 * s;
  return threshold_in_box(c, lb, threshold, [&](int v) { return up.ptr<float>(v + dv) + du; });
}

// Step 3: one instance's mask in the frame: sigmoid(coefficients · prototypes) at the prototypes'
// resolution, zero outside the box, upsampled to the input, the letterbox undone, thresholded and
// kept inside the box. Empty when nothing passes the threshold.
Mask instance_mask(const Rows& rows, int first_coefficient, const cv::Mat& protos,
                   const Candidate& c, const Letterbox& lb, double threshold, bool in_box) {
  const int ph = protos.size[2], pw = protos.size[3];
  if (in_box && lb.scale == 1.0 && lb.input_width % pw == 0 && lb.input_height % ph == 0 &&
      lb.input_width / pw == lb.input_height / ph)
    return instance_mask_in_box(rows, first_coefficient, protos, c, lb, threshold);
  const cv::Mat basis(kMaskCoefficients, ph * pw, CV_32F, const_cast<float*>(protos.ptr<float>()));
  cv::Mat coefficients(1, kMaskCoefficients, CV_32F);
  for (int k = 0; k < kMaskCoefficients; ++k)
    coefficients.at<float>(k) = rows.at(c.source, first_coefficient + k);
  cv::Mat logits = coefficients * basis;  // 1 × (ph · pw)
  cv::Mat proto_mask = logits.reshape(1, ph);
  // The box at the prototypes' resolution (input pixels / stride); outside it, 0 (crop_mask).
  const ProtoBox b = proto_box(c, lb, pw, ph);
  for (int v = 0; v < ph; ++v) {
    float* row = proto_mask.ptr<float>(v);
    for (int u = 0; u < pw; ++u) {
      const bool inside = u >= b.x1 && u < b.x2 && v >= b.y1 && v < b.y2;
      row[u] = inside ? 1.f / (1.f + std::exp(-row[u])) : 0.f;
    }
  }
  cv::Mat input_mask;
  cv::resize(proto_mask, input_mask, cv::Size(lb.input_width, lb.input_height), 0, 0,
             cv::INTER_LINEAR);
  const cv::Rect content(lb.pad_x, lb.pad_y,
                         static_cast<int>(std::lround(lb.image_width * lb.scale)),
                         static_cast<int>(std::lround(lb.image_height * lb.scale)));
  cv::Mat frame_mask = input_mask(content & cv::Rect(0, 0, lb.input_width, lb.input_height));
  if (frame_mask.cols != lb.image_width || frame_mask.rows != lb.image_height)
    cv::resize(frame_mask, frame_mask, cv::Size(lb.image_width, lb.image_height), 0, 0,
               cv::INTER_LINEAR);
  return threshold_in_box(c, lb, threshold, [&](int v) { return frame_mask.ptr<float>(v); });
}

// Protobuf, as much as onnx_input_shape needs: varints and length-delimited fields.
struct ProtoReader {
  const std::uint8_t* p = nullptr;
  const std::uint8_t* end = nullptr;
  bool varint(std::uint64_t& v) {
    v = 0;
    for (int shift = 0; shift < 64 && p < end; shift += 7) {
      const std::uint8_t b = *p++;
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return true;
    }
    return false;
  }
  // The next field: its number and wire type; a varint's value in `value`; for wire type 2, `sub`
  // spans its bytes. False at the end or on a malformed field.
  bool next(std::uint32_t& field, std::uint32_t& wire, ProtoReader& sub, std::uint64_t& value) {
    std::uint64_t key = 0;
    if (p >= end || !varint(key)) return false;
    field = static_cast<std::uint32_t>(key >> 3);
    wire = static_cast<std::uint32_t>(key & 7);
    const auto skip = [&](std::ptrdiff_t n) { return end - p >= n && (p += n, true); };
    switch (wire) {
      case 0:
        return varint(value);
      case 1:
        return skip(8);
      case 5:
        return skip(4);
      case 2:
        if (!varint(value) || value > static_cast<std::uint64_t>(end - p)) return false;
        sub = {p, p + value};
        p += value;
        return true;
      default:
        return false;
    }
  }
  // The first length-delimited field `number`.
  bool find(std::uint32_t number, ProtoReader& out) {
    std::uint32_t field = 0, wire = 0;
    std::uint64_t value = 0;
    ProtoReader sub;
    while (next(field, wire, sub, value))
      if (field == number && wire == 2) return (out = sub, true);
    return false;
  }
};

}  // namespace

const char* to_string(YoloSegLayout layout) {
  return layout == YoloSegLayout::kV5 ? "yolov5-seg" : "yolov8-seg";
}

Letterbox make_letterbox(int image_width, int image_height, int input_width, int input_height) {
  Letterbox lb;
  lb.image_width = image_width;
  lb.image_height = image_height;
  lb.input_width = input_width;
  lb.input_height = input_height;
  lb.scale = std::min({1.0, static_cast<double>(input_width) / image_width,
                       static_cast<double>(input_height) / image_height});
  const int w = static_cast<int>(std::lround(image_width * lb.scale));
  const int h = static_cast<int>(std::lround(image_height * lb.scale));
  lb.pad_x = (input_width - w) / 2;
  lb.pad_y = (input_height - h) / 2;
  return lb;
}

cv::Mat letterbox_blob(const cv::Mat& image_bgr, const Letterbox& lb) {
  cv::Mat canvas, blob;
  letterbox_blob(image_bgr, lb, canvas, blob);
  return blob;
}

void letterbox_blob(const cv::Mat& image_bgr, const Letterbox& lb, cv::Mat& canvas, cv::Mat& blob) {
  canvas.create(lb.input_height, lb.input_width, CV_8UC3);
  const cv::Size size(static_cast<int>(std::lround(lb.image_width * lb.scale)),
                      static_cast<int>(std::lround(lb.image_height * lb.scale)));
  const cv::Rect content(cv::Point(lb.pad_x, lb.pad_y), size);
  canvas.setTo(cv::Scalar(114, 114, 114));
  cv::Mat roi = canvas(content);
  if (size == image_bgr.size())
    image_bgr.copyTo(roi);
  else
    cv::resize(image_bgr, roi, size, 0, 0, cv::INTER_LINEAR);
  cv::dnn::blobFromImage(canvas, blob, 1.0 / 255.0, cv::Size(), cv::Scalar(), /*swapRB=*/true,
                         /*crop=*/false);
}

YoloSegLayout yolo_seg_layout(const cv::Mat& detections, const cv::Mat& protos,
                              std::size_t class_count, const std::string& where) {
  const int columns = static_cast<int>(class_count) + kMaskCoefficients;
  const std::string shapes = "output0 " + shape_text(detections) + ", output1 " +
                             shape_text(protos) + " for " + std::to_string(class_count) +
                             " classes";
  require(protos.dims == 4 && protos.size[0] == 1 && protos.size[1] == kMaskCoefficients, where,
          "unexpected output shapes (" + shapes + "); expected Ultralytics YOLOv5-seg [1, N, " +
              std::to_string(5 + columns) + "] or YOLOv8-seg [1, " + std::to_string(4 + columns) +
              ", N] detections and [1, 32, h, w] mask prototypes");
  if (detections.dims == 3 && detections.size[0] == 1 && detections.size[2] == 5 + columns)
    return YoloSegLayout::kV5;
  if (detections.dims == 3 && detections.size[0] == 1 && detections.size[1] == 4 + columns)
    return YoloSegLayout::kV8;
  throw InputError(where, "unexpected output shapes (" + shapes +
                              "); expected Ultralytics YOLOv5-seg [1, N, " +
                              std::to_string(5 + columns) + "] or YOLOv8-seg [1, " +
                              std::to_string(4 + columns) +
                              ", N] detections (a classes file that fits the model)");
}

std::vector<Instance> decode_yolo_seg(const ModelInfo& model, const DetectOptions& options,
                                      const cv::Mat& detections, const cv::Mat& protos,
                                      const Letterbox& letterbox, MaskDecode decode) {
  const YoloSegLayout layout =
      yolo_seg_layout(detections, protos, model.class_names.size(), model.model.string());
  const bool v5 = layout == YoloSegLayout::kV5;
  const cv::Mat d = detections.isContinuous() ? detections : detections.clone();
  const Rows rows{d.ptr<float>(), v5 ? d.size[1] : d.size[2], v5 ? d.size[2] : d.size[1], !v5};
  const int first_coefficient = (v5 ? 5 : 4) + static_cast<int>(model.class_names.size());
  const cv::Mat p = protos.isContinuous() ? protos : protos.clone();

  // 1. Candidates, 2. NMS, 3. masks; boxes to 1/100 px and scores to 1e-6 as detect() does.
  std::vector<Instance> instances;
  for (const Candidate& c :
       detail::suppress_non_maxima(seg_candidates(model, options, rows, v5, letterbox), options)) {
    Mask mask = instance_mask(rows, first_coefficient, p, c, letterbox, options.mask_threshold,
                              decode == MaskDecode::kInBox);
    if (mask.data.empty()) continue;  // nothing of the object survives the threshold
    Instance instance;
    instance.class_name = model.class_names[static_cast<std::size_t>(c.class_id)];
    instance.score = std::round(c.score / 1e-6) * 1e-6;
    const auto r = [](double v) { return std::round(v / 0.01) * 0.01; };
    instance.bbox = {r(c.box.x), r(c.box.y), r(c.box.width), r(c.box.height)};
    instance.mask = std::move(mask);
    instances.push_back(std::move(instance));
  }
  return instances;
}

std::vector<std::int64_t> onnx_input_shape(const fs::path& model) {
  std::ifstream in(model, std::ios::binary);
  require(static_cast<bool>(in), model.string(), "cannot be read; expected an ONNX model");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  ProtoReader file{bytes.data(), bytes.data() + bytes.size()};
  ProtoReader graph, input, type, tensor, shape;
  // ModelProto.graph (7) → GraphProto.input (11) → ValueInfoProto.type (2) → TypeProto.tensor_type
  // (1) → shape (2) → dim (1) → dim_value (1, varint) | dim_param (2, a name: -1 here).
  require(file.find(7, graph) && graph.find(11, input) && input.find(2, type) &&
              type.find(1, tensor) && tensor.find(2, shape),
          model.string(),
          "no graph input with a tensor shape; expected an ONNX model (e.g. an Ultralytics "
          "YOLOv5-seg / YOLOv8-seg export)");
  std::vector<std::int64_t> dims;
  std::uint32_t field = 0, wire = 0;
  std::uint64_t value = 0;
  ProtoReader dim;
  while (shape.next(field, wire, dim, value)) {
    if (field != 1 || wire != 2) continue;
    std::int64_t size = -1;
    std::uint32_t f = 0, w = 0;
    std::uint64_t v = 0;
    ProtoReader sub;
    while (dim.next(f, w, sub, v))
      if (f == 1 && w == 0) size = static_cast<std::int64_t>(v);
    dims.push_back(size);
  }
  return dims;
}

}  // namespace objmap::segmentation
