#include "objmap/io/library_errors.h"

#include <algorithm>
#include <exception>
#include <filesystem>
#include <ios>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "objmap/core/error.h"

namespace objmap::io {

namespace {

// `text` on one line: line breaks as spaces, no trailing space.
std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

}  // namespace

void rethrow_naming_file(const std::string& file) {
  try {
    throw;
  } catch (const InputError&) {
    throw;
  } catch (const cv::Exception& e) {
    // err is the reason ("Incorrect indentation", "isMap()"); func where OpenCV found it.
    const std::string where = e.func.empty() ? "" : " in " + e.func;
    throw InputError(file, "OpenCV cannot read it: " + one_line(e.err + where));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, "nlohmann::json cannot read it: " + one_line(e.what()));
  } catch (const std::ios_base::failure& e) {
    throw InputError(file, "read error: " + one_line(e.what()));
  } catch (const std::filesystem::filesystem_error& e) {
    throw InputError(file, "cannot read it: " + one_line(e.code().message()));
  }
}

}  // namespace objmap::io
