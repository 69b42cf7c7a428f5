#include "objmap/io/camera_io.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::copy_tree;
using test::read_text;
using test::TempDir;
using test::write_text;

// ORB-SLAM2's Examples/RGB-D/TUM1.yaml (camera part).
const char* kTum1Yaml = R"(%YAML:1.0

# Camera calibration and distortion parameters (OpenCV)
Camera.fx: 517.306408
Camera.fy: 516.469215
Camera.cx: 318.643040
Camera.cy: 255.313989

Camera.k1: 0.262383
Camera.k2: -0.953104
Camera.p1: -0.005358
Camera.p2: 0.002628
Camera.k3: 1.163314

Camera.width: 640
Camera.height: 480

# Camera frames per second
Camera.fps: 30.0

# IR projector baseline times fx (aprox.)
Camera.bf: 40.0

# Color order of the images (0: BGR, 1: RGB. It is ignored if images are grayscale)
Camera.RGB: 1

# Close/Far threshold. Baseline times.
ThDepth: 40.0

# Deptmap values factor
DepthMapFactor: 5000.0
)";

// The reason of the InputError of read_camera_file(file); where goes to *where.
std::string camera_error(const fs::path& file, std::string* where = nullptr) {
  return test::error_reason([&] { read_camera_file(file); }, file.string(), where);
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(ReadCameraFile, YcbvJson) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f");
  const Camera c = read_camera_file(dir / "camera.json");
  EXPECT_EQ(c.fx, 1066.778);
  EXPECT_EQ(c.fy, 1067.487);
  EXPECT_EQ(c.cx, 312.9869);
  EXPECT_EQ(c.cy, 241.3109);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.depth_factor, 10000.0);
  EXPECT_FALSE(c.has_distortion());
  EXPECT_EQ(c.name, (dir / "camera.json").string());
}

TEST(ReadCameraFile, OrbSlam2Yaml) {
  TempDir dir;
  write_text(dir / "TUM1.yaml", kTum1Yaml);
  const Camera c = read_camera_file(dir / "TUM1.yaml");
  EXPECT_EQ(c.fx, 517.306408);
  EXPECT_EQ(c.cy, 255.313989);
  EXPECT_EQ(c.distortion[0], 0.262383);
  EXPECT_EQ(c.distortion[4], 1.163314);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.depth_factor, 5000.0);
  // Without size, k3 and DepthMapFactor: 640x480, k3 = 0, factor 5000.
  std::string text = replace(kTum1Yaml, "Camera.width: 640\nCamera.height: 480\n", "");
  text = replace(text, "Camera.k3: 1.163314\n", "");
  text = replace(text, "DepthMapFactor: 5000.0\n", "");
  write_text(dir / "mono.yml", text);
  const Camera m = read_camera_file(dir / "mono.yml");
  EXPECT_EQ(m.width, 640);
  EXPECT_EQ(m.height, 480);
  EXPECT_EQ(m.distortion[4], 0.0);
  EXPECT_EQ(m.depth_factor, 5000.0);
}

TEST(ReadCameraFile, YamlMissingOrBadField) {
  TempDir dir;
  std::string where;
  write_text(dir / "a.yaml", replace(kTum1Yaml, "Camera.fy: 516.469215\n", ""));
  EXPECT_EQ(camera_error(dir / "a.yaml", &where), "missing; it is required");
  EXPECT_EQ(where, (dir / "a.yaml").string() + ": Camera.fy");
  write_text(dir / "b.yaml", replace(kTum1Yaml, "Camera.cx: 318.643040", "Camera.cx: left"));
  EXPECT_EQ(camera_error(dir / "b.yaml", &where), "is not a number; expected a number");
  EXPECT_EQ(where, (dir / "b.yaml").string() + ": Camera.cx");
  write_text(dir / "c.yaml", replace(kTum1Yaml, "Camera.width: 640", "Camera.width: 640.5"));
  EXPECT_NE(camera_error(dir / "c.yaml", &where).find("expected a whole number of pixels > 0"),
            std::string::npos);
  write_text(dir / "d.yaml", replace(kTum1Yaml, "Camera.fx: 517.306408", "Camera.fx: -1"));
  EXPECT_EQ(camera_error(dir / "d.yaml"), "focal length fx/fy must be finite and > 0");
  write_text(dir / "e.yaml", "%YAML:1.0\nCamera.fx: [1, 2\n");
  EXPECT_NE(camera_error(dir / "e.yaml").find("not a readable OpenCV YAML file"),
            std::string::npos);
}

