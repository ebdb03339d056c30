// make-fuzz-seeds OUT_DIR SOURCE_DIR: writes each fuzz target's seed corpus, OUT_DIR/<target>/,
// from the project's own encoders (toLcm on the test samples), the journal and log formats,
// and the shipped config/ files. Run by scripts/fuzz; nothing here is committed.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "common/map_journal.h"
#include "rgbdslam/image/codec.h"
#include "rgbdslam/map/map_file.h"
#include "sample_messages.h"

using namespace rgbdslam;
namespace fs = std::filesystem;

namespace {

void write(const fs::path& dir, const std::string& name, const std::vector<uint8_t>& bytes) {
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                                    static_cast<std::streamsize>(bytes.size()));
}

void writeMessages(const fs::path& out) {
  const RgbdFrame frame = test::sampleFrame();
  write(out / "fuzz_rgbd_frame", "raw_zlib", test::encode(toLcm(frame, FrameEncoding{})));
  write(out / "fuzz_rgbd_frame", "jpeg_raw", test::encode(toLcm(frame, FrameEncoding{true, 90, false, 1})));
  RgbdFrame depth_only = test::sampleFrame(16, 12);
  depth_only.colour = cv::Mat();
  write(out / "fuzz_rgbd_frame", "depth_only", test::encode(toLcm(depth_only, FrameEncoding{})));
  const KeyframeData keyframe = test::sampleKeyframe();
  write(out / "fuzz_keyframe", "lossless", test::encode(toLcm(keyframe)));
  KeyframeData anchored = keyframe;  // names the keyframe its pose rests on (mapper.h, "Anchor")
  anchored.anchor = keyframe.id - 1;
  anchored.T_w_anchor = SE3(Mat3::Identity(), Vec3(0.5, 0.0, -0.25));
  write(out / "fuzz_keyframe", "anchored", test::encode(toLcm(anchored)));
  write(out / "fuzz_keyframe", "jpeg_half", test::encode(toLcm(keyframe, KeyframeEncoding{true, 75, 2})));
  write(out / "fuzz_keyframe", "jpeg_quarter", test::encode(toLcm(keyframe, KeyframeEncoding{true, 75, 4})));
  KeyframeEncoding inverse{true, 75, 4};
  inverse.inverse_depth_step = 8.3e-4;  // the tracker's default: a quarter of the depth sigma
  write(out / "fuzz_keyframe", "jpeg_quarter_inverse", test::encode(toLcm(keyframe, inverse)));
  inverse.depth_step = 1;
  write(out / "fuzz_keyframe", "jpeg_inverse", test::encode(toLcm(keyframe, inverse)));
  inverse.depth_step = 8;  // the link budget's last rung
  write(out / "fuzz_keyframe", "jpeg_eighth_inverse", test::encode(toLcm(keyframe, inverse)));
  write(out / "fuzz_map", "snapshot", test::encode(toLcm(test::sampleMapUpdate())));
  MapUpdate delta;
  delta.map_id = 3, delta.version = 4, delta.acked_below = 2;
  write(out / "fuzz_map", "delta", test::encode(toLcm(delta)));
  write(out / "fuzz_status", "tracker", test::encode(toLcm(test::sampleStatus())));
  write(out / "fuzz_status", "empty", test::encode(toLcm(ComponentStatus{})));
  write(out / "fuzz_pose", "tracking", test::encode(toLcm(test::samplePose(), 77)));
  write(out / "fuzz_map_receipt", "behind", test::encode(toLcm(test::sampleReceipt())));
  MapReceipt first;  // a new tracker's first receipt: nothing applied, keyframe 0 sendable
  first.map_id = 1;
  write(out / "fuzz_map_receipt", "first", test::encode(toLcm(first)));
}

void writeFiles(const fs::path& out, const fs::path& source) {
  fs::create_directories(out / "fuzz_camera");
  for (const auto& entry : fs::directory_iterator(source / "config/cameras")) {
    if (entry.path().extension() != ".yaml") continue;
    fs::copy_file(entry.path(), out / "fuzz_camera" / entry.path().filename(), fs::copy_options::overwrite_existing);
  }
  fs::create_directories(out / "fuzz_config");
  fs::copy_file(source / "config/slam.yaml", out / "fuzz_config/slam.yaml", fs::copy_options::overwrite_existing);
  const std::string small = "%YAML:1.0\ntracker:\n  fine_max_points: 500\nmapper:\n  min_depth_m: 0.5\n";
  write(out / "fuzz_config", "small.yaml", std::vector<uint8_t>(small.begin(), small.end()));
  std::string tum = "# colour\n1.000000 rgb/1.png\n1.033333 rgb/1.png\n";
  tum += '\0';
  tum += "# depth\n1.005000 depth/1.png\n";
  write(out / "fuzz_tum_list", "pair", std::vector<uint8_t>(tum.begin(), tum.end()));
}

