// `objmap replay` as an outline (run_replay): 1. the events of the recording (each frame's files,
// each listing or trajectory line, at its timestamp); 2. the files that are not frames, at once;
// 3. the events at the recording's own rate; 4. DST/done.
#include "objmap/pipeline/replay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "objmap/core/clock.h"
#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/io/atomic.h"
#include "objmap/io/dataset.h"
#include "objmap/io/text_lines.h"
#include "objmap/io/trajectory.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

namespace {

const io::OutputKind kReplayFolder{"objmap replay", {"replay.json"}, false};

// One thing the replay writes at a recording time: a file copied (src -> rel), or a line appended
// to a listing or the trajectory (rel), or the trajectory rewritten.
struct Event {
  enum Kind { kFile, kLine, kRewrite } kind = kFile;
  double t = 0.0;
  fs::path src;        // kFile
  fs::path rel;        // kFile: where it goes; kLine: the file it is appended to
  std::string line;    // kLine, with its '\n'
  bool frame = false;  // kFile: a frame's colour image (counted, progress)
};

// A text file of the recording split into its header (comments, blank lines) and its data lines.
struct Listing {
  std::string header;
  std::vector<std::string> lines;  // without '\n'
};

Listing read_listing(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  require(static_cast<bool>(in), file.string(), "cannot be read");
  Listing listing;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#')
      listing.header += line + "\n";
    else
      listing.lines.push_back(line);
  }
  return listing;
}

double line_timestamp(const std::string& line, const fs::path& file, std::size_t n) {
  const auto fields = io::split_fields(line);
  require(!fields.empty(), file.string() + ":" + std::to_string(n), "empty line");
  return io::parse_double(fields[0], file.string() + ":" + std::to_string(n), "timestamp");
}

// A trajectory line moved by the drift `world_drift` (world_drift * world_from_cam).
std::string drifted_line(const std::string& line, const Pose& world_drift, const std::string& at) {
  const auto f = io::split_fields(line);
  require(f.size() == 8, at, std::to_string(f.size()) + " fields; expected 8");
  double v[8];
  for (int i = 0; i < 8; ++i) v[i] = io::parse_double(f[i], at, "field " + std::to_string(i + 1));
  const Pose pose = world_drift * io::pose_from_tum(v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
  const Eigen::Quaterniond q = io::quaternion_of(pose);
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g", v[0],
                pose.translation().x(), pose.translation().y(), pose.translation().z(), q.x(),
                q.y(), q.z(), q.w());
  return buf;
}

// The drift at share s of the way to the rewrite: a rotation about the world's z and a shift
// along x, both growing linearly.
Pose drift_at(const ReplayOptions& o, double s) {
  Pose d = Pose::Identity();
  d.linear() = Eigen::AngleAxisd(s * o.drift_deg * M_PI / 180.0, Vec3::UnitZ()).toRotationMatrix();
  d.translation() = Vec3(s * o.drift_m, 0.0, 0.0);
  return d;
}

// The trajectory's events: each line at its timestamp (drifted before the rewrite), the rewrite.
void trajectory_events(const ReplayOptions& o, const fs::path& file, const fs::path& rel,
                       double t_first, double t_rewrite, std::vector<Event>& events,
                       Listing& listing) {
  listing = read_listing(file);
  for (std::size_t i = 0; i < listing.lines.size(); ++i) {
    const std::string at = file.string() + ":" + std::to_string(i + 1);
    const double t = line_timestamp(listing.lines[i], file, i + 1);
    std::string line = listing.lines[i];
    if (o.rewrite_at >= 0 && t <= t_rewrite) {
      const double s = t_rewrite > t_first ? (t - t_first) / (t_rewrite - t_first) : 1.0;
      line = drifted_line(line, drift_at(o, std::clamp(s, 0.0, 1.0)), at);
    }
    events.push_back({Event::kLine, t, {}, rel, line + "\n", false});
  }
  if (o.rewrite_at >= 0) events.push_back({Event::kRewrite, t_rewrite, {}, rel, {}, false});
}

// A TUM listing (rgb.txt, depth.txt): each line copies its file, then appears in the listing.
void listing_events(const fs::path& src, const std::string& name, bool frames,
                    std::vector<Event>& events, std::map<std::string, std::string>& headers) {
  const fs::path file = src / name;
  const Listing listing = read_listing(file);
  headers[name] = listing.header;
  for (std::size_t i = 0; i < listing.lines.size(); ++i) {
    const auto fields = io::split_fields(listing.lines[i]);
    const std::string at = file.string() + ":" + std::to_string(i + 1);
    require(fields.size() >= 2, at, "expected: timestamp filename");
    const double t = io::parse_double(fields[0], at, "timestamp");
    events.push_back({Event::kFile, t, src / fields[1], fields[1], {}, frames});
    events.push_back({Event::kLine, t, {}, name, listing.lines[i] + "\n", false});
  }
}

