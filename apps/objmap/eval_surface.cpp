// objmap eval surface: each object's mesh and point cloud of a fuse run against the true surface of
// its model (accuracy, completeness, F-score; eval/surface.h). setup_eval_surface() is called by
// the `eval` group (eval.cpp).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "command.h"
#include "objmap/core/error.h"
#include "objmap/eval/surface.h"
#include "objmap/io/atomic.h"
#include "objmap/io/dataset.h"
#include "objmap/io/json_file.h"
#include "objmap/io/obj_mesh.h"
#include "objmap/io/ply.h"
#include "objmap/io/trajectory.h"

namespace objmap::app {

namespace {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

struct EvalSurfaceArgs {
  std::string run;        // RUN folder of objmap fuse
  std::string models;     // DIR with <name>.obj
  std::string poses;      // objects_pose.txt
  std::string json_file;  // empty: not written
  eval::SurfaceEvalOptions options;
};

// What the run says: its objects (class, box, files, the keyframes that saw each), the recording,
// its camera and trajectory.
struct RunObject {
  int id = -1;
  std::string cls, cloud_file, mesh_file;
  Vec3 centre = Vec3::Zero();
  std::vector<double> timestamps;
};
struct RunInputs {
  std::vector<RunObject> objects;
  io::Dataset dataset;
  Camera camera;
  Trajectory trajectory;
};

RunInputs read_run(const fs::path& run) {
  const nlohmann::json r = io::read_json_file(run / "run.json", "expected a run folder of fuse");
  const nlohmann::json o = io::read_json_file(run / "objects.json", "expected a run folder");
  RunInputs in;
  try {
    const auto& inputs = r.at("inputs");
    io::DatasetOptions dataset_options;
    dataset_options.layout = inputs.at("dataset").at("layout").get<std::string>();
    in.dataset =
        io::read_dataset(inputs.at("dataset").at("path").get<std::string>(), dataset_options);
    const auto& c = inputs.at("camera");
    in.camera.width = c.at("width");
    in.camera.height = c.at("height");
    in.camera.fx = c.at("fx");
    in.camera.fy = c.at("fy");
    in.camera.cx = c.at("cx");
    in.camera.cy = c.at("cy");
    for (int i = 0; i < 5; ++i) in.camera.distortion[i] = c.at("distortion").at(i);
    in.camera.depth_factor = c.at("depth_factor");
    in.trajectory = io::read_trajectory(inputs.at("trajectory").at("path").get<std::string>());
    for (const auto& j : o.at("objects")) {
      RunObject x;
      x.id = j.at("id");
      x.cls = j.at("class");
      x.cloud_file = j.at("ply");
      if (j.contains("mesh") && j["mesh"].at("file").is_string()) x.mesh_file = j["mesh"]["file"];
      for (int a = 0; a < 3; ++a)
        x.centre[a] = 0.5 * (j.at("aabb").at("min").at(a).get<double>() +
                             j.at("aabb").at("max").at(a).get<double>());
      for (const auto& obs : j.at("observations")) x.timestamps.push_back(obs.at("timestamp"));
      in.objects.push_back(x);
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(run.string(), std::string("run.json/objects.json: ") + e.what());
  }
  return in;
}

// The depth images and poses of the keyframes that observed `object`.
std::vector<eval::DepthImage> views_of(const RunObject& object, const RunInputs& in) {
  std::vector<eval::DepthImage> views;
  for (double t : object.timestamps) {
    const io::FramePair* frame = nullptr;
    for (const auto& f : in.dataset.frames)
      if (std::abs(f.rgb_timestamp - t) < 1e-3) frame = &f;
    const StampedPose* pose = nullptr;
    for (const auto& p : in.trajectory.poses)
      if (std::abs(p.timestamp - t) < 0.02 &&
          (!pose || std::abs(p.timestamp - t) < std::abs(pose->timestamp - t)))
        pose = &p;
    if (!frame || !pose) continue;
    views.push_back(
        {in.camera, pose->world_from_cam, io::read_frame_depth(in.dataset, *frame, in.camera)});
  }
  return views;
}

std::string class_of_model(std::string name) {
  for (char& c : name)
    if (c == '_') c = ' ';
  return name;
}

ordered_json scores_json(const eval::SurfaceScores& s) {
  return {{"samples", s.reconstruction_samples},
          {"accuracy_mean_mm", 1000 * s.accuracy_mean_m},
          {"accuracy_p90_mm", 1000 * s.accuracy_p90_m},
          {"precision", s.precision},
          {"completeness", s.completeness},
          {"fscore", s.fscore}};
}

std::string row(const std::string& model, const char* what, const eval::SurfaceScores& s) {
  char line[200];
  std::snprintf(line, sizeof(line), "  %-18s %-6s %8zu %9.2f %9.2f %9.3f %9.3f %9.3f\n",
                model.c_str(), what, s.reconstruction_samples, 1000 * s.accuracy_mean_m,
                1000 * s.accuracy_p90_m, s.precision, s.completeness, s.fscore);
  return line;
}

// One model: the run object of its class nearest to it, its mesh and its cloud scored.
ordered_json score_model(const io::ModelPose& pose, const EvalSurfaceArgs& args,
                         const RunInputs& in, std::ostream& text) {
  TriangleMesh truth = io::read_obj_mesh(fs::path(args.models) / (pose.name + ".obj"));
  for (Vec3f& v : truth.vertices) v = (pose.world_from_object * v.cast<double>()).cast<float>();
  Vec3 centre = Vec3::Zero();
  for (const Vec3f& v : truth.vertices) centre += v.cast<double>();
  centre /= static_cast<double>(truth.vertices.size());
  ordered_json j = {{"model", pose.name}, {"class", class_of_model(pose.name)}};
  const RunObject* object = nullptr;
  for (const RunObject& o : in.objects)
    if (o.cls == class_of_model(pose.name) &&
        (!object || (o.centre - centre).norm() < (object->centre - centre).norm()))
      object = &o;
  if (!object) {
    j["object"] = nullptr;
    text << "  " << pose.name << ": no object of its class in the run\n";
    return j;
  }
  j["object"] = object->id;
  const eval::SurfaceSamples samples = eval::sample_mesh(truth, args.options.sample_spacing_m);
  const std::vector<bool> seen = eval::seen_samples(samples, views_of(*object, in), args.options);
  std::vector<Vec3> seen_points;
  for (std::size_t i = 0; i < seen.size(); ++i)
    if (seen[i]) seen_points.push_back(samples.points[i]);
  j["truth_samples"] = samples.points.size();
  j["truth_samples_seen"] = seen_points.size();
  const eval::MeshDistance distance(truth);
  if (!object->mesh_file.empty()) {
    const TriangleMesh mesh = io::read_mesh_ply(fs::path(args.run) / object->mesh_file);
    const eval::SurfaceScores s =
        eval::score_surface(eval::sample_mesh(mesh, args.options.sample_spacing_m).points, distance,
                            seen_points, args.options);
    j["mesh"] = scores_json(s);
    text << row(pose.name, "mesh", s);
  } else {
    j["mesh"] = nullptr;
  }
  std::vector<Vec3> cloud;
  for (const Vec3f& p : io::read_ply(fs::path(args.run) / object->cloud_file).points)
    cloud.push_back(p.cast<double>());
  const eval::SurfaceScores s = eval::score_surface(cloud, distance, seen_points, args.options);
  j["cloud"] = scores_json(s);
  text << row(pose.name, "cloud", s);
  return j;
}

void run_eval_surface(const EvalSurfaceArgs& args) {
  check_naming_flags([&] { args.options.check(); },
                     {{"sample_spacing_m", "--spacing"},
                      {"threshold_m", "--threshold"},
                      {"visible_tolerance_m", "--visible-tolerance"}});
  io::require_not_an_input(
      {"--json", args.json_file},
      {{"--run", args.run}, {"--models", args.models}, {"--poses", args.poses}});
  const RunInputs in = read_run(args.run);
  const std::vector<io::ModelPose> poses = io::read_model_poses(args.poses);
  std::ostringstream text;
  char head[200];
  std::snprintf(head, sizeof(head), "  %-18s %-6s %8s %9s %9s %9s %9s %9s\n", "model", "what",
                "samples", "acc_mm", "acc90_mm", "prec", "compl", "F");
  text << "surface: accuracy (reconstruction -> true surface), completeness (seen true surface "
          "within "
       << 1000 * args.options.threshold_m << " mm), F-score\n"
       << head;
  ordered_json models = ordered_json::array();
  for (const io::ModelPose& pose : poses) models.push_back(score_model(pose, args, in, text));
  ordered_json doc = {{"run", args.run},
                      {"models", args.models},
                      {"poses", args.poses},
                      {"threshold_m", args.options.threshold_m},
                      {"sample_spacing_m", args.options.sample_spacing_m},
                      {"visible_tolerance_m", args.options.visible_tolerance_m},
                      {"objects", models}};
  if (!args.json_file.empty()) io::write_file_atomic(args.json_file, doc.dump(2) + "\n");
  std::cout << text.str();
}

}  // namespace

void setup_eval_surface(CLI::App& eval_app) {
  auto args = std::make_shared<EvalSurfaceArgs>();
  CLI::App* cmd = eval_app.add_subcommand(
      "surface",
      "Each object's mesh and cloud of a fuse run against its true model surface: accuracy (mean "
      "and 90th percentile, mm), completeness of the surface the cameras saw, F-score");
  cmd->add_option("--run", args->run, "Run folder of objmap fuse")->required();
  cmd->add_option("--models", args->models, "Folder of the true models, <name>.obj in metres")
      ->required();
  cmd->add_option(
         "--poses", args->poses,
         "The models' world poses: 'label name tx ty tz qx qy qz qw' per line "
         "(objects_pose.txt); an object is the run's nearest of class name with _ as space")
      ->required();
  cmd->add_option("--threshold", args->options.threshold_m, "Completeness/F-score distance, m")
      ->capture_default_str();
  cmd->add_option("--spacing", args->options.sample_spacing_m, "Mesh sample spacing, m")
      ->capture_default_str();
  cmd->add_option("--visible-tolerance", args->options.visible_tolerance_m,
                  "A true sample is seen when a view's depth there is within this, m")
      ->capture_default_str();
  cmd->add_option("--json", args->json_file, "Write the result as JSON here");
  cmd->callback([args] { run_eval_surface(*args); });
}

}  // namespace objmap::app
