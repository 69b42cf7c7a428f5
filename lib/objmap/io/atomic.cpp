#include "objmap/io/atomic.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
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

void make_parent(const fs::path& file) {
  const fs::path parent = file.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw InputError(parent.string(), "cannot create the folder: " + ec.message());
}

}  // namespace

void write_file_atomic(const fs::path& file, const std::string& bytes) {
  AtomicFile out(file);
  out.write(bytes.data(), bytes.size());
  out.commit();
}

AtomicFile::AtomicFile(const fs::path& file) : file_(file) {
  require(file.has_filename(), file.string(), "expected a file name, got a folder");
  make_parent(file);
  tmp_ = with_suffix(file, ".tmp-");
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

StagingDir::StagingDir(const fs::path& out) : out_(out) {
  if (!out_.has_filename()) out_ = out_.parent_path();
  require(!out_.empty(), out.string(), "expected an output folder name");
  std::error_code ec;
  if (fs::exists(out_, ec) && !fs::is_directory(out_, ec))
    throw InputError(out_.string(), "exists and is not a folder; expected a folder (or nothing)");
  make_parent(out_);
  staging_ = with_suffix(out_, ".tmp-");
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
  std::error_code ec;
  fs::path aside;
  if (fs::exists(out_, ec)) {
    aside = with_suffix(out_, ".old-");
    fs::remove_all(aside, ec);
    fs::rename(out_, aside, ec);
    if (ec) throw InputError(out_.string(), "cannot replace the existing folder: " + ec.message());
  }
  fs::rename(staging_, out_, ec);
  if (ec) {
    std::error_code ignored;
    if (!aside.empty()) fs::rename(aside, out_, ignored);  // put the old one back
    throw InputError(out_.string(),
                     "cannot move " + staging_.string() + " into place: " + ec.message());
  }
  committed_ = true;
  if (!aside.empty()) fs::remove_all(aside, ec);
}

}  // namespace objmap::io
