#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>

// The part of ONNX Runtime's C API that objmap calls (ort_session.cpp), declared by objmap from the
// API's binary interface rather than from its 12,000 lines of headers: the library hands out a
// table of function pointers (OrtApi) whose slots never move between releases (new functions are
// only appended), so a function is its slot's index and its signature. The indices and signatures
// are those of API version 29 (ONNX Runtime 1.29.0, include/onnxruntime/core/session/
// onnxruntime_c_api.h); a library of that release or newer serves them (GetApi(29)). Linux: the
// default calling convention, `char` paths.
namespace objmap::segmentation::ort {

constexpr std::uint32_t kApiVersion = 29;

// Opaque objects of the library (only pointers to them pass).
struct OrtStatus;
struct OrtEnv;
struct OrtSession;
struct OrtSessionOptions;
struct OrtRunOptions;
struct OrtValue;
struct OrtTypeInfo;
struct OrtTensorTypeAndShapeInfo;
struct OrtMemoryInfo;
struct OrtAllocator;

// The enumerators objmap passes (C enums: int-sized).
enum OrtLoggingLevel : int { ORT_LOGGING_LEVEL_FATAL = 4 };
enum GraphOptimizationLevel : int { ORT_ENABLE_ALL = 99 };
enum OrtAllocatorType : int { OrtArenaAllocator = 1 };
enum OrtMemType : int { OrtMemTypeDefault = 0 };
enum ONNXTensorElementDataType : int { ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT = 1 };

struct OrtApiTable;  // the library's OrtApi: read only through bind_api

// What OrtGetApiBase (the library's one exported symbol) returns.
struct OrtApiBase {
  const OrtApiTable* (*GetApi)(std::uint32_t version);
  const char* (*GetVersionString)();
};

// The functions objmap calls, each taken from its slot of the table (the slot index beside it).
struct OrtApi {
  const char* (*GetErrorMessage)(const OrtStatus*);                 // 2
  OrtStatus* (*CreateEnv)(OrtLoggingLevel, const char*, OrtEnv**);  // 3
  OrtStatus* (*CreateSession)(const OrtEnv*, const char*, const OrtSessionOptions*,
                              OrtSession**);  // 7
  OrtStatus* (*Run)(OrtSession*, const OrtRunOptions*, const char* const*, const OrtValue* const*,
                    std::size_t, const char* const*, std::size_t,
                    OrtValue**);                            // 9
  OrtStatus* (*CreateSessionOptions)(OrtSessionOptions**);  // 10
  OrtStatus* (*SetSessionGraphOptimizationLevel)(OrtSessionOptions*,
                                                 GraphOptimizationLevel);                    // 23
  OrtStatus* (*SetIntraOpNumThreads)(OrtSessionOptions*, int);                               // 24
  OrtStatus* (*SetInterOpNumThreads)(OrtSessionOptions*, int);                               // 25
  OrtStatus* (*SessionGetInputCount)(const OrtSession*, std::size_t*);                       // 30
  OrtStatus* (*SessionGetOutputCount)(const OrtSession*, std::size_t*);                      // 31
  OrtStatus* (*SessionGetInputTypeInfo)(const OrtSession*, std::size_t, OrtTypeInfo**);      // 33
  OrtStatus* (*SessionGetInputName)(const OrtSession*, std::size_t, OrtAllocator*, char**);  // 36
  OrtStatus* (*SessionGetOutputName)(const OrtSession*, std::size_t, OrtAllocator*,
                                     char**);  // 37
  OrtStatus* (*CreateTensorWithDataAsOrtValue)(const OrtMemoryInfo*, void*, std::size_t,
                                               const std::int64_t*, std::size_t,
                                               ONNXTensorElementDataType, OrtValue**);  // 49
  OrtStatus* (*GetTensorMutableData)(OrtValue*, void**);                                // 51
  OrtStatus* (*CastTypeInfoToTensorInfo)(const OrtTypeInfo*,
                                         const OrtTensorTypeAndShapeInfo**);         // 55
  OrtStatus* (*GetDimensionsCount)(const OrtTensorTypeAndShapeInfo*, std::size_t*);  // 61
  OrtStatus* (*GetDimensions)(const OrtTensorTypeAndShapeInfo*, std::int64_t*,
                              std::size_t);                                           // 62
  OrtStatus* (*GetTensorTypeAndShape)(const OrtValue*, OrtTensorTypeAndShapeInfo**);  // 65
  OrtStatus* (*CreateCpuMemoryInfo)(OrtAllocatorType, OrtMemType, OrtMemoryInfo**);   // 69
  OrtStatus* (*AllocatorFree)(OrtAllocator*, void*);                                  // 76
  OrtStatus* (*GetAllocatorWithDefaultOptions)(OrtAllocator**);                       // 78
  void (*ReleaseEnv)(OrtEnv*);                                                        // 92
  void (*ReleaseStatus)(OrtStatus*);                                                  // 93
  void (*ReleaseMemoryInfo)(OrtMemoryInfo*);                                          // 94
  void (*ReleaseSession)(OrtSession*);                                                // 95
  void (*ReleaseValue)(OrtValue*);                                                    // 96
  void (*ReleaseTypeInfo)(OrtTypeInfo*);                                              // 98
  void (*ReleaseTensorTypeAndShapeInfo)(OrtTensorTypeAndShapeInfo*);                  // 99
  void (*ReleaseSessionOptions)(OrtSessionOptions*);                                  // 100
  OrtStatus* (*AddSessionConfigEntry)(OrtSessionOptions*, const char*, const char*);  // 130
};

namespace detail {
// Slot `index` of the table as a function pointer of `fn`'s type (copied byte for byte: the slots
// are function pointers of the library's own types).
template <typename Fn>
void take_slot(const OrtApiTable* table, std::size_t index, Fn& fn) {
  static_assert(sizeof(Fn) == sizeof(void*), "a slot is one pointer");
  std::memcpy(&fn, reinterpret_cast<const unsigned char*>(table) + index * sizeof(void*),
              sizeof(fn));
}
}  // namespace detail

// The functions above taken from the library's table.
inline OrtApi bind_api(const OrtApiTable* table) {
  OrtApi a{};
  using detail::take_slot;
  take_slot(table, 2, a.GetErrorMessage);
  take_slot(table, 3, a.CreateEnv);
  take_slot(table, 7, a.CreateSession);
  take_slot(table, 9, a.Run);
  take_slot(table, 10, a.CreateSessionOptions);
  take_slot(table, 23, a.SetSessionGraphOptimizationLevel);
  take_slot(table, 24, a.SetIntraOpNumThreads);
  take_slot(table, 25, a.SetInterOpNumThreads);
  take_slot(table, 30, a.SessionGetInputCount);
  take_slot(table, 31, a.SessionGetOutputCount);
  take_slot(table, 33, a.SessionGetInputTypeInfo);
  take_slot(table, 36, a.SessionGetInputName);
  take_slot(table, 37, a.SessionGetOutputName);
  take_slot(table, 49, a.CreateTensorWithDataAsOrtValue);
  take_slot(table, 51, a.GetTensorMutableData);
  take_slot(table, 55, a.CastTypeInfoToTensorInfo);
  take_slot(table, 61, a.GetDimensionsCount);
  take_slot(table, 62, a.GetDimensions);
  take_slot(table, 65, a.GetTensorTypeAndShape);
  take_slot(table, 69, a.CreateCpuMemoryInfo);
  take_slot(table, 76, a.AllocatorFree);
  take_slot(table, 78, a.GetAllocatorWithDefaultOptions);
  take_slot(table, 92, a.ReleaseEnv);
  take_slot(table, 93, a.ReleaseStatus);
  take_slot(table, 94, a.ReleaseMemoryInfo);
  take_slot(table, 95, a.ReleaseSession);
  take_slot(table, 96, a.ReleaseValue);
  take_slot(table, 98, a.ReleaseTypeInfo);
  take_slot(table, 99, a.ReleaseTensorTypeAndShapeInfo);
  take_slot(table, 100, a.ReleaseSessionOptions);
  take_slot(table, 130, a.AddSessionConfigEntry);
  return a;
}

}  // namespace objmap::segmentation::ort
