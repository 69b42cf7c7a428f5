#include "objmap/segmentation/class_sizes.h"

#include <cmath>

#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::segmentation {

namespace {

// The largest horizontal extent of a COCO class's instances as they are usually found, in metres:
// furniture standing (a chair's seat and legs, not its height), small things possibly lying on
// their side (a bottle's length). Ranges from common product dimensions; the maximum is what the
// split rule uses, so it is the large end of the class (an armchair, a side-by-side refrigerator,
// a full keyboard with its number pad). docs/fusion.md lists the same table.
const std::map<std::string, ClassSize>& builtin_table() {
  static const std::map<std::string, ClassSize> table = {
      {"person", {0.3, 1.0}},        {"bicycle", {1.4, 2.0}},      {"car", {3.0, 5.5}},
      {"motorcycle", {1.6, 2.5}},    {"airplane", {0.2, 80.0}},    {"bus", {6.0, 19.0}},
      {"train", {10.0, 400.0}},      {"truck", {4.0, 20.0}},       {"boat", {1.5, 40.0}},
      {"traffic light", {0.2, 1.3}}, {"fire hydrant", {0.2, 0.6}}, {"stop sign", {0.5, 1.0}},
      {"parking meter", {0.2, 0.5}}, {"bench", {0.8, 2.5}},        {"bird", {0.08, 1.2}},
      {"cat", {0.3, 1.0}},           {"dog", {0.25, 1.3}},         {"horse", {1.5, 2.8}},
      {"sheep", {0.8, 1.6}},         {"cow", {1.5, 3.0}},          {"elephant", {3.0, 7.5}},
      {"bear", {1.0, 3.0}},          {"zebra", {1.8, 2.8}},        {"giraffe", {2.0, 5.5}},
      {"backpack", {0.25, 0.5}},     {"umbrella", {0.5, 1.5}},     {"handbag", {0.15, 0.55}},
      {"tie", {0.06, 1.6}},          {"suitcase", {0.35, 0.85}},   {"frisbee", {0.2, 0.3}},
      {"skis", {1.4, 2.1}},          {"snowboard", {1.2, 1.8}},    {"sports ball", {0.04, 0.3}},
      {"kite", {0.4, 3.5}},          {"baseball bat", {0.7, 1.1}}, {"baseball glove", {0.2, 0.4}},
      {"skateboard", {0.6, 1.1}},    {"surfboard", {1.5, 3.2}},    {"tennis racket", {0.6, 0.75}},
      {"bottle", {0.05, 0.4}},       {"wine glass", {0.06, 0.25}}, {"cup", {0.06, 0.18}},
      {"fork", {0.12, 0.25}},        {"knife", {0.15, 0.4}},       {"spoon", {0.1, 0.25}},
      {"bowl", {0.1, 0.4}},          {"banana", {0.12, 0.3}},      {"apple", {0.05, 0.12}},
      {"sandwich", {0.08, 0.3}},     {"orange", {0.05, 0.12}},     {"broccoli", {0.08, 0.3}},
      {"carrot", {0.08, 0.35}},      {"hot dog", {0.12, 0.35}},    {"pizza", {0.15, 0.55}},
      {"donut", {0.05, 0.15}},       {"cake", {0.08, 0.5}},        {"chair", {0.4, 0.7}},
      {"couch", {1.2, 3.5}},         {"potted plant", {0.1, 1.5}}, {"bed", {0.9, 2.4}},
      {"dining table", {0.5, 4.0}},  {"toilet", {0.35, 0.8}},      {"tv monitor", {0.3, 2.0}},
      {"laptop", {0.25, 0.5}},       {"mouse", {0.05, 0.14}},      {"remote", {0.1, 0.3}},
      {"keyboard", {0.25, 0.55}},    {"cell phone", {0.08, 0.2}},  {"microwave", {0.35, 0.65}},
      {"oven", {0.45, 1.0}},         {"toaster", {0.2, 0.45}},     {"sink", {0.3, 1.3}},
      {"refrigerator", {0.5, 1.0}},  {"book", {0.1, 0.5}},         {"clock", {0.08, 0.6}},
      {"vase", {0.06, 0.45}},        {"scissors", {0.1, 0.3}},     {"teddy bear", {0.08, 1.0}},
      {"hair drier", {0.15, 0.35}},  {"toothbrush", {0.12, 0.22}},
  };
  return table;
}

}  // namespace

ClassSizes::ClassSizes() : table_(builtin_table()) {}

ClassSizes ClassSizes::none() {
  ClassSizes sizes;
  sizes.table_.clear();
  return sizes;
}

ClassSizes ClassSizes::from_spec(const std::string& spec) {
  if (spec == "builtin") return ClassSizes();
  if (spec == "none") return none();
  ClassSizes sizes;
  sizes.update(io::read_json_file(spec, "cannot open the class sizes file"), spec);
  return sizes;
}

std::optional<ClassSize> ClassSizes::find(const std::string& class_name) const {
  const auto it = table_.find(canonical_class(class_name));
  if (it == table_.end()) return std::nullopt;
  return it->second;
}

void ClassSizes::update(const nlohmann::json& document, const std::string& where) {
  const auto sizes = document.find("sizes");
  if (!document.is_object() || sizes == document.end() || !sizes->is_object())
    throw InputError(where,
                     "no \"sizes\" object; expected {\"sizes\": {\"<class>\": [min_m, "
                     "max_m], ...}}");
  for (const auto& item : sizes->items()) {
    const std::string& name = item.key();
    const nlohmann::json& value = item.value();  // not a structured binding: the lambda uses it
    const std::string field = "sizes." + name;
    const std::string canonical = canonical_class(name);
    if (canonical.empty()) throw InputError(where + ": " + field, "an empty class name");
    if (value.is_null()) {
      table_.erase(canonical);
      continue;
    }
    const auto number = [&](std::size_t k) {
      return value.is_array() && value.size() == 2 && value[k].is_number() ? value[k].get<double>()
                                                                           : std::nan("");
    };
    const double lo = number(0), hi = number(1);
    if (!(lo > 0.0 && lo <= hi && hi <= 500.0))
      throw InputError(where + ": " + field,
                       "got " + value.dump() +
                           "; expected [min_m, max_m] with 0 < min_m <= max_m <= 500, or null");
    table_[canonical] = {lo, hi};
  }
}

}  // namespace objmap::segmentation
