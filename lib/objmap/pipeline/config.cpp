#include "objmap/pipeline/config.h"

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

namespace {

std::vector<std::string> split_key(const std::string& key) {
  std::vector<std::string> parts;
  std::stringstream ss(key);
  std::string part;
  while (std::getline(ss, part, '.')) parts.push_back(part);
  return parts;
}

// Every key path present in `j` (leaves), with dots.
void leaves(const nlohmann::json& j, const std::string& prefix, std::vector<std::string>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object())
      leaves(*it, key, out);
    else
      out.push_back(key);
  }
}

}  // namespace

std::vector<std::string> apply_config_file(const fs::path& file,
                                           const std::vector<ConfigField>& fields) {
  const nlohmann::json j =
      io::read_json_file(file, "cannot open the config file; expected a readable JSON file");
  if (!j.is_object()) throw InputError(file.string(), "expected a JSON object at the top level");

  std::set<std::string> known;
  std::set<std::string> known_groups;
  for (const auto& f : fields) {
    known.insert(f.key);
    std::string group;
    for (const auto& part : split_key(f.key)) {
      group = group.empty() ? part : group + "." + part;
      if (group != f.key) known_groups.insert(group);
    }
  }
  std::vector<std::string> present;
  leaves(j, "", present);
  for (const auto& key : present) {
    if (known.count(key)) continue;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw InputError(file.string() + ": " + key, known_groups.count(key)
                                                     ? "is a group; expected an object"
                                                     : "unknown option; expected one of " + list);
  }

  std::vector<std::string> set;
  for (const auto& f : fields) {
    const nlohmann::json* node = &j;
    for (const auto& part : split_key(f.key)) {
      if (!node->is_object() || !node->contains(part)) {
        node = nullptr;
        break;
      }
      node = &(*node)[part];
    }
    if (!node) continue;
    const std::string where = file.string() + ": " + f.key;
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (std::is_same_v<T, bool>) {
            if (!node->is_boolean()) throw InputError(where, "expected true or false");
            *target = node->get<bool>();
          } else if constexpr (std::is_same_v<T, int>) {
            if (!node->is_number_integer())
              throw InputError(where, "expected an integer, got " + node->dump());
            // 3000000000 would wrap round to a negative int: out of int's range is refused.
            const bool fits =
                node->is_number_unsigned()
                    ? node->get<std::uint64_t>() <= std::numeric_limits<int>::max()
                    : node->get<std::int64_t>() >= std::numeric_limits<int>::min() &&
                          node->get<std::int64_t>() <= std::numeric_limits<int>::max();
            if (!fits)
              throw InputError(where, "is " + node->dump() + "; expected an integer within " +
                                          std::to_string(std::numeric_limits<int>::min()) + ".." +
                                          std::to_string(std::numeric_limits<int>::max()));
            *target = node->get<int>();
          } else if constexpr (std::is_same_v<T, double>) {
            if (!node->is_number())
              throw InputError(where, "expected a number, got " + node->dump());
            *target = node->get<double>();
          } else {
            if (!node->is_string())
              throw InputError(where, "expected a string, got " + node->dump());
            *target = node->get<std::string>();
          }
        },
        f.target);
    set.push_back(f.key);
  }
  return set;
}

std::string config_to_json(const std::vector<ConfigField>& fields, int indent) {
  ordered_json j = ordered_json::object();
  for (const auto& f : fields) {
    ordered_json* node = &j;
    const auto parts = split_key(f.key);
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      if (!node->contains(parts[i])) (*node)[parts[i]] = ordered_json::object();
      node = &(*node)[parts[i]];
    }
    std::visit([&](auto* target) { (*node)[parts.back()] = *target; }, f.target);
  }
  return j.dump(indent);
}

void check_part(const std::function<void()>& check, const std::string& part_name,
                const std::string& prefix,
                const std::vector<std::pair<std::string, std::string>>& renames) {
  try {
    check();
  } catch (const InputError& e) {
    const std::string head = part_name + ".";
    if (e.where().compare(0, head.size(), head) != 0) throw;
    const std::string member = e.where().substr(head.size());
    for (const auto& [from, key] : renames)
      if (from == member) throw InputError(key, e.reason());
    throw InputError(prefix + "." + member, e.reason());
  }
}

}  // namespace objmap::pipeline
