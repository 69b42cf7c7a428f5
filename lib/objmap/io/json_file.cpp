#include "objmap/io/json_file.h"

#include <fstream>
#include <system_error>

#include "objmap/core/error.h"
#include "objmap/io/library_errors.h"

namespace objmap::io {

nlohmann::json read_json_file(const std::filesystem::path& file, const std::string& cannot_open) {
  // A folder opens as a stream on Linux; reading it would then throw std::ios_base::failure.
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    throw InputError(file.string(), "is a folder; expected a JSON file");
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), cannot_open);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file.string(), std::string("malformed JSON: ") + e.what());
  } catch (...) {
    rethrow_naming_file(file.string());
  }
}

}  // namespace objmap::io
