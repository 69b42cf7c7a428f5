#pragma once
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

// A whole JSON file read as every reader of objmap reads one.
namespace objmap::io {

// The parsed file. Throws InputError(file, cannot_open) when it cannot be opened,
// InputError(file, "is a folder; expected a JSON file") for a folder, InputError(file, "malformed
// JSON: <the parser's reason>") when it is not JSON, and InputError(file, "read error: ...") when
// reading it fails.
nlohmann::json read_json_file(const std::filesystem::path& file, const std::string& cannot_open);

}  // namespace objmap::io
