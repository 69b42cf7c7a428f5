#pragma once
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

// ONNX Runtime as a second backend of `objmap detect` for ONNX models, through its C API. The
// library is optional: it is loaded at run time (dlopen), never linked, so objmap builds and runs
// without it (OpenCV's dnn is then the only backend). Where it is looked for, in order:
//   1. the file named by the environment variable OBJMAP_ONNXRUNTIME, when set: that file only (a
//      name that does not exist, e.g. "none", turns ONNX Runtime off);
//   2. /usr/local/lib/objmap/libonnxruntime.so.1, where `scripts/install-deps.sh` (make deps)
//      puts the library of the npm package onnxruntime-node (docs/cli.md, "objmap detect");
//   3. libonnxruntime.so.1 on the loader's path (LD_LIBRARY_PATH, ldconfig).
// The C API is that of ONNX Runtime 1.29.0 (ort_api.h); a library of that release or newer
// serves it.
namespace objmap::segmentation {

// Whether ONNX Runtime can be used, and which (the library is loaded once per process).
struct OnnxRuntimeStatus {
  bool available = false;
  std::string library;  // the file loaded
  std::string version;  // e.g. "1.29.0"
  std::string reason;   // why not, when !available: the places tried and what each said
};
const OnnxRuntimeStatus& onnxruntime_status();

// One ONNX model loaded in ONNX Runtime (CPU execution provider, graph optimisations on), run on
// float tensors. Not copyable; Run is called from one thread at a time.
class OnnxRuntimeSession {
 public:
  // `threads`: intra-op threads (0: ONNX Runtime's default, the cores). Throws InputError naming
  // the model when ONNX Runtime is not available (with how to install it) or cannot load the file.
  OnnxRuntimeSession(const std::filesystem::path& model, int threads);
  ~OnnxRuntimeSession();
  OnnxRuntimeSession(const OnnxRuntimeSession&) = delete;
  OnnxRuntimeSession& operator=(const OnnxRuntimeSession&) = delete;

  // The first input's shape as the model declares it (-1 for a symbolic dimension).
  const std::vector<std::int64_t>& input_shape() const;
  std::size_t output_count() const;

  // Runs the model on `input` (CV_32F, its dims the input tensor's, e.g. 1 × 3 × H × W) and returns
  // every output as a float Mat of the output's dims, valid until the next run (ONNX Runtime's
  // memory, not copied). Throws InputError naming
  // the model and `where` when ONNX Runtime refuses (e.g. an input size the model does not take).
  std::vector<cv::Mat> run(const cv::Mat& input, const std::string& where);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap::segmentation
