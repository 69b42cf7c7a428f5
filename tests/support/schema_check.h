#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace objmap::test {

// A small JSON Schema (draft 2020-12 / 07) validator for the tests: type (incl. arrays of types),
// required, properties, additionalProperties (bool or schema), patternProperties is not supported,
// items, minItems, maxItems, enum, const, minimum, maximum, exclusiveMinimum, exclusiveMaximum,
// minLength, oneOf/anyOf, and local $ref ("#/$defs/x", "#/definitions/x"). Returns the list of
// violations as "<json pointer>: <what>"; empty when the document is valid.
std::vector<std::string> validate_json(const nlohmann::json& document,
                                       const nlohmann::json& schema);

// Loads schemas/<name> from the source tree.
nlohmann::json load_schema(const std::string& name);

}  // namespace objmap::test
