#pragma once
#include <gtest/gtest.h>

#include <Eigen/Core>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "objmap/core/camera.h"

namespace objmap::test {

namespace fs = std::filesystem;

// The real data folder: $OBJMAP_DATA, else <repo>/../shared/data.
fs::path data_dir();

// True when the real data folder has `relative` (e.g. "tum/fr1_desk_9").
bool has_data(const std::string& relative);

// With OBJMAP_REQUIRE_DATA=1 (CI sets it) a missing data folder is a failure, not a skip.
bool data_required();

// The message of the objmap::InputError that `call` throws, or "(no error)" when it throws none.
std::string error_of(const std::function<void()>& call);
// The reason of that InputError, its where() into *where when given; when `call` throws none, a
// test failure "no error for <what>" and "".
std::string error_reason(const std::function<void()>& call, const std::string& what,
                         std::string* where = nullptr);

// A fresh empty folder under the system temp dir, removed with the object.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

struct RunResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// The built objmap binary (for scripts that take its path).
fs::path objmap_binary();

// Runs the built objmap binary with `args` (no shell interpretation of the arguments).
RunResult run_objmap(const std::vector<std::string>& args);

// As run_objmap, but once `ready()` is true (polled every 5 ms) the process gets `signal`. A
// process that ends before that is not signalled. exit_code is 128 + the signal when it ended by
// one.
RunResult run_objmap_interrupted(const std::vector<std::string>& args,
                                 const std::function<bool()>& ready, int signal);

// The output folder of `objmap <args>` where the argument "{OUT}" stands for the folder, made once
// and kept under <build>/test-cache/<stamp of the objmap binary>/<key> (a rebuilt binary starts a
// new cache), so that several test processes share one synthetic scene or one fuse run. Tests that
// use it carry the CTest RESOURCE_LOCK "objmap_cache". On failure the folder is absent and `result`
// (when given) says why.
fs::path cached_output(const std::string& key, const std::vector<std::string>& args,
                       RunResult* result = nullptr);

// A 64×48 pinhole camera (f = 50 px, centred), 1 mm depth units: small images for unit tests.
inline Camera small_test_camera() {
  Camera c;
  c.width = 64;
  c.height = 48;
  c.fx = c.fy = 50.0;
  c.cx = 32.0;
  c.cy = 24.0;
  c.depth_factor = 1000.0;
  return c;
}

// Total cost of an assignment (row -> column, -1 for none) of a cost matrix, to check an
// assignment solver against brute force.
inline double assignment_cost(const Eigen::MatrixXd& cost, const std::vector<int>& row_to_col) {
  double total = 0.0;
  for (int r = 0; r < static_cast<int>(row_to_col.size()); ++r)
    if (row_to_col[r] >= 0) total += cost(r, row_to_col[r]);
  return total;
}

std::string read_text(const fs::path& file);
void write_text(const fs::path& file, const std::string& text);
// Copies a folder recursively (to make malformed copies of real data).
void copy_tree(const fs::path& from, const fs::path& to);

}  // namespace objmap::test

// Declares `fs::path var` = data_dir()/relative, or skips the test (fails under
// OBJMAP_REQUIRE_DATA=1) when that folder is not there.
#define OBJMAP_DATA_OR_SKIP(var, relative)                                              \
  const ::objmap::test::fs::path var = ::objmap::test::data_dir() / (relative);         \
  if (!::objmap::test::fs::exists(var)) {                                               \
    if (::objmap::test::data_required()) FAIL() << "real data missing: " << var;        \
    GTEST_SKIP() << "real data missing: " << var << " (set OBJMAP_DATA to the folder)"; \
  }