// A top level that is no mapping: OpenCV's FileStorage reads the file, then asserts isMap() when a
// key is looked up (a cv::Exception that was "internal error", exit 1; found by fuzz_camera_yaml,
// tests/fuzz/seeds/camera_yaml/finding_top_level_sequence.yaml).
TEST(ReadCameraFile, AYamlWhoseTopLevelIsNoMappingIsAnInputErrorNamingTheFile) {
  TempDir dir;
  std::string where;
  write_text(dir / "seq.yaml", "%YAML:1.\n- 1\n");
  EXPECT_EQ(camera_error(dir / "seq.yaml", &where),
            "the top level is a sequence, not a mapping; expected ORB-SLAM2 settings "
            "(Camera.fx: ...)");
  EXPECT_EQ(where, (dir / "seq.yaml").string());
  write_text(dir / "list.yaml", "%YAML:1.0\n- Camera.fx: 500\n- Camera.fy: 500\n");
  EXPECT_EQ(camera_error(dir / "list.yaml", &where),
            "the top level is a sequence, not a mapping; expected ORB-SLAM2 settings "
            "(Camera.fx: ...)");
  // An empty document is a mapping without keys.
  write_text(dir / "empty.yaml", "%YAML:1.0\n");
  EXPECT_EQ(camera_error(dir / "empty.yaml", &where), "missing; it is required");
  EXPECT_EQ(where, (dir / "empty.yaml").string() + ": Camera.fx");
}

TEST(ReadCameraFile, JsonMissingOrBadField) {
  TempDir dir;
  const std::string good =
      R"({"fx": 500, "fy": 500, "cx": 320, "cy": 240, "width": 640, "height": 480})";
  std::string where;
  write_text(dir / "ok.json", good);
  EXPECT_EQ(read_camera_file(dir / "ok.json").depth_factor, 5000.0);  // default

  write_text(dir / "a.json", replace(good, R"("fy": 500, )", ""));
  EXPECT_EQ(camera_error(dir / "a.json", &where), "missing; it is required");
  EXPECT_EQ(where, (dir / "a.json").string() + ": fy");
  write_text(dir / "b.json", replace(good, R"("cx": 320)", R"("cx": "320")"));
  EXPECT_EQ(camera_error(dir / "b.json", &where), "is \"320\"; expected a number");
  EXPECT_EQ(where, (dir / "b.json").string() + ": cx");
  write_text(dir / "c.json", replace(good, R"("width": 640)", R"("width": 0)"));
  EXPECT_EQ(camera_error(dir / "c.json", &where), "is 0; expected a whole number of pixels > 0");
  write_text(dir / "d.json", replace(good, "}", R"(, "distortion": [0.1, 0.2]})"));
  EXPECT_EQ(camera_error(dir / "d.json", &where),
            "is [0.1,0.2]; expected an array of 5 numbers [k1, k2, p1, p2, k3]");
  write_text(dir / "e.json", replace(good, "}", R"(, "fxx": 1})"));
  EXPECT_EQ(camera_error(dir / "e.json", &where).rfind("unknown field", 0), 0u);
  EXPECT_EQ(where, (dir / "e.json").string() + ": fxx");
  write_text(dir / "f.json", replace(good, "}", R"(, "depth_factor": -5})"));
  EXPECT_EQ(camera_error(dir / "f.json"), "depth_factor must be finite and > 0");
  write_text(dir / "g.json", "{\"fx\": 500,");
  EXPECT_EQ(camera_error(dir / "g.json").rfind("not valid JSON", 0), 0u);
  write_text(dir / "h.json", replace(good, "}", R"(, "k1": 0.1, "k3": 0.3, "name": "kinect"})"));
  const Camera h = read_camera_file(dir / "h.json");
  EXPECT_EQ(h.distortion[0], 0.1);
  EXPECT_EQ(h.distortion[4], 0.3);
  EXPECT_EQ(h.name, "kinect");
  write_text(dir / "i.txt", good);
  EXPECT_EQ(camera_error(dir / "i.txt"),
            "unknown camera file type '.txt'; expected .json or ORB-SLAM2 settings .yaml/.yml");
  EXPECT_EQ(camera_error(dir / "none.json"), "camera file not found");
}

TEST(ReadCameraFile, ABrokenYamlIsOneLine) {
  // OpenCV's parser message spans two lines; objmap's error is one.
  TempDir dir;
  write_text(dir / "orb.yaml", "%YAML:1.0\nCamera.fx: [1, 2\nCamera.fy: 3\n");
  try {
    read_camera_file(dir / "orb.yaml");
    FAIL();
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find("not a readable OpenCV YAML file"), std::string::npos) << what;
  }
}

TEST(ReadCameraFile, ASizeBeyondAnIntIsRefused) {
  // "width": 1e300 was cast to int to see whether it is whole
  // (undefined: UBSan float-cast-overflow in the fuzz build, fuzz_camera_json) before its range
  // was checked.
  TempDir dir;
  std::string where;
  for (const char* width : {"1e300", "-1e300", "640.5", "2e6"}) {
    write_text(dir / "camera.json",
               std::string(R"({"fx": 500, "fy": 500, "cx": 320, "cy": 240, )") + R"("width": )" +
                   width + R"(, "height": 480})");
    const std::string reason = camera_error(dir / "camera.json", &where);
    EXPECT_EQ(where, (dir / "camera.json").string() + ": width") << width;
    EXPECT_NE(reason.find("; expected a whole number of pixels > 0"), std::string::npos) << reason;
  }
  EXPECT_EQ(camera_error(dir / "camera.json"),
            "is 2000000.0; expected a whole number of pixels > 0");
}

