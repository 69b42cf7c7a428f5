#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <utility>
#include <vector>

// Each subcommand lives in its own file: an options struct, a `setup_<name>(CLI::App&)` that
// declares the flags and a `run_<name>(const Options&)` that does the work and returns the exit
// code. The file registers its setup with OBJMAP_COMMAND so main.cpp needs no list.
namespace objmap::app {

using SetupFn = std::function<void(CLI::App& parent)>;

// Registers a subcommand; `order` sorts them in --help (the pipeline's order).
bool register_command(int order, const std::string& name, SetupFn setup);

// Calls every registered setup in order.
void setup_all(CLI::App& app);

// Runs `check` (an options struct's check()); an InputError naming a library option
// ("TrackerOptions.max_age") is thrown again naming the flag bound to it ("--max-age"), the name
// the user wrote.
void check_naming_flags(const std::function<void()>& check,
                        const std::vector<std::pair<std::string, std::string>>& option_to_flag);

// --dataset and --layout as every command that reads a recording takes them.
inline constexpr const char* kDatasetHelp =
    "recording folder in any layout: TUM RGB-D (rgb.txt, depth.txt), 7-Scenes / 3DMatch, ScanNet "
    "(SensReader export), Replica (NICE-SLAM), Open3D reconstruction system, or any posed capture "
    "described by an objmap_layout.json, or a ROS 1 .bag (RealSense recordings) (docs/formats.md)";
inline constexpr const char* kLayoutHelp =
    "auto (detected from the folder's contents), tum, 7scenes, scannet, replica, open3d, generic, "
    "rosbag, or the path of an objmap_layout.json";
inline constexpr const char* kTopicsHelp =
    "rosbag: the colour and the depth image topic, COLOR,DEPTH (default: chosen from the bag: one "
    "colour and one depth stream, an aligned depth first, infrared never)";

}  // namespace objmap::app

#define OBJMAP_COMMAND(order, name, fn) \
  static const bool objmap_registered_##fn = ::objmap::app::register_command(order, name, fn)
