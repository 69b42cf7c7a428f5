#include "objmap/segmentation/ort_session.h"

#include <dlfcn.h>

#include <cstdlib>
#include <cstring>
#include <mutex>

#include "objmap/core/error.h"
#include "objmap/segmentation/ort_api.h"

namespace objmap::segmentation {

namespace fs = std::filesystem;
using ort::bind_api;
using ort::kApiVersion;
using ort::ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT;
using ort::ORT_ENABLE_ALL;
using ort::ORT_LOGGING_LEVEL_FATAL;
using ort::OrtAllocator;
using ort::OrtApi;
using ort::OrtApiBase;
using ort::OrtApiTable;
using ort::OrtArenaAllocator;
using ort::OrtEnv;
using ort::OrtMemoryInfo;
using ort::OrtMemTypeDefault;
using ort::OrtSession;
using ort::OrtSessionOptions;
using ort::OrtStatus;
using ort::OrtTensorTypeAndShapeInfo;
using ort::OrtTypeInfo;
using ort::OrtValue;

namespace {

constexpr const char* kInstallHint =
    "install it with `scripts/install-deps.sh` (`make deps`: the library of the npm package "
    "onnxruntime-node 1.29.0) or name the library in OBJMAP_ONNXRUNTIME, or use --backend opencv";

// The loaded library and its API table: once per process, never unloaded.
struct Runtime {
  OnnxRuntimeStatus status;
  OrtApi calls;                 // the table's functions objmap calls
  const OrtApi* api = nullptr;  // &calls once the library serves them
  OrtEnv* env = nullptr;
};

// Tries one place; true when the library is loaded and serves this header's API version.
bool try_load(const std::string& file, Runtime& rt, std::string& tried) {
  void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* error = dlerror();
    tried += "; " + (error ? std::string(error) : file + ": cannot be loaded");
    return false;
  }
  using GetApiBase = const OrtApiBase* (*)();
  const auto get_base = reinterpret_cast<GetApiBase>(dlsym(handle, "OrtGetApiBase"));
  const OrtApiBase* base = get_base ? get_base() : nullptr;
  if (base == nullptr) {
    tried += "; " + file + ": no OrtGetApiBase (not ONNX Runtime)";
    dlclose(handle);
    return false;
  }
  const std::string version = base->GetVersionString();
  const OrtApiTable* table = base->GetApi(kApiVersion);
  if (table == nullptr) {
    tried += "; " + file + ": ONNX Runtime " + version + " is older than the C API objmap uses (" +
             std::to_string(kApiVersion) + ", ONNX Runtime 1." + std::to_string(kApiVersion) + ")";
    dlclose(handle);
    return false;
  }
  rt.calls = bind_api(table);
  rt.api = &rt.calls;
  // Its errors come back as statuses (one line, objmap's); its own log only for fatal ones.
  OrtStatus* s = rt.api->CreateEnv(ORT_LOGGING_LEVEL_FATAL, "objmap", &rt.env);
  if (s != nullptr) {
    tried += "; " + file + ": " + rt.api->GetErrorMessage(s);
    rt.api->ReleaseStatus(s);
    rt.api = nullptr;
    return false;
  }
  rt.status = {true, file, version, ""};
  return true;
}

Runtime& runtime() {
  static Runtime rt;
  static std::once_flag once;
  std::call_once(once, [] {
    std::string tried;
    std::vector<std::string> places;
    if (const char* env = std::getenv("OBJMAP_ONNXRUNTIME"); env && *env) {
      places.push_back(env);  // that file only
    } else {
      places.push_back("/usr/local/lib/objmap/libonnxruntime.so.1");
      places.push_back("libonnxruntime.so.1");
    }
    for (const std::string& place : places)
      if (try_load(place, rt, tried)) return;
    rt.status.reason = "ONNX Runtime not found (" + tried.substr(2) + ")";
  });
  return rt;
}

// An OrtStatus as an InputError naming `where` (the status is released).
void check(const OrtApi* api, OrtStatus* status, const std::string& where,
           const std::string& doing) {
  if (status == nullptr) return;
  const std::string message = api->GetErrorMessage(status);
  api->ReleaseStatus(status);
  throw InputError(where, "ONNX Runtime cannot " + doing + " (" + message + ")");
}

}  // namespace

const OnnxRuntimeStatus& onnxruntime_status() { return runtime().status; }

struct OnnxRuntimeSession::Impl {
  const OrtApi* api = nullptr;
  std::string model;
  OrtSession* session = nullptr;
  OrtMemoryInfo* memory = nullptr;
  std::vector<std::string> input_names, output_names;
  std::vector<std::int64_t> input_shape;
  std::vector<OrtValue*> outputs;  // of the last run, until the next one
  void release_outputs() {
    for (OrtValue* v : outputs)
      if (v) api->ReleaseValue(v);
    outputs.clear();
  }
  ~Impl() {
    if (api == nullptr) return;
    release_outputs();
    if (memory) api->ReleaseMemoryInfo(memory);
    if (session) api->ReleaseSession(session);
  }
  // The name of input (or output) `index`, copied.
  std::string name(bool input, std::size_t index) {
    OrtAllocator* allocator = nullptr;
    check(api, api->GetAllocatorWithDefaultOptions(&allocator), model, "give an allocator");
    char* text = nullptr;
    check(api,
          input ? api->SessionGetInputName(session, index, allocator, &text)
                : api->SessionGetOutputName(session, index, allocator, &text),
          model, "name the model's inputs and outputs");
    std::string out = text;
    if (OrtStatus* freed = api->AllocatorFree(allocator, text)) api->ReleaseStatus(freed);
    return out;
  }
  void read_input_shape() {
    OrtTypeInfo* type = nullptr;
    check(api, api->SessionGetInputTypeInfo(session, 0, &type), model, "read the input's type");
    const OrtTensorTypeAndShapeInfo* tensor = nullptr;
    OrtStatus* s = api->CastTypeInfoToTensorInfo(type, &tensor);
    std::size_t dims = 0;
    if (s == nullptr && tensor != nullptr) s = api->GetDimensionsCount(tensor, &dims);
    input_shape.assign(dims, 0);
    if (s == nullptr && tensor != nullptr && dims > 0)
      s = api->GetDimensions(tensor, input_shape.data(), dims);
    api->ReleaseTypeInfo(type);
    check(api, s, model, "read the input's shape");
  }
};