// A folder of per-frame files named by their timestamp (segmentation/<t>.json, detections/<t>.txt).
bool stamped_folder_events(const fs::path& src, const fs::path& dir, std::vector<Event>& events) {
  std::vector<Event> found;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    char* end = nullptr;
    const std::string stem = e.path().stem().string();
    const double t = std::strtod(stem.c_str(), &end);
    if (stem.empty() || *end != '\0' || !std::isfinite(t)) return false;
    found.push_back({Event::kFile, t, e.path(), fs::relative(e.path(), src), {}, false});
  }
  events.insert(events.end(), found.begin(), found.end());
  return !found.empty();
}

// 7-Scenes: a frame's files are those that share its colour image's name up to the first dot.
void sevenscenes_events(const io::Dataset& dataset, std::vector<Event>& events,
                        std::set<fs::path>& framed) {
  std::map<std::string, double> time_of;
  for (const auto& f : dataset.frames) {
    const std::string name = f.rgb_file.filename().string();
    time_of[name.substr(0, name.find('.') + 1)] = f.rgb_timestamp;
  }
  for (const auto& e : fs::directory_iterator(dataset.root)) {
    const std::string name = e.path().filename().string();
    const auto it = time_of.find(name.substr(0, name.find('.') + 1));
    if (it == time_of.end() || name.find('.') == std::string::npos) continue;
    const bool colour = name.find(".color.") != std::string::npos;
    events.push_back({Event::kFile, it->second, e.path(), name, {}, colour});
    framed.insert(e.path());
  }
}

void append_line(const fs::path& file, const std::string& line) {
  std::FILE* f = std::fopen(file.c_str(), "ab");
  require(f != nullptr, file.string(), "cannot be opened to append");
  const bool ok = std::fwrite(line.data(), 1, line.size(), f) == line.size();  // one write
  require(std::fclose(f) == 0 && ok, file.string(), "cannot be written");
}

void copy_file_atomic(const fs::path& src, const fs::path& dst) {
  fs::create_directories(dst.parent_path());
  const fs::path tmp = dst.parent_path() / (".replay-tmp-" + dst.filename().string());
  std::error_code ec;
  fs::copy_file(src, tmp, fs::copy_options::overwrite_existing, ec);
  require(!ec, src.string(), "cannot be copied to " + tmp.string() + ": " + ec.message());
  fs::rename(tmp, dst, ec);
  require(!ec, dst.string(), "cannot be renamed into place: " + ec.message());
}

// The source's trajectory lines up to t (as the source has them) with its header: the rewrite.
std::string rewritten_text(const Listing& listing, double t) {
  std::string text = listing.header;
  for (const auto& line : listing.lines) {
    char* end = nullptr;
    if (std::strtod(line.c_str(), &end) <= t) text += line + "\n";
  }
  return text;
}

}  // namespace

void ReplayOptions::check() const {
  require(std::isfinite(speed) && speed > 0, "--speed", "must be > 0");
  require(rewrite_at < 0 || rewrite_at <= 1.0, "--rewrite-at", "must be a fraction in [0, 1]");
  require(std::isfinite(drift_deg) && std::isfinite(drift_m), "--drift", "must be finite");
}

