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

// The field where parsing `text` fails ("instances[0].score"): the one that holds the value the
// parser refused (a number beyond a double, a broken string); "" at the top level or when it
// parses.
std::string json_failing_field(const std::string& text);

}  // namespace objmap::io
