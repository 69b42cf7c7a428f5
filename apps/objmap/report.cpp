// objmap report: a picture and a summary of a fuse run (the top view of the semantic map with the
// objects drawn on it, and a Markdown table of the objects).
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "command.h"
#include "objmap/core/error.h"
#include "objmap/fusion/palette.h"
#include "objmap/io/atomic.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/ply.h"
#include "objmap/report/topview.h"

namespace objmap::app {
namespace {

namespace fs = std::filesystem;

struct ReportOptions {
  fs::path run;            // fuse output folder
  fs::path out;            // default RUN/report
  std::string up = "z";    // world up axis
  double pixel_m = 0.005;  // top view resolution
};

void run_report(const ReportOptions& options) {
  const fs::path objects_file = options.run / "objects.json";
  const fs::path map_file = options.run / "map_semantic.ply";
  require(options.up == "x" || options.up == "y" || options.up == "z", "--up",
          "'" + options.up + "'; expected x, y or z");
  const auto objects = io::read_objects_json(objects_file);
  const PointCloud map = io::read_ply(map_file);

  // 1. The top view with the objects.
  report::TopViewOptions view_options;
  view_options.up_axis = options.up[0] - 'x';
  view_options.pixel_m = options.pixel_m;
  std::vector<report::TopViewObject> drawn;
  for (const auto& o : objects)
    drawn.push_back({o.id, std::to_string(o.id) + " " + o.class_name, o.obb,
                     fusion::class_color(o.class_name)});
  const report::TopView view = report::render_top_view(map, drawn, view_options);
  std::vector<unsigned char> png;
  cv::imencode(".png", view.image, png);

  // 2. The summary: counts of the run, the objects table, the picture.
  nlohmann::json run;
  if (std::ifstream in(options.run / "run.json"); in)
    run = nlohmann::json::parse(in, nullptr, false);
  std::ostringstream md;
  md << "# objmap run " << options.run.filename().string() << "\n\n";
  if (run.is_object() && run.contains("counts")) {
    const auto& c = run["counts"];
    md << "Keyframes: " << c.value("keyframes", 0) << " of " << c.value("frames", 0)
       << " frames; instances: " << c.value("instances", 0)
       << "; objects: " << c.value("objects_confirmed", 0) << " confirmed of "
       << c.value("objects_before_confirmation", 0) << ".\n\n";
  }
  md << "![top view of the semantic map](topview.png)\n\n";
  md << "Top view of `map_semantic.ply` (" << view.pixel_m * 1000 << " mm per pixel, " << options.up
     << " up); each object's oriented box outlined and labelled \"id class\".\n\n";
  md << "| id | class | x | y | z | points | observations | score |\n";
  md << "|---:|---|---:|---:|---:|---:|---:|---:|\n";
  std::map<std::string, int> per_class;
  char line[256];
  for (const auto& o : objects) {
    std::snprintf(line, sizeof line, "| %d | %s | %.3f | %.3f | %.3f | %zu | %d | %.2f |\n", o.id,
                  o.class_name.c_str(), o.centroid.x(), o.centroid.y(), o.centroid.z(), o.points,
                  o.observations, o.score);
    md << line;
    ++per_class[o.class_name];
  }
  md << "\nObjects per class: ";
  bool first = true;
  for (const auto& [name, count] : per_class) {
    md << (first ? "" : ", ") << name << " " << count;
    first = false;
  }
  md << ".\n";

  const fs::path out = options.out.empty() ? options.run / "report" : options.out;
  io::StagingDir staging(out);
  io::write_file_atomic(staging.path() / "topview.png", std::string(png.begin(), png.end()));
  io::write_file_atomic(staging.path() / "report.md", md.str());
  staging.commit();
  std::printf("objects     %zu\n", objects.size());
  std::printf("written     %s/topview.png (%dx%d), %s/report.md\n", out.c_str(), view.image.cols,
              view.image.rows, out.c_str());
}

void setup_report(CLI::App& app) {
  auto options = std::make_shared<ReportOptions>();
  auto* cmd = app.add_subcommand(
      "report",
      "Pictures and a summary of a fuse run: OUT/topview.png (the semantic map seen from above "
      "with "
      "every object's box and label) and OUT/report.md (counts and the objects table).");
  cmd->add_option("--run", options->run, "the folder written by 'objmap fuse'")->required();
  cmd->add_option("--out", options->out, "output folder (default RUN/report)");
  cmd->add_option("--up", options->up, "world axis that points up: x, y or z")
      ->capture_default_str();
  cmd->add_option("--pixel", options->pixel_m, "top view resolution, metres per pixel")
      ->capture_default_str();
  cmd->callback([options] { run_report(*options); });
}

}  // namespace

OBJMAP_COMMAND(80, "report", setup_report);

}  // namespace objmap::app
