#include "rgbdslam/map/map_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <fstream>
#include <random>

#include "test_support.h"

namespace rgbdslam {
namespace {

// A small camera keeps the images (and the test) small.
PinholeCamera mapFileTestCamera() {
  PinholeCamera camera;
  camera.name = "small";
  camera.width = 160, camera.height = 120;
  camera.fx = camera.fy = 130.0, camera.cx = 79.5, camera.cy = 59.5;
  camera.k1 = 0.01;
  camera.depth_factor = 5000.0;
  return camera;
}

// Keyframes 0, 1 and 3 (an id skipped, as a mapper skips lost keyframes) with textured
// images and depth (some pixels without a reading), points seen from several of them.
struct MapFileSample {
  std::vector<KeyframeData> keyframes;
  std::vector<MapPointData> points;
  Map map;
};

MapFileSample makeMapFileSample(const PinholeCamera& camera) {
  MapFileSample s;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> grey(0, 255), raw(2000, 20000);
  const KeyframeId ids[] = {0, 1, 3};
  for (KeyframeId id : ids) {
    KeyframeData kf;
    kf.id = id;
    kf.utime = 1000000 + id * 33333;
    kf.T_w_c = SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * id, Vec3(0.2, 1, 0.1).normalized())),
                   Vec3(0.1 * id, -0.05 * id, 0.02));
    kf.grey = cv::Mat(camera.height, camera.width, CV_8UC1);
    kf.depth = cv::Mat(camera.height, camera.width, CV_16UC1);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        kf.grey.at<uint8_t>(v, u) = static_cast<uint8_t>(grey(rng));
        kf.depth.at<uint16_t>(v, u) = (u + v) % 11 == 0 ? 0 : static_cast<uint16_t>(raw(rng));
      }
    }
    // Keyframe 3's depth as it comes over the link at every 4th pixel and row, decoded by
    // repetition: a slope, whose readings the map interpolates between (map/keyframe_depth.h),
    // and a block without a reading. The file keeps the readings, not the interpolation.
    if (id == 3) {
      for (int v = 0; v < camera.height; ++v) {
        for (int u = 0; u < camera.width; ++u) {
          kf.depth.at<uint16_t>(v, u) = u / 4 == 2 && v / 4 == 1 ? 0 : static_cast<uint16_t>(10000 + 20 * (u / 4) + 10 * (v / 4));
        }
      }
    }
    kf.depth_scale = camera.depth_factor;
    s.keyframes.push_back(kf);
  }
  for (int i = 0; i < 30; ++i) {
    const KeyframeId source = ids[i % 3];
    s.points.push_back({provisionalPointId(source, i), Vec3(0.01 * i, -0.3 + 0.02 * i, 1.5 + 0.03 * i), source,
                        Eigen::Vector2d(10.25 + 4 * i, 8.5 + 3 * i), i % kMaxLevels});
  }
  std::sort(s.points.begin(), s.points.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  for (KeyframeData& kf : s.keyframes) {
    for (const MapPointData& p : s.points) {
      if (p.source_keyframe <= kf.id) kf.measurements.push_back({p.id, p.uv + Eigen::Vector2d(0.5, 0.25), p.level, 0.1 * static_cast<double>(p.id % 7)});
    }
    std::sort(kf.measurements.begin(), kf.measurements.end(), [](const auto& a, const auto& b) { return a.point_id < b.point_id; });
  }
  for (const KeyframeData& kf : s.keyframes) {
    KeyframeData bare = kf;
    bare.measurements.clear();
    Keyframe* added = s.map.addKeyframe(makeKeyframe(bare, KeyframeBuildOptions{}));
    added->median_depth = 1.25 + kf.id;
  }
  for (const MapPointData& p : s.points) s.map.addPoint(MapPoint(p));
  for (const KeyframeData& kf : s.keyframes) {
    for (const Measurement& m : kf.measurements) s.map.addMeasurement(kf.id, m);
  }
  return s;
}

std::vector<uint8_t> encodedSample(const MapFileSample& s, const PinholeCamera& camera) {
  auto bytes = encodeMapFile(s.map, camera, SlamMode::kDepthInit);
  EXPECT_TRUE(bytes.ok()) << (bytes ? "" : bytes.error());
  return bytes ? *bytes : std::vector<uint8_t>{};
}

void writeRawFile(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

void putFileU32(std::vector<uint8_t>* bytes, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) (*bytes)[at + i] = static_cast<uint8_t>(v >> (8 * i));
}

// The sample map saved in a temporary folder.
class MapFileSaved : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(saveMap(s.map, camera, SlamMode::kDepthInit, path).ok()); }
  const PinholeCamera camera = mapFileTestCamera();
  const MapFileSample s = makeMapFileSample(camera);
  test::TempDir dir;
  const std::string path = dir.file("sample.map");
};