ReplayResult run_replay(const ReplayOptions& o, const ReplayProgress& progress) {
  o.check();
  io::require_not_an_input({"--out", o.out}, {{"--dataset", o.dataset}});
  io::require_replaceable(o.out, kReplayFolder);
  {  // the replay copies the source's folders: an --out inside it would copy itself
    const fs::path src = fs::weakly_canonical(o.dataset), out = fs::weakly_canonical(o.out);
    const auto [end, _] = std::mismatch(src.begin(), src.end(), out.begin(), out.end());
    require(end != src.end(), o.out.string(),
            "lies inside the recording " + o.dataset.string() + "; expected a folder outside it");
  }
  const auto t_start = Clock::now();
  ReplayResult result;
  // 1. The events of the recording.
  const io::Dataset dataset = io::read_dataset(o.dataset);
  result.layout = dataset.layout;
  require(dataset.layout == "tum" || dataset.layout == "7scenes", o.dataset.string(),
          "a " + dataset.layout + " recording; expected tum or 7scenes (objmap replay)");
  require(!dataset.frames.empty(), o.dataset.string(), "no frames");
  fs::path trajectory = o.trajectory;
  if (trajectory.empty() && dataset.layout == "tum" && fs::exists(o.dataset / "groundtruth.txt"))
    trajectory = o.dataset / "groundtruth.txt";
  require(o.rewrite_at < 0 || !trajectory.empty(), "--rewrite-at",
          "needs a trajectory file to rewrite (--trajectory)");
  std::vector<Event> events;
  std::map<std::string, std::string> headers;  // listing -> its header, written first
  std::set<fs::path> framed;                   // source files written as events
  if (dataset.layout == "tum") {
    listing_events(o.dataset, "rgb.txt", true, events, headers);
    listing_events(o.dataset, "depth.txt", false, events, headers);
    framed = {o.dataset / "rgb.txt", o.dataset / "depth.txt", o.dataset / "rgb",
              o.dataset / "depth"};
    for (const auto& e : fs::directory_iterator(o.dataset))
      if (e.is_directory() && !framed.count(e.path()) &&
          stamped_folder_events(o.dataset, e.path(), events))
        framed.insert(e.path());
  } else {
    sevenscenes_events(dataset, events, framed);
  }
  const double t_first = dataset.frames.front().rgb_timestamp;
  const std::size_t n = dataset.frames.size();
  const double t_rewrite =
      dataset.frames[std::min(n - 1, static_cast<std::size_t>(o.rewrite_at * n))].rgb_timestamp;
  Listing trajectory_listing;
  const fs::path trajectory_rel = trajectory.filename();
  if (!trajectory.empty()) {
    trajectory_events(o, trajectory, trajectory_rel, t_first, t_rewrite, events,
                      trajectory_listing);
    headers[trajectory_rel.string()] = trajectory_listing.header;
    framed.insert(fs::weakly_canonical(trajectory));
  }
  // Files before lines at one time (a listed frame is there when its line appears); the rewrite
  // after the lines of its time.
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) {
    return a.t < b.t || (a.t == b.t && a.kind < b.kind);
  });

  // 2. The folder, the listings' headers and the files that are not frames, at once.
  // The folder itself is kept (a follower may already watch it: its removal ends objmap follow);
  // an earlier replay's files in it are removed.
  if (fs::exists(o.out)) {
    std::vector<fs::path> earlier;
    for (const auto& e : fs::directory_iterator(o.out)) earlier.push_back(e.path());
    for (const fs::path& p : earlier) fs::remove_all(p);
  }
  fs::create_directories(o.out);
  nlohmann::ordered_json doc = {
      {"source", o.dataset.string()},      {"layout", dataset.layout},
      {"trajectory", trajectory.string()}, {"speed", o.speed},
      {"rewrite_at", o.rewrite_at},        {"rewrite_time", o.rewrite_at >= 0 ? t_rewrite : 0.0},
      {"drift_deg", o.drift_deg},          {"drift_m", o.drift_m}};
  io::write_file_atomic(o.out / "replay.json", doc.dump(2) + "\n");
  for (const auto& [name, header] : headers) io::write_file_atomic(o.out / name, header);
  for (const auto& e : fs::directory_iterator(o.dataset)) {
    if (framed.count(e.path()) || framed.count(fs::weakly_canonical(e.path()))) continue;
    if (e.is_regular_file()) copy_file_atomic(e.path(), o.out / e.path().filename());
    if (e.is_directory())
      fs::copy(e.path(), o.out / e.path().filename(), fs::copy_options::recursive);
  }

  // 3. The events at the recording's own rate (speed times faster).
  const auto t0 = Clock::now();
  for (const Event& e : events) {
    const double due = (e.t - t_first) / o.speed;
    const double now = seconds_since(t0);
    if (due > now) std::this_thread::sleep_for(std::chrono::duration<double>(due - now));
    result.behind_s = std::max(result.behind_s, seconds_since(t0) - due);
    if (e.kind == Event::kFile) {
      copy_file_atomic(e.src, o.out / e.rel);
      ++result.files;
      if (e.frame && progress)
        progress(++result.frames, n);
      else if (e.frame)
        ++result.frames;
    } else if (e.kind == Event::kLine) {
      append_line(o.out / e.rel, e.line);
      if (e.rel == trajectory_rel) ++result.trajectory_lines;
    } else {
      io::write_file_atomic(o.out / e.rel, rewritten_text(trajectory_listing, e.t));
      result.rewritten = true;
    }
  }
  // 4. The end of the recording.
  io::write_file_atomic(o.out / "done", "");
  result.seconds = seconds_since(t_start);
  return result;
}

}  // namespace objmap::pipeline
