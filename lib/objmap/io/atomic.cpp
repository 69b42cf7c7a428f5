#include "objmap/io/atomic.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iterator>
#include <mutex>
#include <system_error>

#include "objmap/core/error.h"

namespace objmap::io {

namespace fs = std::filesystem;

namespace {

fs::path with_suffix(const fs::path& path, const std::string& suffix) {
  fs::path p = path;
  if (!p.has_filename()) p = p.parent_path();  // "out/" -> "out"
  return p.parent_path() / (p.filename().string() + suffix + std::to_string(::getpid()));
}

void make_parent(const fs::path& file);  // below the registry

// The unfinished outputs of the process. Never destroyed: the signal thread may use it while the
// process exits.
struct Registry {
  std::mutex mutex;
  std::vector<fs::path> paths;
  bool closed = false;  // remove_unfinished_outputs() ran: the process is ending
};

Registry& registry() {
  static Registry* r = new Registry;
  return *r;
}

void make_parent(const fs::path& file) {
  const fs::path parent = file.parent_path();
  if (!parent.empty()) create_output_folders(parent);
}

}  // namespace

void create_output_folders(const fs::path& folder) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  if (r.closed) throw InputError(folder.string(), "not created: the process is interrupted");
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder.string(), "cannot create the folder: " + ec.message());
}

UnfinishedOutput::UnfinishedOutput(fs::path path) : path_(std::move(path)) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  if (r.closed) return;
  r.paths.push_back(path_);
  registered_ = true;
}

void UnfinishedOutput::release() {
  if (!registered_) return;
  std::lock_guard<std::mutex> lock(registry().mutex);
  release_locked();
}

void UnfinishedOutput::release_locked() {
  if (!registered_) return;
  registered_ = false;
  auto& paths = registry().paths;
  const auto it = std::find(paths.begin(), paths.end(), path_);
  if (it != paths.end()) paths.erase(it);
}

std::vector<fs::path> remove_unfinished_outputs() {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  r.closed = true;
  std::vector<fs::path> removed;
  for (const fs::path& p : r.paths) {
    std::error_code ec;
    if (!fs::exists(fs::symlink_status(p, ec))) continue;
    // The other threads still run: a file they make in a folder meanwhile fails its removal
    // (not empty), so a few passes.
    for (int pass = 0; pass < 5 && fs::exists(fs::symlink_status(p, ec)); ++pass)
      fs::remove_all(p, ec);
    removed.push_back(p);
  }
  r.paths.clear();
  return removed;
}

bool interrupt_started() {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  return r.closed;
}

void write_file_atomic(const fs::path& file, const std::string& bytes) {
  AtomicFile out(file);
  out.write(bytes.data(), bytes.size());
  out.commit();
}

AtomicFile::AtomicFile(const fs::path& file)
    : file_(file), tmp_(with_suffix(file, ".tmp-")), unfinished_(tmp_) {
  require(file.has_filename(), file.string(), "expected a file name, got a folder");
  make_parent(file);
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw InputError(file.string(), std::string("cannot write the file: ") + std::strerror(errno));
}

AtomicFile::~AtomicFile() {
  if (fd_ < 0) return;  // committed
  ::close(fd_);
  std::error_code ec;
  fs::remove(tmp_, ec);  // never throws from a destructor
}

void AtomicFile::write(const char* data, std::size_t size) {
  require(fd_ >= 0, file_.string(), "AtomicFile written after commit");
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd_, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0)
      throw InputError(file_.string(),
                       std::string("cannot write the file: ") + std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
}

void AtomicFile::commit() {
  require(fd_ >= 0, file_.string(), "AtomicFile committed twice");
  const int fd = fd_;
  fd_ = -1;
  std::string error;
  if (::close(fd) != 0) error = std::strerror(errno);
  if (error.empty() && std::rename(tmp_.c_str(), file_.c_str()) != 0) error = std::strerror(errno);
  if (!error.empty()) {
    std::error_code ec;
    fs::remove(tmp_, ec);
    throw InputError(file_.string(), "cannot write the file: " + error);
  }
}

const OutputKind kRunFolder{"objmap fuse run", {"run.json"}, false};
const OutputKind kSyntheticSequence{"objmap synth sequence", {"synth.json"}, false};
const OutputKind kSegmentationFolder{
    "segmentation (<timestamp>.json files)", {"tracks.json"}, true};
const OutputKind kReportFolder{"objmap report", {"report.html"}, false};
const OutputKind kPipelineFolder{"objmap run", {"stages.json"}, false};
const OutputKind kSummaryFolder{"objmap summary", {"summary.json"}, false};

namespace {

// "out", "out/" -> "out"; "." and ".." (which cannot be renamed) -> the folder they name.
fs::path output_path(const fs::path& out) {
  fs::path p = out;
  if (!p.has_filename()) p = p.parent_path();
  if (p.filename() == "." || p.filename() == "..") {
    std::error_code ec;
    const fs::path resolved = fs::weakly_canonical(fs::absolute(p, ec), ec);
    if (!ec && resolved.has_filename()) p = resolved;
  }
  return p;
}

// "<number>.json", the name of a canonical segmentation frame.
bool is_frame_file(const std::string& name) {
  const std::size_t dot = name.size() >= 5 ? name.size() - 5 : std::string::npos;
  if (dot == std::string::npos || dot == 0 || name.compare(dot, 5, ".json") != 0) return false;
  bool digit = false;
  for (std::size_t i = 0; i < dot; ++i) {
    const char c = name[i];
    if (c >= '0' && c <= '9')
      digit = true;
    else if (c != '.')
      return false;
  }
  return digit;
}

}  // namespace

