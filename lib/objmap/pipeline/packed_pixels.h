#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "objmap/geometry/pixel_runs.h"

// objmap follow's kept pixels, compressed: a keyframe's observations are kept as pixel runs for a
// loop closure (geometry/pixel_runs.h: 5 bytes a point), which is the part of follow's memory that
// grows with the recording. Packed, the runs' depths and colours are each point's difference from
// the point before, as byte planes (the depths' low bytes, their high bytes, then red, green and
// blue), deflated: ~2-2.5 bytes a point on real and synthetic recordings (docs/follow.md,
// "Memory"). Unpacked, they are the runs they were made of, bit for bit.
namespace objmap::pipeline {

struct PackedPixelRuns {
  int stride = 1;
  std::vector<std::uint32_t> first, end;  // as PixelRuns'
  std::size_t points = 0;
  bool colors = false;
  std::vector<std::uint8_t> planes;  // deflated

  std::size_t bytes() const;  // what they hold
};

// `runs` packed; their run starts and ends are moved, not copied.
PackedPixelRuns pack_pixel_runs(geometry::PixelRuns runs);

// The runs `packed` was made of. Throws std::logic_error when its planes do not inflate to its
// points (corrupted memory, or follow's own file damaged: never a user's input).
geometry::PixelRuns unpack_pixel_runs(const PackedPixelRuns& packed);

// Packed runs kept in a file rather than in memory, so that what follow holds does not grow with
// the recording's keyframes: an unnamed file in a folder (Linux's O_TMPFILE, or a file unlinked as
// soon as it is made), written at its end and read back at any place; it goes when closed, so
// nothing is left behind however the process ends. Its pages are the kernel's page cache, which
// gives them up under pressure (not the process's memory).
class PackedPixelFile {
 public:
  // Where a packed runs' parts lie in the file.
  struct Entry {
    std::uint64_t offset = 0;
    std::uint32_t runs = 0;          // first and end: runs each
    std::uint64_t planes_bytes = 0;  // after them
    std::size_t points = 0;
    int stride = 1;
    bool colors = false;
  };

  // Throws InputError(folder, …) when no file can be made there.
  explicit PackedPixelFile(const std::filesystem::path& folder);
  ~PackedPixelFile();
  PackedPixelFile(const PackedPixelFile&) = delete;
  PackedPixelFile& operator=(const PackedPixelFile&) = delete;

  // Written at the file's end; throws InputError(folder, …) when the write fails (disk full).
  Entry append(const PackedPixelRuns& packed);
  // Read back; throws InputError(folder, …) when the read fails.
  PackedPixelRuns read(const Entry& entry) const;
  std::uint64_t bytes() const { return end_; }

 private:
  std::filesystem::path folder_;
  int fd_ = -1;
  std::uint64_t end_ = 0;
};

}  // namespace objmap::pipeline
