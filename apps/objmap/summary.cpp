// objmap summary: one table for many recordings (the run folders of `objmap run` or of the
// Snakemake workflow, scripts/workflow/Snakefile): objects per class, duplicates, trajectory and
// object errors where there is ground truth, time and memory per stage, and the recordings that
// failed.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "command.h"
#include "objmap/io/atomic.h"
#include "objmap/io/run_summary.h"
#include "objmap/report/summary.h"

namespace objmap::app {
namespace {

namespace fs = std::filesystem;

struct SummaryCommand {
  std::vector<std::string> runs;
  std::string out;  // empty: the Markdown on stdout only
};

void run_summary(const SummaryCommand& c) {
  std::vector<io::NamedPath> inputs;
  for (const std::string& run : c.runs) inputs.push_back({"RUN", run});
  if (!c.out.empty()) {
    io::require_not_an_input({"--out", c.out}, inputs);
    io::require_replaceable(c.out, io::kSummaryFolder);
  }
  std::vector<io::RunSummary> runs;
  for (const std::string& run : c.runs) runs.push_back(io::read_run_summary(run));
  const std::string markdown = report::summary_markdown(runs);
  if (!c.out.empty()) {
    io::StagingDir staging(c.out, io::kSummaryFolder);
    io::write_file_atomic(staging.path() / "summary.md", markdown);
    io::write_file_atomic(staging.path() / "summary.csv", report::summary_csv(runs));
    io::write_file_atomic(staging.path() / "summary.json", report::summary_json(runs));
    io::write_file_atomic(staging.path() / "objects.svg", report::objects_per_recording_svg(runs));
    io::write_file_atomic(staging.path() / "errors.svg", report::errors_per_recording_svg(runs));
    staging.commit();
  }
  std::fputs(markdown.c_str(), stdout);
  if (!c.out.empty())
    std::printf(
        "\nwritten     %s/{summary.md, summary.csv, summary.json, objects.svg, errors.svg}\n",
        c.out.c_str());
}

void setup_summary(CLI::App& app) {
  auto cmd = std::make_shared<SummaryCommand>();
  CLI::App* c = app.add_subcommand(
      "summary",
      "One table for many recordings: each RUN is the output folder of objmap run or of the "
      "Snakemake workflow for one recording (docs/workflow.md). Objects per class, duplicates, "
      "ATE/RPE and object errors where there is ground truth, time and memory per stage, and "
      "the recordings that failed (stage and error line). Prints the Markdown; with --out also "
      "writes summary.md, summary.csv, summary.json, objects.svg and errors.svg");
  c->add_option("runs", cmd->runs, "run folders, one per recording")->required();
  c->add_option("--out", cmd->out,
                "output folder (created; an earlier objmap summary output is replaced, any other "
                "folder refused)");
  c->callback([cmd] { run_summary(*cmd); });
}

}  // namespace

OBJMAP_COMMAND(90, "summary", setup_summary);

}  // namespace objmap::app
