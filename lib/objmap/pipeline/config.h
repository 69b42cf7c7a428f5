#pragma once
#include <filesystem>
#include <functional>
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
// known keys of that level) or a value of the wrong type. Returns the keys the file set.
std::vector<std::string> apply_config_file(const std::filesystem::path& file,
                                           const std::vector<ConfigField>& fields);

// The fields' current values as a nested JSON object text (pretty, keys in table order).
std::string config_to_json(const std::vector<ConfigField>& fields, int indent = 2);

// Runs `check` (the check() of a part of a command's options, e.g. ObjectMapOptions); an InputError
// that names a member of the part as "<part_name>.<member>" is thrown again naming the member's
// config key: the key `renames` gives it (member -> key), else "<prefix>.<member>". So the user
// reads "objects.weight_id", what they wrote, not a library struct's name.
void check_part(const std::function<void()>& check, const std::string& part_name,
                const std::string& prefix,
                const std::vector<std::pair<std::string, std::string>>& renames = {});

}  // namespace objmap::pipeline