OnnxRuntimeSession::OnnxRuntimeSession(const fs::path& model, int threads)
    : impl_(std::make_unique<Impl>()) {
  Runtime& rt = runtime();
  require(rt.status.available, model.string(), rt.status.reason + "; " + kInstallHint);
  Impl& d = *impl_;
  d.api = rt.api;
  d.model = model.string();
  const OrtApi* api = d.api;
  OrtSessionOptions* options = nullptr;
  check(api, api->CreateSessionOptions(&options), d.model, "make session options");
  OrtStatus* s = api->SetIntraOpNumThreads(options, threads);
  if (s == nullptr) s = api->SetInterOpNumThreads(options, 1);
  if (s == nullptr) s = api->SetSessionGraphOptimizationLevel(options, ORT_ENABLE_ALL);
  // Idle threads sleep instead of spinning: the machine is shared (other stages, other jobs).
  if (s == nullptr) s = api->AddSessionConfigEntry(options, "session.intra_op.allow_spinning", "0");
  if (s == nullptr) s = api->CreateSession(rt.env, d.model.c_str(), options, &d.session);
  api->ReleaseSessionOptions(options);
  check(api, s, d.model, "load the model; expected an ONNX model");
  check(api, api->CreateCpuMemoryInfo(OrtArenaAllocator, OrtMemTypeDefault, &d.memory), d.model,
        "describe CPU memory");
  std::size_t inputs = 0, outputs = 0;
  check(api, api->SessionGetInputCount(d.session, &inputs), d.model, "count the inputs");
  check(api, api->SessionGetOutputCount(d.session, &outputs), d.model, "count the outputs");
  require(inputs == 1, d.model,
          "has " + std::to_string(inputs) + " inputs; expected one image input");
  d.input_names.push_back(d.name(true, 0));
  for (std::size_t i = 0; i < outputs; ++i) d.output_names.push_back(d.name(false, i));
  d.read_input_shape();
}

OnnxRuntimeSession::~OnnxRuntimeSession() = default;

const std::vector<std::int64_t>& OnnxRuntimeSession::input_shape() const {
  return impl_->input_shape;
}

std::size_t OnnxRuntimeSession::output_count() const { return impl_->output_names.size(); }

std::vector<cv::Mat> OnnxRuntimeSession::run(const cv::Mat& input, const std::string& where) {
  Impl& d = *impl_;
  const OrtApi* api = d.api;
  require(input.type() == CV_32F && input.isContinuous(), where,
          "the network input is not a continuous float tensor");
  std::vector<std::int64_t> shape(input.size.p, input.size.p + input.dims);
  OrtValue* tensor = nullptr;
  check(api,
        api->CreateTensorWithDataAsOrtValue(
            d.memory, const_cast<float*>(input.ptr<float>()), input.total() * sizeof(float),
            shape.data(), shape.size(), ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT, &tensor),
        d.model, "take the input tensor of " + where);
  std::vector<const char*> input_names{d.input_names[0].c_str()}, output_names;
  for (const auto& n : d.output_names) output_names.push_back(n.c_str());
  std::vector<OrtValue*> values(output_names.size(), nullptr);
  d.release_outputs();  // the last run's, so that ONNX Runtime's arena can reuse their memory
  OrtStatus* s = api->Run(d.session, nullptr, input_names.data(), &tensor, 1, output_names.data(),
                          output_names.size(), values.data());
  api->ReleaseValue(tensor);
  if (s != nullptr)
    for (OrtValue* v : values)
      if (v) api->ReleaseValue(v);
  check(api, s, d.model, "run the network on " + where);
  // The outputs stay ONNX Runtime's until the next run (no copy): wrapped, not cloned.
  d.outputs = values;
  std::vector<cv::Mat> out;
  for (OrtValue* v : values) {
    OrtTensorTypeAndShapeInfo* info = nullptr;
    std::size_t dims = 0;
    OrtStatus* e = api->GetTensorTypeAndShape(v, &info);
    if (e == nullptr) e = api->GetDimensionsCount(info, &dims);
    std::vector<std::int64_t> size(dims);
    if (e == nullptr) e = api->GetDimensions(info, size.data(), dims);
    if (info) api->ReleaseTensorTypeAndShapeInfo(info);
    float* data = nullptr;
    if (e == nullptr) e = api->GetTensorMutableData(v, reinterpret_cast<void**>(&data));
    check(api, e, d.model, "read the outputs of " + where);
    const std::vector<int> sizes(size.begin(), size.end());
    out.push_back(cv::Mat(static_cast<int>(sizes.size()), sizes.data(), CV_32F, data));
  }
  return out;
}

}  // namespace objmap::segmentation