TEST_F(MapFileSaved, RoundTripKeepsEveryField) {
  auto loaded = loadMap(path, camera);
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  EXPECT_EQ(loaded->camera.name, "small");
  EXPECT_TRUE(sameCamera(loaded->camera, camera));
  EXPECT_EQ(loaded->mode, SlamMode::kDepthInit);
  ASSERT_EQ(loaded->keyframes.size(), s.keyframes.size());
  EXPECT_EQ(loaded->nextKeyframeId(), 4);
  for (size_t i = 0; i < s.keyframes.size(); ++i) {
    const KeyframeData& a = s.keyframes[i];
    const KeyframeData& b = loaded->keyframes[i];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.utime, a.utime);
    EXPECT_EQ(b.T_w_c.translation(), a.T_w_c.translation());
    EXPECT_NEAR(b.T_w_c.rotation().angularDistance(a.T_w_c.rotation()), 0.0, 1e-12);
    EXPECT_EQ(cv::norm(b.grey, a.grey, cv::NORM_INF), 0.0) << "grey of keyframe " << a.id;
    ASSERT_EQ(b.depth.type(), CV_16UC1);
    EXPECT_EQ(cv::norm(b.depth, a.depth, cv::NORM_INF), 0.0) << "depth of keyframe " << a.id;
    EXPECT_EQ(b.depth_scale, a.depth_scale);
    EXPECT_EQ(loaded->median_depths[i], 1.25 + static_cast<double>(a.id));
    ASSERT_EQ(b.measurements.size(), a.measurements.size());
    for (size_t k = 0; k < a.measurements.size(); ++k) {
      EXPECT_EQ(b.measurements[k].point_id, a.measurements[k].point_id);
      EXPECT_EQ(b.measurements[k].uv, a.measurements[k].uv);
      EXPECT_EQ(b.measurements[k].level, a.measurements[k].level);
      EXPECT_EQ(b.measurements[k].depth, a.measurements[k].depth);
    }
  }
  ASSERT_EQ(loaded->points.size(), s.points.size());
  for (size_t i = 0; i < s.points.size(); ++i) {
    EXPECT_EQ(loaded->points[i].id, s.points[i].id);
    EXPECT_EQ(loaded->points[i].p_w, s.points[i].p_w);
    EXPECT_EQ(loaded->points[i].source_keyframe, s.points[i].source_keyframe);
    EXPECT_EQ(loaded->points[i].uv, s.points[i].uv);
    EXPECT_EQ(loaded->points[i].level, s.points[i].level);
  }
}

TEST_F(MapFileSaved, SavingLeavesNoTemporaryFileAndReplacesAnOldMap) {
  writeRawFile(path, {'o', 'l', 'd'});
  ASSERT_TRUE(saveMap(s.map, camera, SlamMode::kDepthBa, path).ok());
  auto replaced = loadMap(path, camera);
  ASSERT_TRUE(replaced.ok()) << replaced.error();
  EXPECT_EQ(replaced->mode, SlamMode::kDepthBa);
  struct stat info {};
  EXPECT_NE(::stat((path + ".tmp-" + std::to_string(::getpid())).c_str(), &info), 0);
  // A folder that does not exist: an error, nothing written.
  const Status failed = saveMap(s.map, camera, SlamMode::kDepthBa, dir.file("missing/room.map"));
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().find("cannot create"), std::string::npos) << failed.error();
}

TEST(MapFile, TruncatedFilesSayWhere) {
  const PinholeCamera camera = mapFileTestCamera();
  const std::vector<uint8_t> bytes = encodedSample(makeMapFileSample(camera), camera);
  for (size_t length : {size_t{0}, size_t{5}, size_t{8}, size_t{20}, size_t{24}, size_t{100}, bytes.size() / 2,
                        bytes.size() - 1}) {
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<long>(length));
    auto loaded = decodeMapFile(cut, "cut.map");
    ASSERT_FALSE(loaded.ok()) << length;
    if (length < 8) {
      EXPECT_NE(loaded.error().find("not a map file"), std::string::npos) << loaded.error();
    } else {
      EXPECT_NE(loaded.error().find("truncated at byte " + std::to_string(length)), std::string::npos)
          << loaded.error();
    }
  }
}

TEST(MapFile, AFlippedByteIsAChecksumMismatch) {
  const PinholeCamera camera = mapFileTestCamera();
  std::vector<uint8_t> bytes = encodedSample(makeMapFileSample(camera), camera);
  bytes[bytes.size() / 3] ^= 0x10;
  auto loaded = decodeMapFile(bytes, "flipped.map");
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().find("checksum mismatch"), std::string::npos) << loaded.error();
}

