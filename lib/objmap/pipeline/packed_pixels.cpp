#include "objmap/pipeline/packed_pixels.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/io/deflate.h"

namespace objmap::pipeline {

std::size_t PackedPixelRuns::bytes() const {
  return (first.size() + end.size()) * sizeof(std::uint32_t) + planes.size();
}

PackedPixelRuns pack_pixel_runs(geometry::PixelRuns runs) {
  PackedPixelRuns p;
  p.stride = runs.stride;
  p.first = std::move(runs.first);
  p.end = std::move(runs.end);
  p.points = runs.size();
  p.colors = !runs.colors.empty();
  const std::size_t n = p.points;
  std::vector<std::uint8_t> planes(n * (p.colors ? 5 : 2));
  std::uint16_t last_raw = 0;
  Rgb last{0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const auto d = static_cast<std::uint16_t>(runs.raw[i] - last_raw);
    last_raw = runs.raw[i];
    planes[i] = static_cast<std::uint8_t>(d & 0xff);
    planes[n + i] = static_cast<std::uint8_t>(d >> 8);
    if (!p.colors) continue;
    const Rgb c = runs.colors[i];
    planes[2 * n + i] = static_cast<std::uint8_t>(c.r - last.r);
    planes[3 * n + i] = static_cast<std::uint8_t>(c.g - last.g);
    planes[4 * n + i] = static_cast<std::uint8_t>(c.b - last.b);
    last = c;
  }
  p.planes = io::deflate_bytes(planes.data(), planes.size());
  return p;
}

geometry::PixelRuns unpack_pixel_runs(const PackedPixelRuns& packed) {
  const std::size_t n = packed.points;
  std::vector<std::uint8_t> planes(n * (packed.colors ? 5 : 2));
  if (!io::inflate_bytes(packed.planes, planes.data(), planes.size()))
    throw std::logic_error("unpack_pixel_runs: the packed planes do not inflate to " +
                           std::to_string(n) + " points");
  geometry::PixelRuns runs;
  runs.stride = packed.stride;
  runs.first = packed.first;
  runs.end = packed.end;
  runs.raw.resize(n);
  if (packed.colors) runs.colors.resize(n);
  std::uint16_t raw = 0;
  Rgb c{0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    raw = static_cast<std::uint16_t>(raw + (planes[i] | planes[n + i] << 8));
    runs.raw[i] = raw;
    if (!packed.colors) continue;
    c = Rgb{static_cast<std::uint8_t>(c.r + planes[2 * n + i]),
            static_cast<std::uint8_t>(c.g + planes[3 * n + i]),
            static_cast<std::uint8_t>(c.b + planes[4 * n + i])};
    runs.colors[i] = c;
  }
  return runs;
}

namespace {

// An unnamed file open for reading and writing in `folder`, or -1 (errno set).
int open_unnamed_file(const std::filesystem::path& folder) {
#ifdef O_TMPFILE
  const int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd >= 0 || (errno != EOPNOTSUPP && errno != EISDIR)) return fd;
#endif
  // A file system without O_TMPFILE: a named file, unlinked at once.
  std::string name = (folder / ".kept_pixels.XXXXXX").string();
  const int named = ::mkostemp(name.data(), O_CLOEXEC);
  if (named >= 0) ::unlink(name.c_str());
  return named;
}

// `size` bytes at `offset` of `fd` moved by `op` (pwrite from `data`, or pread into it), through
// short counts and interruptions; the reason as a line when it fails (`short_count`: none moved).
template <typename Op, typename Byte>
std::string transfer_at(Op op, int fd, Byte* at, std::size_t size, std::uint64_t offset,
                        const char* short_count) {
  while (size > 0) {
    const ssize_t n = op(fd, at, size, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 ? std::strerror(errno) : short_count;
    at += n;
    size -= static_cast<std::size_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
  return {};
}

std::string write_at(int fd, const void* data, std::size_t size, std::uint64_t offset) {
  return transfer_at(::pwrite, fd, static_cast<const char*>(data), size, offset, "nothing written");
}

std::string read_at(int fd, void* data, std::size_t size, std::uint64_t offset) {
  return transfer_at(::pread, fd, static_cast<char*>(data), size, offset, "it ends early");
}

}  // namespace

PackedPixelFile::PackedPixelFile(const std::filesystem::path& folder)
    : folder_(folder), fd_(open_unnamed_file(folder)) {
  require(fd_ >= 0, folder_.string(),
          std::string("cannot make the file of the kept pixels there: ") + std::strerror(errno) +
              "; expected a writable folder");
}

PackedPixelFile::~PackedPixelFile() {
  if (fd_ >= 0) ::close(fd_);
}

PackedPixelFile::Entry PackedPixelFile::append(const PackedPixelRuns& packed) {
  const Entry entry{end_,
                    static_cast<std::uint32_t>(packed.first.size()),
                    packed.planes.size(),
                    packed.points,
                    packed.stride,
                    packed.colors};
  const std::size_t run_bytes = packed.first.size() * sizeof(std::uint32_t);
  std::string error = write_at(fd_, packed.first.data(), run_bytes, end_);
  if (error.empty()) error = write_at(fd_, packed.end.data(), run_bytes, end_ + run_bytes);
  if (error.empty())
    error = write_at(fd_, packed.planes.data(), packed.planes.size(), end_ + 2 * run_bytes);
  if (!error.empty())
    throw InputError(folder_.string(), "cannot write the kept pixels' file there: " + error +
                                           "; expected room on its disk");
  end_ += 2 * run_bytes + packed.planes.size();
  return entry;
}

PackedPixelRuns PackedPixelFile::read(const Entry& entry) const {
  PackedPixelRuns packed;
  packed.stride = entry.stride;
  packed.points = entry.points;
  packed.colors = entry.colors;
  packed.first.resize(entry.runs);
  packed.end.resize(entry.runs);
  packed.planes.resize(entry.planes_bytes);
  const std::size_t run_bytes = std::size_t{entry.runs} * sizeof(std::uint32_t);
  std::string error = read_at(fd_, packed.first.data(), run_bytes, entry.offset);
  if (error.empty()) error = read_at(fd_, packed.end.data(), run_bytes, entry.offset + run_bytes);
  if (error.empty())
    error = read_at(fd_, packed.planes.data(), packed.planes.size(), entry.offset + 2 * run_bytes);
  if (!error.empty())
    throw InputError(folder_.string(), "cannot read the kept pixels' file back: " + error);
  return packed;
}

}  // namespace objmap::pipeline
