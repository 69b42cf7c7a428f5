#pragma once
#include <map>
#include <optional>
#include <string>

#include <nlohmann/json_fwd.hpp>

// How large an instance of a class can be: the usual range of its largest horizontal extent, in the
// pose it is usually found in (a chair standing, a bottle possibly lying on its side). An object of
// the map wider than its class allows is not one instance: a detector's one mask over two chairs
// packed along a table, joined by the tracker's one id (docs/fusion.md, "The extent of one
// instance", lists the table).
namespace objmap::segmentation {

struct ClassSize {
  double min_m = 0.0;  // the smallest usual extent (documentation; no rule uses it)
  double max_m = 0.0;  // the largest usual extent: larger objects are split (fusion/oversize.h)
};

// Sizes by canonical class name (canonical_class): the built-in table of the 80 COCO classes,
// with what a file adds or replaces (YCB names, a site's own furniture).
class ClassSizes {
 public:
  // The built-in table: every COCO-80 class.
  ClassSizes();
  // No class has a size (nothing is split): `--class-sizes none`.
  static ClassSizes none();
  // `--class-sizes`: "builtin", "none", or a JSON file (update()) read over the built-in table.
  // Throws InputError naming the file for one that cannot be read or holds a bad size.
  static ClassSizes from_spec(const std::string& spec);

  // The size of `class_name` (any spelling canonical_class accepts); nullopt when the table has
  // none (a class outside COCO-80 that no file names).
  std::optional<ClassSize> find(const std::string& class_name) const;

  // Adds or replaces sizes from a JSON document {"sizes": {"<class>": [min_m, max_m], ...}} (a
  // class's value null removes it). `where` names the file in errors: InputError
  // "<where>: sizes.<class>: ...; expected [min_m, max_m] with 0 < min_m <= max_m <= 500".
  void update(const nlohmann::json& document, const std::string& where);

  const std::map<std::string, ClassSize>& table() const { return table_; }

 private:
  std::map<std::string, ClassSize> table_;
};

}  // namespace objmap::segmentation