TEST(MapFile, WrongMagicIsNotAMapFile) {
  const PinholeCamera camera = mapFileTestCamera();
  std::vector<uint8_t> bytes = encodedSample(makeMapFileSample(camera), camera);
  bytes[0] = 'X';
  auto loaded = decodeMapFile(bytes, "other.bin");
  ASSERT_FALSE(loaded.ok());
  EXPECT_EQ(loaded.error(), "other.bin: not a map file (no RGBDSMAP magic)");
  test::TempDir dir;
  auto missing = loadMap(dir.file("nothing.map"), camera);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("cannot open map file"), std::string::npos) << missing.error();
  auto folder = loadMap(dir.path(), camera);
  ASSERT_FALSE(folder.ok());
  EXPECT_NE(folder.error().find("not a map file"), std::string::npos) << folder.error();
}

TEST(MapFile, ANewerVersionIsRefusedByNumber) {
  const PinholeCamera camera = mapFileTestCamera();
  std::vector<uint8_t> bytes = encodedSample(makeMapFileSample(camera), camera);
  putFileU32(&bytes, 8, kMapFileVersion + 1);
  auto loaded = decodeMapFile(bytes, "new.map");
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().find("version " + std::to_string(kMapFileVersion + 1) + " not supported"),
            std::string::npos)
      << loaded.error();
}

TEST_F(MapFileSaved, AnotherCameraIsRefusedWithBothDescribed) {
  PinholeCamera other = camera;
  other.name = "other";
  other.fx = 131.0;
  auto loaded = loadMap(path, other);
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().find("made with camera 'small' 160x120 fx 130"), std::string::npos) << loaded.error();
  EXPECT_NE(loaded.error().find("this run's camera is 'other' 160x120 fx 131"), std::string::npos) << loaded.error();
  other = camera;
  other.name = "renamed";  // the name is a label: the same intrinsics load
  EXPECT_TRUE(loadMap(path, other).ok());
}

// A valid checksum over wrong content (a writer's bug, or a deliberate edit) is still held
// to every bound: counts beyond the bytes left, an unknown point.
TEST(MapFile, ContentWithAValidChecksumIsStillChecked) {
  const PinholeCamera camera = mapFileTestCamera();
  const std::vector<uint8_t> good = encodedSample(makeMapFileSample(camera), camera);
  auto reseal = [](std::vector<uint8_t> bytes) {
    // Recomputes the header's CRC so that only the content check can fail.
    const uint32_t crc = static_cast<uint32_t>(crc32(0L, bytes.data() + 24, static_cast<uInt>(bytes.size() - 24)));
    putFileU32(&bytes, 20, crc);
    return bytes;
  };
  // The point count (the last u32 before the points) claims far more than is there.
  const size_t points_at = good.size() - 30 * (8 + 24 + 8 + 4 + 16) - 4;
  std::vector<uint8_t> bytes = good;
  putFileU32(&bytes, points_at, 1000000);
  auto loaded = decodeMapFile(reseal(bytes), "count.map");
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().find("corrupt at byte " + std::to_string(points_at)), std::string::npos) << loaded.error();
  // The first point's id changed: measurements name a point the file lacks.
  bytes = good;
  bytes[points_at + 4] ^= 0x01;
  loaded = decodeMapFile(reseal(bytes), "id.map");
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().find("corrupt at byte"), std::string::npos) << loaded.error();
}

// Bounded fuzzing: random truncations and flips, with and without a resealed checksum, give
// an error or a map, never a crash (run under the sanitizers in CI).
TEST(MapFile, RandomDamageNeverCrashes) {
  const PinholeCamera camera = mapFileTestCamera();
  const std::vector<uint8_t> good = encodedSample(makeMapFileSample(camera), camera);
  std::mt19937 rng(11);
  std::uniform_int_distribution<size_t> any_byte(0, good.size() - 1);
  std::uniform_int_distribution<int> any_bit(0, 7);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> bytes = good;
    if (trial % 3 == 0) {
      bytes.resize(any_byte(rng));
    } else {
      for (int k = 0; k < 1 + trial % 4; ++k) bytes[any_byte(rng)] ^= static_cast<uint8_t>(1 << any_bit(rng));
    }
    if (trial % 2 == 1 && bytes.size() >= 24) {
      putFileU32(&bytes, 20, static_cast<uint32_t>(crc32(0L, bytes.data() + 24, static_cast<uInt>(bytes.size() - 24))));
    }
    auto loaded = decodeMapFile(bytes, "fuzz.map");
    if (!loaded.ok()) {
      ++refused;
      EXPECT_FALSE(loaded.error().empty());
    }
  }
  EXPECT_GT(refused, 200);  // damage is almost always noticed (a flip in a pixel may not be)
}

}  // namespace
}  // namespace rgbdslam