TEST(ReadCameraFile, ANumberBeyondADoubleIsNamed) {
  // "fx": 1e999 overflows a double: nlohmann's out_of_range error was exit 1 naming no file.
  TempDir dir;
  write_text(dir / "camera.json", R"({"fx": 1e999, "fy": 525, "cx": 320, "cy": 240})");
  try {
    read_camera_file(dir / "camera.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "camera.json").string());
    EXPECT_NE(e.reason().find("number overflow parsing '1e999'"), std::string::npos) << e.what();
  }
}

TEST(WriteCameraJson, RoundTrip) {
  TempDir dir;
  Camera c = camera_preset("fr1");
  c.depth_factor = 1000.0;
  c.cx = 1.0 / 3.0;
  write_camera_json(dir / "cam.json", c);
  const Camera back = read_camera_file(dir / "cam.json");
  EXPECT_EQ(back.name, "fr1");
  EXPECT_EQ(back.cx, c.cx);
  EXPECT_EQ(back.fy, c.fy);
  EXPECT_EQ(back.distortion, c.distortion);
  EXPECT_EQ(back.depth_factor, 1000.0);
  EXPECT_EQ(back.width, 640);
}

TEST(ChooseCamera, FromFolderNames) {
  OBJMAP_DATA_OR_SKIP(data, "tum");
  CameraChoice c = choose_camera(data / "fr1_desk_9", "");
  EXPECT_EQ(c.camera.name, "fr1");
  EXPECT_EQ(c.camera.fx, 517.3);
  EXPECT_EQ(c.reason, "preset fr1 from the folder name 'fr1_desk_9'");
  c = choose_camera(data / "fr1_desk_9/", "");  // trailing slash
  EXPECT_EQ(c.reason, "preset fr1 from the folder name 'fr1_desk_9'");
  // fr3_cabinet_58kf's rgb.txt has no "# file" header: the folder name decides.
  c = choose_camera(data / "fr3_cabinet_58kf", "");
  EXPECT_EQ(c.camera.name, "fr3");
  EXPECT_EQ(c.reason, "preset fr3 from the folder name 'fr3_cabinet_58kf'");
  EXPECT_EQ(choose_camera(data / "fr1_rpy_every4", "").camera.name, "fr1");
}

TEST(ChooseCamera, CameraJsonInTheDataset) {
  OBJMAP_DATA_OR_SKIP(dir, "ycbv_0000_10f");
  const CameraChoice c = choose_camera(dir, "");
  EXPECT_EQ(c.camera.depth_factor, 10000.0);
  EXPECT_EQ(c.camera.fx, 1066.778);
  EXPECT_EQ(c.reason, "file " + (dir / "camera.json").string() + " in the dataset");
}

TEST(ChooseCamera, FromRgbTxtHeaderThenError) {
  OBJMAP_DATA_OR_SKIP(src, "tum/fr1_desk_9");
  TempDir tmp;
  const fs::path dir = tmp / "desk";
  fs::create_directories(dir);
  write_text(dir / "rgb.txt", read_text(src / "rgb.txt"));
  const CameraChoice c = choose_camera(dir, "");
  EXPECT_EQ(c.camera.name, "fr1");
  EXPECT_EQ(c.reason,
            "preset fr1 from rgb.txt's header \"# file: 'rgbd_dataset_freiburg1_desk.bag'\"");
  write_text(dir / "rgb.txt", "# color images\n1 rgb/1.png\n");
  try {
    choose_camera(dir, "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir.string());
    EXPECT_NE(e.reason().find("pass --camera"), std::string::npos);
  }
}

TEST(ChooseCamera, ExplicitArgument) {
  TempDir dir;
  CameraChoice c = choose_camera(dir.path(), "freiburg2");
  EXPECT_EQ(c.camera.name, "fr2");
  EXPECT_EQ(c.reason, "preset fr2 (--camera)");
  write_text(dir / "TUM1.yaml", kTum1Yaml);
  c = choose_camera(dir.path(), (dir / "TUM1.yaml").string());
  EXPECT_EQ(c.camera.fx, 517.306408);
  EXPECT_EQ(c.reason, "file " + (dir / "TUM1.yaml").string() + " (--camera)");
  try {
    choose_camera(dir.path(), "fr4");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--camera");
    EXPECT_EQ(e.reason(),
              "'fr4' is neither a preset (fr1, fr2, fr3, freiburg1..3) nor an existing camera "
              "file (.json, .yaml)");
  }
}

TEST(PresetFromName, Patterns) {
  EXPECT_EQ(preset_from_name("fr1_desk_9"), "fr1");
  EXPECT_EQ(preset_from_name("rgbd_dataset_freiburg3_long_office_household"), "fr3");
  EXPECT_EQ(preset_from_name("FR2-pioneer"), "fr2");
  EXPECT_EQ(preset_from_name("my_fr2"), "fr2");
  EXPECT_EQ(preset_from_name("frame1"), "");
  EXPECT_EQ(preset_from_name("fr12"), "");
  EXPECT_EQ(preset_from_name("ycbv_0000_10f"), "");
}

}  // namespace
}  // namespace objmap::io
