// objmap follow's report: OUT/report made again from a published map on a thread of its own, while
// the next publishes replace OUT/map.
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <exception>
#include <memory>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/follow_state.h"
#include "objmap/pipeline/report.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

namespace {

// OUT/map's files as hard links in `copy` (no byte copied: the next publish renames a new OUT/map
// into place and removes the old folder, the links keep its files); copied where the file system
// has no hard links.
void link_tree(const fs::path& from, const fs::path& copy) {
  fs::create_directories(copy.parent_path());
  std::error_code ec;
  fs::copy(from, copy, fs::copy_options::recursive | fs::copy_options::create_hard_links, ec);
  if (!ec) return;
  fs::remove_all(copy);
  fs::copy(from, copy, fs::copy_options::recursive);
}

// The report of `source` (a copy of OUT/map) into OUT/report, the run named OUT/map; `poses`, when
// set, the trajectory's poses read so far. One line on failure.
ReportDone make_report(const fs::path& out, const fs::path& source, const fs::path& poses) {
  const auto started = Clock::now();
  ReportDone done;
  try {
    ReportOptions options;
    options.run = source;
    options.shown_run = out / "map";
    options.trajectory = poses;
    options.out = out / "report";
    options.check();
    run_report(options);
  } catch (const std::exception& e) {
    done.error = e.what();
  }
  done.seconds = seconds_since(started);
  return done;
}

constexpr int kReportNice = 10;

void start_report(FollowState& s, const FollowEvents& events) {
  // The map in place now: no publish is in flight while the loop's thread runs this.
  const fs::path out = s.options.out;
  const fs::path scratch = out / (".report-" + std::to_string(::getpid()));
  auto unfinished = std::make_shared<io::UnfinishedOutput>(scratch);
  fs::path poses;
  try {
    fs::remove_all(scratch);
    link_tree(out / "map", scratch / "map");
    if (!s.options.fuse.trajectory.empty()) {  // a file still being written: the lines read
      poses = scratch / "trajectory.txt";
      io::write_trajectory(poses, s.trajectory);
    }
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove_all(scratch, ec);
    if (events.warning) events.warning(std::string("report not made: ") + e.what());
    return;
  }
  s.last_report = Clock::now();
  s.reporting_publish = s.status.publishes;
  s.reporting = std::async(std::launch::async, [out, scratch, poses, unfinished] {
    // Below the keyframes and the publishes when the cores are busy (Linux: a thread's own nice
    // value, which the threads it starts inherit).
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kReportNice);
    ReportDone done = make_report(out, scratch / "map", poses);
    std::error_code ec;
    fs::remove_all(scratch, ec);
    unfinished->release();
    return done;
  });
}

}  // namespace

void start_report_if_due(FollowState& s, const FollowEvents& events) {
  if (s.reporting.valid() || s.options.report_every_s <= 0) return;
  if (s.last_report && seconds_since(*s.last_report) < s.options.report_every_s) return;
  start_report(s, events);
}

void finish_report(FollowState& s, const FollowEvents& events, bool wait) {
  if (!s.reporting.valid()) return;
  if (!wait && s.reporting.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  const ReportDone done = s.reporting.get();
  s.status.report_seconds_last = done.seconds;
  if (!done.error.empty()) {
    if (events.warning)
      events.warning("report of publish " + std::to_string(s.reporting_publish) + ": " +
                     done.error);
    return;
  }
  ++s.status.reports;
  s.status.report_publish = s.reporting_publish;
  write_status(s);
}

void report_last_map(FollowState& s, const FollowEvents& events) {
  finish_report(s, events, true);
  if (s.status.publishes == 0 || s.status.report_publish == s.status.publishes) return;
  start_report(s, events);
  finish_report(s, events, true);
}

}  // namespace objmap::pipeline
