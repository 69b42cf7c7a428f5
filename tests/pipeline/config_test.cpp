// The fuse options' errors name what the user wrote: the config key of the field (and the app adds
// its flag), never a library struct's member.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <set>

#include "objmap/core/error.h"
#include "objmap/pipeline/config.h"
#include "objmap/pipeline/fuse.h"
#include "support/test_support.h"

namespace objmap::pipeline {
namespace {

using test::error_of;

FuseOptions valid_options() {
  FuseOptions o;
  o.dataset = "d";
  o.trajectory = "t";
  o.segmentation = "s";
  o.out = "o";
  return o;
}

// Every numeric field set to values no check may accept (NaN, and far out of range) and every
// text field to nonsense: when check() refuses it, the error names that field's config key (or,
// for a limit between two fields, the other one's: depth.max_m must exceed depth.min_m).
TEST(FuseOptions, EveryErrorOfAFieldNamesItsConfigKey) {
  int refused = 0, named = 0;
  FuseOptions probe = valid_options();
  std::set<std::string> keys;
  for (const ConfigField& f : fuse_config_fields(probe)) keys.insert(f.key);
  const std::size_t n = keys.size();
  for (std::size_t i = 0; i < n; ++i) {
    for (int variant = 0; variant < 3; ++variant) {
      FuseOptions o = valid_options();
      const ConfigField field = fuse_config_fields(o)[i];
      bool set = true;
      std::visit(
          [&](auto* target) {
            using T = std::remove_pointer_t<decltype(target)>;
            if constexpr (std::is_same_v<T, double>)
              *target = variant == 0   ? std::numeric_limits<double>::quiet_NaN()
                        : variant == 1 ? -1e9
                                       : 1e9;
            else if constexpr (std::is_same_v<T, int>)
              *target = variant == 0 ? -1000000 : variant == 1 ? 1000000 : 0;
            else if constexpr (std::is_same_v<T, std::string>)
              *target = "no-such-value";
            else
              set = false;  // a bool has no wrong value
          },
          field.target);
      if (!set) continue;
      try {
        o.check();
      } catch (const InputError& e) {
        ++refused;
        named += e.where() == field.key;
        EXPECT_TRUE(keys.count(e.where())) << field.key << ": " << e.what();
      }
    }
  }
  EXPECT_GT(refused, 60);         // most fields have a range
  EXPECT_GE(named, refused - 2);  // depth.min_m = 1e9: "depth.max_m must be > depth.min_m"
}

TEST(CheckPart, NamesTheConfigKeyAndLeavesOtherErrorsAlone) {
  EXPECT_EQ(error_of([] {
              check_part([] { require(false, "PartOptions.gain", "must be > 0"); }, "PartOptions",
                         "part");
            }),
            "part.gain: must be > 0");
  EXPECT_EQ(error_of([] {
              check_part([] { require(false, "PartOptions.gain_m", "must be > 0"); }, "PartOptions",
                         "part", {{"gain_m", "part.gain"}});
            }),
            "part.gain: must be > 0");
  EXPECT_EQ(error_of([] {
              check_part([] { require(false, "file.txt:3", "bad"); }, "PartOptions", "part");
            }),
            "file.txt:3: bad");
}

TEST(ConfigFile, AnIntegerBeyondIntsRangeIsNamedNotWrapped) {
  test::TempDir dir;
  int n = 7;
  const std::vector<ConfigField> fields = {{"map.count", "--count", "a count", &n}};
  for (const std::string big : {"3000000000", "-3000000000", "18446744073709551615"}) {
    std::ofstream(dir / "c.json") << R"({"map": {"count": )" << big << "}}";
    EXPECT_EQ(error_of([&] { apply_config_file(dir / "c.json", fields); }),
              (dir / "c.json").string() + ": map.count: is " + big +
                  "; expected an integer within -2147483648..2147483647");
    EXPECT_EQ(n, 7) << "left as it was";
  }
  std::ofstream(dir / "c.json") << R"({"map": {"count": -2147483648}})";
  apply_config_file(dir / "c.json", fields);
  EXPECT_EQ(n, -2147483648);
}

}  // namespace
}  // namespace objmap::pipeline
