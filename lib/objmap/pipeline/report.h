#pragma once
#include <cstddef>
#include <filesystem>
#include <string>

#include "objmap/report/page.h"

// `objmap report`: one self-contained HTML page (and a Markdown summary) of a fuse run: the
// semantic map seen from above with the objects, the trajectories coloured by their error, the
// error over time, a thumbnail per object and the paper's tables. Written atomically to OUT
// (default RUN/report): report.html, report.md and their pictures.
namespace objmap::pipeline {

struct ReportOptions {
  std::filesystem::path run;  // fuse output folder
  // The run as the page names it, when `run` is a copy of it (objmap follow reports hard links of
  // RUN/map); default `run`.
  std::filesystem::path shown_run;
  // The poses of the run's trajectory (the file run.json names) read from this file instead
  // (objmap follow: the lines read so far of a trajectory still being written); default that file.
  std::filesystem::path trajectory;
  std::filesystem::path out;  // default RUN/report
  std::filesystem::path gt;   // ground-truth trajectory; default the dataset's groundtruth.txt
  std::filesystem::path
      corrected;  // corrected trajectory; default RUN/trajectory_corrected.txt if present
  std::filesystem::path
      gt_objects;  // ground-truth objects; default the dataset's objects_gt.json if present
  std::filesystem::path reference;  // or a reference map RUN_GT/objects.json
  std::string gt_class = "object";  // class of the objects of a cuboid list
  std::string up = "auto";          // world up axis: auto (objects.json), x, y or z
  double pixel_m = 0.005;           // top view resolution
  int thumbnail_px = 160;           // thumbnail side
  // The 3D view draws the semantic map thinned to at most this many points: 200k draw smoothly in
  // a browser and keep report.html at a few MB.
  std::size_t view_points = 200000;
  // Whether the options are sound and the output may be replaced; throws the usage error (naming
  // the flag) otherwise.
  void check() const;
};

struct ReportResult {
  report::PageContent page;   // what the page shows (its summary line and notes for the app)
  std::filesystem::path out;  // the report folder written
};

// Reads the run, makes the page and writes the report folder. Throws InputError for bad input.
ReportResult run_report(const ReportOptions& options);

}  // namespace objmap::pipeline
