#include "objmap/io/run_path.h"

#include <algorithm>
#include <system_error>

#include "objmap/core/error.h"

namespace objmap::io {

namespace fs = std::filesystem;

namespace {

// The path with every existing symlink resolved and "." and ".." gone (as far as it exists).
fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path out = fs::weakly_canonical(fs::absolute(p, ec), ec);
  if (ec) out = fs::absolute(p).lexically_normal();
  // weakly_canonical keeps a trailing separator of a folder ("run/"): one form for the comparison.
  if (!out.empty() && out.filename().empty()) out = out.parent_path();
  return out;
}

}  // namespace

fs::path path_in_run(const fs::path& run, const std::string& relative, const fs::path& file,
                     const std::string& field) {
  const fs::path root = resolved(run);
  const fs::path target = resolved(run / relative);
  // Inside: the root's components are a proper prefix of the target's.
  const auto [r, t] = std::mismatch(root.begin(), root.end(), target.begin(), target.end());
  const bool inside = r == root.end() && t != target.end();
  if (relative.empty())
    throw InputError(file.string() + ": " + field,
                     "empty; expected a path inside the run folder " + run.string());
  if (!inside)
    throw InputError(file.string() + ": " + field,
                     "'" + relative + "' resolves outside the run folder " + run.string() +
                         "; expected a path inside it");
  return run / relative;
}

}  // namespace objmap::io
