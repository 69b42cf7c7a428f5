#pragma once
#include <filesystem>
#include <string>

#include "objmap/sim/synth.h"

// Writes a SynthSequence as a TUM RGB-D folder with ground truth:
//   rgb/<t>.png  depth/<t>.png (16-bit, factor 5000)  rgb.txt  depth.txt  camera.json
//   groundtruth.txt  estimated.txt  estimated_slam_frame.txt (estimated.txt in its first camera's
//   frame)  objects_gt.json (objects, up, surfaces, `on` relations)  synth.json
//   segmentation/<t>.json (noisy)  segmentation_gt/<t>.json (exact, track_id = object id)
namespace objmap::sim {

// The whole folder is written under a temporary name and renamed to `out` at the end (an existing
// `out` is replaced). PNGs are encoded on `threads` threads (0 = all cores); the bytes do not
// depend on it. Throws InputError when `out` cannot be written.
void write_sequence(const std::filesystem::path& out, const SynthSequence& sequence,
                    int threads = 0);

// Fails early (InputError naming `out`) when `out` cannot become a folder: it is a file, or its
// parent cannot be created. Call it before the expensive synthesis.
void check_output_dir(const std::filesystem::path& out);

// Renders and writes batch by batch (memory stays at a few frames whatever the length), giving
// the same files as write_sequence(out, synthesize(options)). Returns the sequence without its
// frames (scene, camera, trajectories, segmentation error counts). `progress` gets frames done.
SynthSequence write_synthetic_sequence(const std::filesystem::path& out,
                                       const SynthOptions& options,
                                       const SynthProgress& progress = {});

// objects_gt.json text (schemas/objects_gt.schema.json): the world's up, the support surfaces
// (support.h) and per object id, class, centroid, obb, volume and what it rests on.
std::string objects_gt_json(const Scene& scene);

// synth.json text: the generator's options and the counts of segmentation errors made.
std::string synth_json(const SynthSequence& sequence);

// "%.6f" of a timestamp: the file stem used for rgb/, depth/ and segmentation files.
std::string timestamp_name(double timestamp);

}  // namespace objmap::sim
