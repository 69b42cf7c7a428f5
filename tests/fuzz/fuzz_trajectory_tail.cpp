// The tolerant trajectory reader of objmap follow (io/trajectory_tail.h, TrajectoryTail): the input
// is "A" kSeparator "B" (B empty without a separator). Three readers:
//  - grown: the file is written with A (it may end inside a line), polled, then B is appended and
//    it is polled twice more: the partial line's path.
//  - rewritten: the file holds A, is polled, is replaced by B, and polled again: the rewrite path.
//  - fresh: a new reader of the final grown file, polled once.
// A finding: any exception (poll() throws nothing for the file's contents), poses out of order or
// not finite, a malformed line's message that is not one line naming the file, a grown file
// reported as rewritten or read otherwise than the fresh reader reads it, a rewrite reported (or
// not) other than the poses say, and, for the file's complete lines, a result that differs from
// io::read_trajectory's where that reads them without error or repeated timestamp.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

#include "fuzz_util.h"
#include "objmap/io/trajectory.h"
#include "objmap/io/trajectory_tail.h"

namespace {

using objmap::Trajectory;
using objmap::fuzz::finding;
namespace fs = std::filesystem;

bool same_pose(const objmap::StampedPose& a, const objmap::StampedPose& b) {
  return a.timestamp == b.timestamp && a.world_from_cam.matrix() == b.world_from_cam.matrix();
}

// True when the first a.size() poses of b are those of a.
bool is_prefix(const Trajectory& a, const Trajectory& b) {
  if (a.poses.size() > b.poses.size()) return false;
  for (std::size_t i = 0; i < a.poses.size(); ++i)
    if (!same_pose(a.poses[i], b.poses[i])) return false;
  return true;
}

// What every poll must give: finite poses in increasing time, messages of one line naming `file`.
objmap::io::TrajectoryTailPoll checked_poll(objmap::io::TrajectoryTail& tail,
                                            const fs::path& file) {
  const Trajectory before = tail.trajectory();
  const auto poll = tail.poll();
  const Trajectory& now = tail.trajectory();
  for (std::size_t i = 0; i < now.poses.size(); ++i) {
    const auto& p = now.poses[i];
    if (!std::isfinite(p.timestamp) || !p.world_from_cam.matrix().allFinite())
      finding("a pose that is not finite");
    if (i > 0 && !(p.timestamp > now.poses[i - 1].timestamp)) finding("poses out of order");
  }
  for (const std::string& m : poll.malformed)
    if (m.empty() || m.find('\n') != std::string::npos || m.rfind(file.string() + ":", 0) != 0 ||
        m.find("; skipped") == std::string::npos)
      finding("malformed-line message: '" + m + "'");
  if (poll.rewritten == is_prefix(before, now))
    finding(poll.rewritten ? "a rewrite reported while the earlier poses are kept"
                           : "earlier poses changed without a rewrite");
  const std::size_t grown =
      now.poses.size() > before.poses.size() ? now.poses.size() - before.poses.size() : 0;
  if (poll.new_poses != grown) finding("new_poses is not the growth of the poses");
  return poll;
}

void append_file(const fs::path& file, std::string_view bytes) {
  std::FILE* f = std::fopen(file.c_str(), "ab");
  if (!f) finding("cannot append to the scratch file");
  // An empty part's view may hold a null pointer, which fwrite must not be given.
  const bool ok = bytes.empty() || std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  if (std::fclose(f) != 0 || !ok) finding("cannot append to the scratch file");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto parts = fuzz::split(data, size, 2);
  const fs::path dir = fuzz::fresh_dir();

  // Grown: A, then A + B.
  const fs::path grown_file = dir / "grown.txt";
  io::TrajectoryTail grown(grown_file);
  checked_poll(grown, grown_file);  // not there yet
  fuzz::write_file(dir, "grown.txt", parts[0]);
  checked_poll(grown, grown_file);
  append_file(grown_file, parts[1]);
  if (checked_poll(grown, grown_file).rewritten) finding("a grown file reported as rewritten");
  const auto again = checked_poll(grown, grown_file);
  if (again.new_poses != 0 || again.rewritten || !again.malformed.empty())
    finding("a poll of an unchanged file found something new");

  // Fresh: the grown file read at once gives what the polls gave.
  io::TrajectoryTail fresh(grown_file);
  checked_poll(fresh, grown_file);
  if (!is_prefix(fresh.trajectory(), grown.trajectory()) ||
      fresh.trajectory().size() != grown.trajectory().size())
    finding("the grown file's poses differ from a fresh read's");
  if (fresh.malformed() != grown.malformed() || fresh.lines() != grown.lines())
    finding("the grown file's counts differ from a fresh read's");

  // Against read_trajectory on the complete lines: where it reads them without an error or a
  // repeated timestamp (which it takes and the tail refuses), the tail reads the same poses and
  // names no line.
  const std::string text = std::string(parts[0]) + std::string(parts[1]);
  const std::size_t end = text.rfind('\n');
  if (end != std::string::npos) {
    const fs::path complete = fuzz::write_file(dir, "complete.txt", text.substr(0, end + 1));
    try {
      const Trajectory whole = io::read_trajectory(complete);
      if (whole.warnings.empty() &&
          (fresh.malformed() != 0 || !is_prefix(whole, fresh.trajectory()) ||
           whole.size() != fresh.trajectory().size()))
        finding("the tail reads a trajectory otherwise than read_trajectory");
    } catch (const InputError& e) {
      fuzz::check_message(e);
      if (fresh.malformed() == 0 && !fresh.trajectory().poses.empty())
        finding("read_trajectory refuses a file the tail reads without a malformed line: " +
                std::string(e.what()));
    }
  }

  // Rewritten: A, then B in its place.
  const fs::path rewritten_file = dir / "rewritten.txt";
  io::TrajectoryTail rewritten(rewritten_file);
  fuzz::write_file(dir, "rewritten.txt", parts[0]);
  checked_poll(rewritten, rewritten_file);
  fuzz::write_file(dir, "rewritten.txt", parts[1]);
  checked_poll(rewritten, rewritten_file);
  io::TrajectoryTail of_b(rewritten_file);
  checked_poll(of_b, rewritten_file);
  if (!is_prefix(of_b.trajectory(), rewritten.trajectory()) ||
      of_b.trajectory().size() != rewritten.trajectory().size())
    finding("the rewritten file's poses differ from a fresh read's");
  return 0;
}