void writeJournalAndLog(const fs::path& out) {
  const fs::path state = out / "journal-state";
  fs::remove_all(state);
  MapJournal::Contents contents;
  auto journal = MapJournal::open(state.string(), &contents);
  if (!journal) throw std::runtime_error(journal.error());
  const auto keyframe = test::encode(toLcm(test::sampleKeyframe()));
  if (!journal->appendKeyframe(keyframe.data(), keyframe.size()) || !journal->appendVersion(1)) {
    throw std::runtime_error("cannot write the seed journal");
  }
  std::ifstream in(state / "map.journal", std::ios::binary);
  write(out / "fuzz_journal", "keyframe_and_version",
        std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()));
  fs::remove_all(state);
  std::vector<uint8_t> log;
  test::appendLogEvent(log, 0, "SLAM_POSE", test::encode(toLcm(test::samplePose(), 1)));
  test::appendLogEvent(log, 1, "RGBD_FRAME", test::encode(toLcm(test::sampleFrame(16, 12), FrameEncoding{})));
  test::appendLogEvent(log, 2, "RGBD_FRAME", test::encode(toLcm(test::sampleFrame(16, 12), FrameEncoding{true, 80, true, 1})));
  write(out / "fuzz_lcm_log", "two_frames", log);
}

// A map file of one keyframe (the sample keyframe, its points and measurements).
void writeMapFile(const fs::path& out) {
  const KeyframeData sample = test::sampleKeyframe();
  PinholeCamera camera;
  camera.width = sample.grey.cols;
  camera.height = sample.grey.rows;
  camera.cx = (camera.width - 1) / 2.0;
  camera.cy = (camera.height - 1) / 2.0;
  camera.depth_factor = sample.depth_scale;
  Map map;
  KeyframeData bare = sample;
  bare.measurements.clear();
  map.addKeyframe(makeKeyframe(bare, KeyframeBuildOptions{}));
  for (const MapPointData& p : sample.new_points) map.addPoint(MapPoint(p));
  for (const Measurement& m : sample.measurements) {
    if (map.point(m.point_id)) map.addMeasurement(sample.id, m);
  }
  const auto bytes = encodeMapFile(map, camera, SlamMode::kDepthBa);
  if (!bytes) throw std::runtime_error("cannot encode the seed map: " + bytes.error());
  write(out / "fuzz_map_file", "one_keyframe", *bytes);
}

// JPEG and PNG images of each kind the suite reads, each read each way (the first byte).
void writeImages(const fs::path& out) {
  const RgbdFrame frame = test::sampleFrame();
  cv::Mat grey;
  cv::cvtColor(frame.colour, grey, cv::COLOR_BGR2GRAY);
  const std::vector<std::pair<std::string, std::vector<uint8_t>>> images = {
      {"grey_jpeg", encodeJpeg(grey, 75, true)}, {"colour_jpeg", encodeJpeg(frame.colour, 90)},
      {"grey_png", encodePng(grey)}, {"colour_png", encodePng(frame.colour)}, {"depth_png", encodePng(frame.depth)}};
  for (const auto& [name, bytes] : images) {
    for (uint8_t read = 0; read < 3; ++read) {
      std::vector<uint8_t> seed{read};
      seed.insert(seed.end(), bytes.begin(), bytes.end());
      write(out / "fuzz_image", name + "_" + std::to_string(read), seed);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: make-fuzz-seeds OUT_DIR SOURCE_DIR\n";
    return 2;
  }
  try {
    writeMessages(argv[1]);
    writeFiles(argv[1], argv[2]);
    writeJournalAndLog(argv[1]);
    writeMapFile(argv[1]);
    writeImages(argv[1]);
  } catch (const std::exception& e) {
    std::cerr << "make-fuzz-seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
