// objmap diff: what changed between two visits of a place (docs/change.md).
#include <cmath>
#include <cstdio>
#include <memory>

#include "command.h"
#include "objmap/pipeline/diff.h"

namespace objmap::app {
namespace {

struct DiffCommand {
  std::string before, after, out, align;
  pipeline::DiffOptions options;
};

void print_diff(const pipeline::DiffOptions& o, const pipeline::DiffResult& r) {
  const change::Registration& g = r.registration;
  const Vec3 t = g.before_from_after.translation();
  std::printf("wrote         %s\n", (o.out / "diff.json").string().c_str());
  std::printf(
      "visits        before %zu objects, %zu dense points, %zu views; after %zu, %zu, %zu\n",
      r.before_objects, r.before_dense_points, r.before_views, r.after_objects,
      r.after_dense_points, r.after_views);
  std::printf("registration  %s: yaw %.2f deg, tilt %.2f deg, translation (%.3f, %.3f, %.3f) m\n",
              g.source.c_str(), g.yaw_deg, g.tilt_deg, t.x(), t.y(), t.z());
  std::printf(
      "              %d common objects (rms %.3f m), ICP fitness %.3f / both %.3f (rms %.4f m)\n",
      g.common_objects, g.coarse_rms_m, g.fitness, g.fitness_both, g.rms_m);
  std::printf(
      "uncertainty   %.3f m at the objects, %.2f deg yaw (dense lower bound %.4f m / %.3f deg)\n",
      g.uncertainty_at_objects_m, g.uncertainty_yaw_deg, g.sigma_translation_m, g.sigma_yaw_deg);
  std::printf("objects      ");
  for (change::Status s :
       {change::Status::kUnchanged, change::Status::kMoved, change::Status::kRemoved,
        change::Status::kAdded, change::Status::kChangedClass, change::Status::kNotSeenAgain,
        change::Status::kNotSeenBefore})
    std::printf(" %s %d", change::status_name(s), r.changes.count(s));
  std::printf("\n");
  for (const change::ObjectChange& c : r.changes.objects) {
    if (c.status == change::Status::kUnchanged) continue;
    const std::string cls = c.before_id ? c.before_class : c.after_class;
    std::printf("  %-15s %-12s before %-4s after %-4s %s\n", change::status_name(c.status),
                cls.c_str(), c.before_id ? std::to_string(*c.before_id).c_str() : "-",
                c.after_id ? std::to_string(*c.after_id).c_str() : "-", c.why.c_str());
  }
  for (const auto& [cls, n] : r.changes.left_out)
    std::printf("left out      %d %s (moves by itself)\n", n, cls.c_str());
  std::printf("time          read %.2f s, register %.2f s, classify %.2f s\n", r.seconds_read,
              r.seconds_register, r.seconds_classify);
}

void run_diff_command(DiffCommand& cmd) {
  pipeline::DiffOptions& o = cmd.options;
  o.before = cmd.before;
  o.after = cmd.after;
  o.out = cmd.out;
  o.align = cmd.align;
  check_naming_flags([&] { o.check(); },
                     {{"RegistrationOptions.min_fitness", "--min-fitness"},
                      {"RegistrationOptions.min_common_objects", "--min-common-objects"},
                      {"RegistrationOptions.icp_voxel_m", "--icp-voxel"},
                      {"RegistrationOptions.icp_final_correspondence_m", "--icp-final-distance"},
                      {"RegistrationOptions.icp_max_points", "--icp-points"},
                      {"ClassifyOptions.same_place_m", "--same-place"},
                      {"ClassifyOptions.max_range_m", "--max-range"}});
  const pipeline::DiffResult r = pipeline::run_diff(o);
  print_diff(o, r);
}

void setup_diff(CLI::App& app) {
  auto cmd = std::make_shared<DiffCommand>();
  auto* c = app.add_subcommand(
      "diff",
      "What changed between two visits of a place: registers the after run's world to the before "
      "run's (yaw about up + translation: objects, then ICP of the dense maps), then gives every "
      "object a status: unchanged, moved, removed, added, changed_class, not_seen_again / "
      "not_seen_before (its place was out of the other visit's view). Writes DIFF/diff.json. "
      "Exit 2 naming why when the two runs do not register (too few common objects, low ICP "
      "fitness).");
  c->add_option("--before", cmd->before, "run folder of objmap fuse: the first visit")->required();
  c->add_option("--after", cmd->after, "run folder of objmap fuse: the second visit")->required();
  c->add_option("--out", cmd->out, "output folder (diff.json)")->required();
  c->add_option("--align", cmd->align,
                "a known transform instead of the registration: a JSON file with "
                "before_from_after (16 numbers, row-major), a diff.json or a changes_gt.json");
  c->add_option("--min-fitness", cmd->options.registration.min_fitness,
                "ICP fitness below which the runs do not register")
      ->capture_default_str();
  c->add_option("--min-common-objects", cmd->options.registration.min_common_objects,
                "objects that must agree on the coarse placement")
      ->capture_default_str();
  c->add_option("--icp-voxel", cmd->options.registration.icp_voxel_m,
                "the dense maps are thinned to one point per voxel of this size for ICP, metres")
      ->capture_default_str();
  c->add_option("--icp-final-distance", cmd->options.registration.icp_final_correspondence_m,
                "ICP's last round pairs points closer than this, metres")
      ->capture_default_str();
  c->add_option("--icp-points", cmd->options.registration.icp_max_points,
                "the after map's ICP points, at most")
      ->capture_default_str();
  c->add_option("--same-place", cmd->options.classify.same_place_m,
                "two objects closer than this (metres; more for large objects) are at the same "
                "place")
      ->capture_default_str();
  c->add_option("--max-range", cmd->options.classify.max_range_m,
                "a view sees a place up to this depth, metres")
      ->capture_default_str();
  c->callback([cmd] { run_diff_command(*cmd); });
}

}  // namespace

OBJMAP_COMMAND(75, "diff", setup_diff);

}  // namespace objmap::app
