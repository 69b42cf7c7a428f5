#pragma once
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "objmap/fusion/object_map.h"
#include "objmap/io/ply.h"
#include "objmap/pipeline/correct.h"
#include "objmap/pipeline/dense_cloud.h"
#include "objmap/pipeline/fuse.h"
#include "objmap/pipeline/fuse_inputs.h"
#include "objmap/scene/scene.h"

// The files of a run folder as `objmap fuse` writes them (and `objmap correct`, which fuses again):
// the maps (map_dense.ply, map_semantic.ply, map_objects.ply, map_mesh.ply), one PLY per object,
// objects.json, run.json and the dataset's own trajectory; `objmap correct`'s correction.json
// (run_folder_correction.cpp). Their readers: run_json.h.
namespace objmap::pipeline {

// The point counts of the written maps (run.json "points").
struct MapPoints {
  std::size_t semantic = 0;
  std::size_t objects = 0;
};

// Step 5: the maps: map_dense.ply and the semantic map (the dense points with the objects'
// colours) on two more threads, the objects-only map and a PLY per object meanwhile; returns the
// objects' records of objects.json.
nlohmann::ordered_json write_maps(const FuseOptions& options, const std::filesystem::path& dir,
                                  const io::PlyWriteOptions& ply, const DenseCloud& dense_cloud,
                                  const FuseResult& result, MapPoints& points);

// objects.json: the records of the confirmed objects (`objects_json`, from write_maps), the
// sightings and the scene.
void write_objects_json(const std::filesystem::path& dir,
                        const nlohmann::ordered_json& objects_json,
                        const std::vector<fusion::ObjectRecord>& sightings,
                        const scene::SceneGraph& scene);

// run.json: options, inputs with checksums, counts per stage, Table 6, time per stage, memory.
void write_run_json(const std::filesystem::path& dir, const FuseOptions& options,
                    const FuseInputs& inputs, const fusion::ObjectMapOptions& object_options,
                    const MapPoints& maps, const FuseResult& result);

// The dataset's own poses as OUT/dataset_trajectory.txt, when the run has no --trajectory.
void write_dataset_trajectory(const std::filesystem::path& dir, const FuseOptions& options,
                              const FuseInputs& inputs, const FuseResult& result);

// correction.json (schemas/correction.schema.json): the run, the method and the verdict, the
// options, the counts, the consistency, the largest correction, the time taken, and per keyframe,
// observation and view link; `input_trajectory` is the trajectory the run was fused with.
std::string correction_json(const CorrectOptions& options, const CorrectResult& result,
                            const RunProblem& rp, const std::string& input_trajectory);

}  // namespace objmap::pipeline
