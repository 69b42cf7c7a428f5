// A bad option of detect, track, correct, eval, report or synth is named by the flag the user gave
// (not a library struct member), and a negative number for an unsigned one is refused, not wrapped
// round.
#include <gtest/gtest.h>

#include "support/test_support.h"

namespace objmap::test {
namespace {

// Each flag with a value out of its range: exit 2, one line that starts with the flag.
void expect_flags_named(const std::vector<std::string>& command,
                        const std::vector<std::pair<std::string, std::string>>& cases) {
  for (const auto& [flag, value] : cases) {
    std::vector<std::string> args = command;
    args.insert(args.end(), {flag, value});
    const RunResult r = run_objmap(args);
    EXPECT_EQ(r.exit_code, 2) << flag;
    EXPECT_EQ(r.err.rfind("objmap: error: " + flag + ": ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

TEST(DetectCli, BadOptionNamesItsFlag) {
  TempDir dir;
  fs::create_directories(dir / "d");
  write_text(dir / "m.weights", "");
  expect_flags_named({"detect", "--dataset", (dir / "d").string(), "--model",
                      (dir / "m.weights").string(), "--out", (dir / "o").string()},
                     {{"--score-threshold", "2"}, {"--nms-threshold", "-1"}});
}

TEST(EvalFlagsCli, BadOptionNamesItsFlag) {
  TempDir dir;
  const std::string t = (dir / "t.txt").string();
  expect_flags_named({"eval", "ate", "--gt", t, "--est", t},
                     {{"--max-diff", "-1"}, {"--offset", "nan"}});
  expect_flags_named({"eval", "rpe", "--gt", t, "--est", t},
                     {{"--delta", "0"}, {"--offset", "nan"}, {"--max-diff", "-1"}});
  expect_flags_named({"eval", "objects", "--map", t, "--reference", t}, {{"--gate", "-1"}});
  expect_flags_named({"eval", "tracks", "--gt", t, "--est", t}, {{"--min-iou", "2"}});
  expect_flags_named({"eval", "masks", "--run", t}, {{"--depth-tolerance", "-1"}});
}

TEST(CommandsCli, AnUnknownCommandIsNamed) {
  const RunResult top = run_objmap({"frobnicate", "--x"});
  EXPECT_EQ(top.exit_code, 2);
  EXPECT_NE(top.err.find("unknown command 'frobnicate'; expected one of synth, run, validate"),
            std::string::npos)
      << top.err;
  const RunResult eval = run_objmap({"eval", "atee"});
  EXPECT_EQ(eval.exit_code, 2);
  EXPECT_NE(eval.err.find("unknown command 'atee'; expected one of ate, rpe, objects, scene, "
                          "surface, tracks, masks"),
            std::string::npos)
      << eval.err;
  EXPECT_EQ(std::count(eval.err.begin(), eval.err.end(), '\n'), 1) << eval.err;
}

TEST(CommandsCli, AnUnknownCommandBesideHelpIsNamedNotHelped) {
  // --help was honoured first: the main help on stdout and exit 0.
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"NOSUCHCOMMAND", "--help"}, {"eval", "nosuch", "--help"}}) {
    const RunResult r = run_objmap(args);
    EXPECT_EQ(r.exit_code, 2) << args[0];
    EXPECT_NE(r.err.find("unknown command '" + args[args.size() - 2] + "'"), std::string::npos)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  const RunResult help = run_objmap({"eval", "ate", "--help"});  // a known command: its help
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_NE(help.out.find("--gt"), std::string::npos);
}

TEST(CommandsCli, APathTheSystemCannotResolveIsBadInput) {
  // A symbolic link loop as the dataset: the filesystem's error was exit 1 ("internal error").
  TempDir dir;
  fs::create_symlink(dir / "loop", dir / "loop");
  const RunResult r = run_objmap({"validate", "--dataset", (dir / "loop").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find((dir / "loop").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("symbolic links"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(FuseFlagsCli, AThresholdNoScoreCanPassIsRefused) {
  // P of eq 22 is at most w_id + w_d + w_m (1 by default): --match-threshold 2 matched nothing.
  TempDir dir;
  const std::string t = (dir / "t").string();
  for (const char* flag : {"--match-threshold", "--merge-threshold"}) {
    const RunResult r = run_objmap({"fuse", "--dataset", t, "--trajectory", t, "--segmentation", t,
                                    "--out", (dir / "o").string(), flag, "2"});
    EXPECT_EQ(r.exit_code, 2) << flag;
    EXPECT_NE(
        r.err.find(std::string("(") + flag + "): must be in [0, w_id + w_d + w_m = 1.000000)"),
        std::string::npos)
        << r.err;
  }
}

TEST(ReportFlagsCli, BadOptionNamesItsFlag) {
  TempDir dir;
  expect_flags_named({"report", "--run", (dir / "run").string()}, {{"--pixel", "0"},
                                                                   {"--pixel", "nan"},
                                                                   {"--thumbnail", "5"},
                                                                   {"--up", "w"},
                                                                   {"--view-points", "10"}});
}

TEST(CorrectCli, BadOptionNamesItsFlag) {
  TempDir dir;
  expect_flags_named({"correct", "--run", (dir / "run").string(), "--out", (dir / "o").string()},
                     {{"--icp-max-view-angle", "-5"},
                      {"--icp-link-max-view-angle", "0"},
                      {"--link-sigma", "0"},
                      {"--link-sigma-deg", "-1"},
                      {"--held-out-link-improvement", "5"},
                      {"--icp-inlier-distance", "0"},
                      {"--icp-min-overlap", "2"},
                      {"--min-pairs", "0"},
                      {"--observation-sigma", "0"},
                      {"--odometry-sigma-fraction", "-1"},
                      {"--ray-sigma-factor", "0"},
                      {"--max-translation", "-1"},
                      {"--max-translation-per-m", "-1"},
                      {"--max-rotation", "-1"},
                      {"--max-rotation-per-m", "-1"},
                      {"--held-out-improvement", "5"},
                      {"--reweight-rounds", "-1"},
                      {"--min-improvement", "5"},
                      {"--threads", "99"}});
}

TEST(TrackCli, BadOptionNamesItsFlag) {
  TempDir dir;
  const std::pair<std::string, std::string> cases[] = {{"--max-age", "-1"},
                                                       {"--n-init", "0"},
                                                       {"--lambda", "2"},
                                                       {"--gate-3d-m", "-1"},
                                                       {"--gate-3d-speed", "-1"},
                                                       {"--gate-3d-history", "0"},
                                                       {"--max-cosine-distance", "3"},
                                                       {"--max-iou-distance", "5"},
                                                       {"--std-position", "0"},
                                                       {"--std-velocity", "0"},
                                                       {"--min-score", "nan"}};
  expect_flags_named({"track", "--dataset", (dir / "d").string(), "--segmentation",
                      (dir / "s").string(), "--out", (dir / "o").string()},
                     {std::begin(cases), std::end(cases)});
}

TEST(SynthCli, NegativeSeedIsRefused) {
  TempDir dir;
  const RunResult r = run_objmap({"synth", "--out", (dir / "s").string(), "--seed", "-1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err,
            "objmap: usage error: --seed: must be a whole number >= 0, got '-1' (see "
            "'objmap --help')\n");
  EXPECT_FALSE(fs::exists(dir / "s"));
}

}  // namespace
}  // namespace objmap::test
