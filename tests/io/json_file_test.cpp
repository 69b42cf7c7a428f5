#include "objmap/io/json_file.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

using test::error_of;
using test::TempDir;
using test::write_text;

TEST(ReadJsonFile, ReadsAnObject) {
  TempDir dir;
  write_text(dir / "a.json", R"({"a": [1, 2]})");
  EXPECT_EQ(read_json_file(dir / "a.json", "cannot open").at("a").at(1), 2);
}

// Every failure is an InputError naming the file: missing, a folder (which opens as a stream on
// Linux, whose reading then throws std::ios_base::failure: once "internal error", exit 1), not
// JSON.
TEST(ReadJsonFile, EveryFailureIsAnInputErrorNamingTheFile) {
  TempDir dir;
  const std::string missing = (dir / "missing.json").string();
  EXPECT_EQ(error_of([&] { read_json_file(missing, "cannot open; expected a run"); }),
            missing + ": cannot open; expected a run");
  std::filesystem::create_directory(dir / "folder.json");
  const std::string folder = (dir / "folder.json").string();
  EXPECT_EQ(error_of([&] { read_json_file(folder, "cannot open"); }),
            folder + ": is a folder; expected a JSON file");
  write_text(dir / "bad.json", "{\"a\": ");
  const std::string bad = (dir / "bad.json").string();
  EXPECT_EQ(
      error_of([&] { read_json_file(bad, "cannot open"); }).rfind(bad + ": malformed JSON: ", 0),
      0u);
}

}  // namespace
}  // namespace objmap::io
