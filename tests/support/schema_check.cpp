#include "support/schema_check.h"

#include <fstream>
#include <stdexcept>

namespace objmap::test {

namespace {

using json = nlohmann::json;

bool has_type(const json& v, const std::string& type) {
  if (type == "object") return v.is_object();
  if (type == "array") return v.is_array();
  if (type == "string") return v.is_string();
  if (type == "number") return v.is_number();
  if (type == "integer")
    return v.is_number_integer() ||
           (v.is_number_float() && v.get<double>() == static_cast<long long>(v.get<double>()));
  if (type == "boolean") return v.is_boolean();
  if (type == "null") return v.is_null();
  return false;
}

const json& resolve(const json& schema, const json& root) {
  if (!schema.is_object() || !schema.contains("$ref")) return schema;
  const std::string ref = schema["$ref"].get<std::string>();
  if (ref.rfind("#/", 0) != 0) throw std::runtime_error("only local $ref supported: " + ref);
  return root.at(json::json_pointer(ref.substr(1)));
}

void check(const json& v, const json& schema_in, const json& root, const std::string& at,
           std::vector<std::string>& errors) {
  if (schema_in.is_boolean()) {
    if (!schema_in.get<bool>()) errors.push_back(at + ": not allowed");
    return;
  }
  const json& s = resolve(schema_in, root);
  if (s.contains("type")) {
    bool ok = false;
    if (s["type"].is_array()) {
      for (const auto& t : s["type"]) ok = ok || has_type(v, t.get<std::string>());
    } else {
      ok = has_type(v, s["type"].get<std::string>());
    }
    if (!ok) {
      errors.push_back(at + ": expected type " + s["type"].dump() + ", got " +
                       v.dump().substr(0, 60));
      return;
    }
  }
  if (s.contains("enum")) {
    bool found = false;
    for (const auto& e : s["enum"]) found = found || e == v;
    if (!found) errors.push_back(at + ": " + v.dump() + " not in enum " + s["enum"].dump());
  }
  if (s.contains("const") && s["const"] != v)
    errors.push_back(at + ": expected " + s["const"].dump());
  if (v.is_number()) {
    const double x = v.get<double>();
    if (s.contains("minimum") && x < s["minimum"].get<double>())
      errors.push_back(at + ": " + v.dump() + " < minimum " + s["minimum"].dump());
    if (s.contains("maximum") && x > s["maximum"].get<double>())
      errors.push_back(at + ": " + v.dump() + " > maximum " + s["maximum"].dump());
    if (s.contains("exclusiveMinimum") && x <= s["exclusiveMinimum"].get<double>())
      errors.push_back(at + ": " + v.dump() + " <= exclusiveMinimum");
    if (s.contains("exclusiveMaximum") && x >= s["exclusiveMaximum"].get<double>())
      errors.push_back(at + ": " + v.dump() + " >= exclusiveMaximum");
  }
  if (v.is_string() && s.contains("minLength") &&
      v.get<std::string>().size() < s["minLength"].get<std::size_t>())
    errors.push_back(at + ": string shorter than minLength");
  if (v.is_object()) {
    if (s.contains("required"))
      for (const auto& r : s["required"])
        if (!v.contains(r.get<std::string>()))
          errors.push_back(at + ": missing required property '" + r.get<std::string>() + "'");
    const json props = s.value("properties", json::object());
    for (auto it = v.begin(); it != v.end(); ++it) {
      const std::string child = at + "/" + it.key();
      if (props.contains(it.key())) {
        check(*it, props[it.key()], root, child, errors);
      } else if (s.contains("additionalProperties")) {
        check(*it, s["additionalProperties"], root, child, errors);
      }
    }
  }
  if (v.is_array()) {
    if (s.contains("minItems") && v.size() < s["minItems"].get<std::size_t>())
      errors.push_back(at + ": fewer than minItems " + s["minItems"].dump());
    if (s.contains("maxItems") && v.size() > s["maxItems"].get<std::size_t>())
      errors.push_back(at + ": more than maxItems " + s["maxItems"].dump());
    if (s.contains("items"))
      for (std::size_t i = 0; i < v.size(); ++i)
        check(v[i], s["items"], root, at + "/" + std::to_string(i), errors);
  }
  for (const char* key : {"oneOf", "anyOf"}) {
    if (!s.contains(key)) continue;
    int passed = 0;
    for (const auto& sub : s[key]) {
      std::vector<std::string> sub_errors;
      check(v, sub, root, at, sub_errors);
      if (sub_errors.empty()) ++passed;
    }
    const bool ok = std::string(key) == "oneOf" ? passed == 1 : passed >= 1;
    if (!ok) errors.push_back(at + ": " + key + " matched " + std::to_string(passed) + " schemas");
  }
  if (s.contains("allOf"))
    for (const auto& sub : s["allOf"]) check(v, sub, root, at, errors);
}

}  // namespace

std::vector<std::string> validate_json(const json& document, const json& schema) {
  std::vector<std::string> errors;
  check(document, schema, schema, "", errors);
  return errors;
}

json load_schema(const std::string& name) {
  std::ifstream in(std::filesystem::path(OBJMAP_SOURCE_DIR) / "schemas" / name);
  if (!in) throw std::runtime_error("schema not found: " + name);
  return json::parse(in);
}

}  // namespace objmap::test
