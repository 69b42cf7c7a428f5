#pragma once
#include <string>

// The exceptions of the libraries that objmap's readers of outside data call, as InputErrors.
namespace objmap::io {

// Called in the `catch (...)` block around a reader of `file`: rethrows an InputError as it is;
// turns an exception of a library the reader calls on the file's bytes (OpenCV's cv::Exception,
// nlohmann::json's, the C++ streams' std::ios_base::failure, std::filesystem's) into
// InputError(file, "<library> cannot read it: <its reason on one line>"); rethrows anything else
// (a bug in objmap, or memory exhausted: "internal error", exit 1).
//   try { ... } catch (...) { rethrow_naming_file(file); }
[[noreturn]] void rethrow_naming_file(const std::string& file);

}  // namespace objmap::io
