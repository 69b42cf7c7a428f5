#pragma once
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

// Options that a command takes both as flags and from a `--config F.json` file: one table per
// command names each field once (JSON key, flag, help), so the flags, the config file and the
// options echoed into run.json can never disagree. Flags given on the command line win over the
// file.
namespace objmap::pipeline {

struct ConfigField {
  std::string key;   // JSON path with dots, e.g. "objects.weight_id"
  std::string flag;  // command-line flag, e.g. "--weight-id"
  std::string help;  // one line for --help and docs/cli.md
  std::variant<double*, int*, bool*, std::string*> target;
};

// Reads a JSON object from `file` and sets every field it names (nested objects follow the dots of
// the keys). Throws InputError "<file>: <key>: ..." for malformed JSON, an unknown key (with the
// known keys of that level) or a value of the wrong type.
void apply_config_file(const std::filesystem::path& file, const std::vector<ConfigField>& fields);

// The fields' current values as a nested JSON object text (pretty, keys in table order).
std::string config_to_json(const std::vector<ConfigField>& fields, int indent = 2);

}  // namespace objmap::pipeline
