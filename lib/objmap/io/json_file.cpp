#include "objmap/io/json_file.h"

#include <fstream>

#include "objmap/core/error.h"

namespace objmap::io {

nlohmann::json read_json_file(const std::filesystem::path& file, const std::string& cannot_open) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), cannot_open);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file.string(), std::string("malformed JSON: ") + e.what());
  }
}

}  // namespace objmap::io
