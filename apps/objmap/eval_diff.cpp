// objmap eval diff: a diff.json of objmap diff against the changes_gt.json of objmap synth
// --second-visit-of (docs/change.md, "Evaluation"). setup_eval_diff() is called by the `eval`
// group (eval.cpp).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "command.h"
#include "objmap/eval/diff.h"
#include "objmap/io/atomic.h"

namespace objmap::app {

namespace {

struct EvalDiffArgs {
  std::string diff_file;
  std::string gt_file;
  std::string json_file;  // empty: not written
  eval::DiffEvalOptions options;
};

void print_score(const char* name, const eval::ChangeScore& s) {
  std::printf("  %-8s %5d %5d %7d %9.3f %7.3f %6.3f\n", name, s.truth, s.found, s.correct,
              s.precision(), s.recall(), s.f1());
}

void run_eval_diff(const EvalDiffArgs& args) {
  check_naming_flags([&] { args.options.check(); }, {{"DiffEvalOptions.match_m", "--match"}});
  io::require_not_an_input({"--json", args.json_file},
                           {{"--diff", args.diff_file}, {"--gt", args.gt_file}});
  const eval::DiffEvalResult r = eval::evaluate_diff(args.diff_file, args.gt_file, args.options);
  if (!args.json_file.empty())
    io::write_file_atomic(args.json_file, eval::diff_eval_json(r, args.options));
  std::printf(
      "registration  rotation error %.3f deg, error at the objects %.2f cm "
      "(translation of true^-1 * est %.2f cm)\n",
      r.rotation_error_deg, 100.0 * r.error_at_objects_m, 100.0 * r.translation_error_m);
  std::printf("  %-8s %5s %5s %7s %9s %7s %6s\n", "change", "true", "found", "correct", "precision",
              "recall", "F1");
  print_score("moved", r.moved);
  print_score("added", r.added);
  print_score("removed", r.removed);
  print_score("all", r.all());
  std::printf("not seen      %d objects left unknown by the diff\n", r.not_seen);
}

}  // namespace

void setup_eval_diff(CLI::App& eval_app) {
  auto args = std::make_shared<EvalDiffArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "diff",
      "A diff.json of objmap diff against the changes_gt.json of objmap synth --second-visit-of: "
      "registration error (degrees, cm at the objects) and precision, recall and F1 of the moved, "
      "added and removed objects (a moved object reported as removed + added counts as two false "
      "positives and a miss)");
  cmd->add_option("--diff", args->diff_file, "diff.json of objmap diff")->required();
  cmd->add_option("--gt", args->gt_file, "changes_gt.json of objmap synth --second-visit-of")
      ->required();
  cmd->add_option("--match", args->options.match_m,
                  "a found change within this of a true one (metres; moved: at both ends) is it")
      ->capture_default_str();
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args] { run_eval_diff(*args); });
}

}  // namespace objmap::app