namespace {
// The output's folder must be one objmap can write in: its nearest existing ancestor is a folder
// and writable (checked before the work, so that a run does not end in a failed rename).
void require_writable_place(const fs::path& out) {
  std::error_code ec;
  fs::path ancestor = fs::absolute(out, ec).parent_path();
  while (!ancestor.empty() && !fs::exists(ancestor, ec) && ancestor != ancestor.parent_path())
    ancestor = ancestor.parent_path();
  if (ancestor.empty()) return;
  require(fs::is_directory(ancestor, ec), out.string(),
          "cannot be written: " + ancestor.string() +
              " is not a folder; expected an output inside a folder");
  require(::access(ancestor.c_str(), W_OK) == 0, out.string(),
          "cannot be written: " + ancestor.string() + " is not writable (" + std::strerror(errno) +
              "); expected a folder objmap may write in");
}
}  // namespace

void require_replaceable(const fs::path& out_given, const OutputKind& kind) {
  const fs::path out = output_path(out_given);
  require(!out.empty(), out_given.string(), "expected an output folder name");
  require_writable_place(out);
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(out, ec);
  if (!fs::exists(status)) return;
  if (fs::is_symlink(status) || !fs::is_directory(status))
    throw InputError(out.string(), std::string("exists and is not a folder") +
                                       (fs::is_symlink(status) ? " (a symbolic link)" : "") +
                                       "; expected a folder (or nothing)");
  std::vector<std::string> names;
  bool marker = false, only_frames = kind.frame_files;
  for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    names.push_back(name);
    const bool is_marker =
        std::find(kind.markers.begin(), kind.markers.end(), name) != kind.markers.end();
    marker = marker || (is_marker && it->is_regular_file());
    if (!is_marker && !(is_frame_file(name) && it->is_regular_file())) only_frames = false;
  }
  if (ec) throw InputError(out.string(), "cannot list the folder: " + ec.message());
  if (names.empty() || marker || only_frames) return;
  std::sort(names.begin(), names.end());
  std::string held;
  for (std::size_t i = 0; i < names.size() && i < 3; ++i) held += (i ? ", " : "") + names[i];
  if (names.size() > 3) held += " and " + std::to_string(names.size() - 3) + " more";
  std::string expected;
  for (std::size_t i = 0; i < kind.markers.size(); ++i)
    expected += (i ? " or " : "") + kind.markers[i];
  if (kind.frame_files)
    expected += std::string(expected.empty() ? "" : " or ") + "only frame files";
  throw InputError(out.string(),
                   "exists and is not an earlier " + kind.name + " (it holds " + held + "; no " +
                       expected +
                       "), so it is not replaced; expected a new or empty folder, or an "
                       "earlier output to replace");
}

namespace {
// `inner` is `outer` or lies inside it (both absolute and normal).
bool within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i)
    if (o->empty() && std::next(o) == outer.end())
      return true;  // a trailing separator
    else if (i == inner.end() || *i != *o)
      return false;
  return true;
}
}  // namespace

void require_not_an_input(const NamedPath& out, const std::vector<NamedPath>& inputs) {
  if (out.path.empty()) return;
  std::error_code ec;
  const fs::path o = fs::weakly_canonical(fs::absolute(out.path), ec);
  if (ec) return;  // a path that cannot be resolved is refused by the writer itself
  for (const NamedPath& in : inputs) {
    if (in.path.empty()) continue;
    const fs::path i = fs::weakly_canonical(fs::absolute(in.path), ec);
    if (ec) continue;
    // An output inside an input folder (a run in the dataset's folder) replaces nothing of it.
    const bool same = o == i, holds = within(i, o);
    if (!same && !holds) continue;
    const std::string how = same ? "is" : "holds";
    throw InputError(out.flag, out.path.string() + " " + how + " the input of " + in.flag + " (" +
                                   in.path.string() +
                                   "); expected an output apart from the inputs (objmap never "
                                   "writes over what it reads)");
  }
}

StagingDir::StagingDir(const fs::path& out, const OutputKind& kind)
    : out_(output_path(out)),
      staging_(with_suffix(out_, ".tmp-")),
      unfinished_(staging_),
      kind_(kind) {
  require_replaceable(out_, kind_);  // also refuses an empty name
  make_parent(out_);
  std::error_code ec;
  fs::remove_all(staging_, ec);  // a stale one from a crashed run with the same pid
  if (!fs::create_directory(staging_, ec) || ec)
    throw InputError(staging_.string(), "cannot create the folder: " + ec.message());
}

StagingDir::~StagingDir() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);  // never throws from a destructor
}

void StagingDir::commit() {
  require(!committed_, out_.string(), "StagingDir committed twice");
  require_replaceable(out_, kind_);  // again: the folder may have come meanwhile
  std::error_code ec;
  fs::path aside;
  {
    // An interrupt waits for the swap: it never finds the old output aside and the new one gone.
    std::lock_guard<std::mutex> lock(registry().mutex);
    if (fs::exists(out_, ec)) {
      aside = with_suffix(out_, ".old-");
      fs::remove_all(aside, ec);
      fs::rename(out_, aside, ec);
      if (ec)
        throw InputError(out_.string(), "cannot replace the existing folder: " + ec.message());
    }
    fs::rename(staging_, out_, ec);
    if (ec) {
      std::error_code ignored;
      if (!aside.empty()) fs::rename(aside, out_, ignored);  // put the old one back
      throw InputError(out_.string(),
                       "cannot move " + staging_.string() + " into place: " + ec.message());
    }
    committed_ = true;
    committed_at_ = std::chrono::steady_clock::now();
    unfinished_.release_locked();
  }
  if (!aside.empty()) {
    const UnfinishedOutput old(aside);  // an interrupt now removes the rest of it
    fs::remove_all(aside, ec);
  }
}

}  // namespace objmap::io
