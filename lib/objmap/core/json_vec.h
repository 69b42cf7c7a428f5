#pragma once
#include <nlohmann/json.hpp>

#include "objmap/core/types.h"

// A 3-vector as the JSON array [x, y, z] that every JSON objmap writes uses.
namespace objmap {

template <typename Json = nlohmann::ordered_json>
Json vec3_json(const Vec3& v) {
  return Json::array({v.x(), v.y(), v.z()});
}

}  // namespace objmap
