#include "objmap/io/library_errors.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <ios>
#include <stdexcept>
#include <system_error>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

using test::error_of;

// What a reader of "f.yaml" throws when `call` throws inside it.
template <typename Call>
std::string named(Call&& call) {
  return error_of([&] {
    try {
      call();
    } catch (...) {
      rethrow_naming_file("f.yaml");
    }
  });
}

TEST(RethrowNamingFile, LibraryExceptionsBecomeOneLineNamingTheFile) {
  // OpenCV's assertion, as FileStorage's lookup in a sequence raises it.
  EXPECT_EQ(named([] {
              cv::FileNode none;
              CV_Assert(none.isMap());
            }),
            "f.yaml: OpenCV cannot read it: none.isMap() in operator()");
  EXPECT_EQ(named([] { (void)nlohmann::json::parse("[1]").at(0).get<std::string>(); }),
            "f.yaml: nlohmann::json cannot read it: [json.exception.type_error.302] type must "
            "be string, but is number");
  EXPECT_EQ(named([] { throw std::ios_base::failure("basic_filebuf::underflow\nsecond line"); }),
            "f.yaml: read error: basic_filebuf::underflow second line: iostream error");
  EXPECT_EQ(named([] {
              throw std::filesystem::filesystem_error(
                  "x", std::make_error_code(std::errc::permission_denied));
            }),
            "f.yaml: cannot read it: Permission denied");
}

TEST(RethrowNamingFile, InputErrorsAndBugsPassUnchanged) {
  EXPECT_EQ(named([] { throw InputError("g.json: fx", "missing"); }), "g.json: fx: missing");
  EXPECT_THROW(
      {
        try {
          throw std::logic_error("a bug");
        } catch (...) {
          rethrow_naming_file("f.yaml");
        }
      },
      std::logic_error);
}

}  // namespace
}  // namespace objmap::io
