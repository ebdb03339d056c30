// Map files (map_file.h): encoding, a decoder that bounds every read, atomic saving.
#include "rgbdslam/map/map_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>

#include "rgbdslam/image/codec.h"
#include "rgbdslam/image/pyramid.h"

namespace rgbdslam {
namespace {

constexpr char kMapFileMagic[8] = {'R', 'G', 'B', 'D', 'S', 'M', 'A', 'P'};
constexpr size_t kMapFileHeaderBytes = 24;  // magic 8, version 4, length 8, crc 4
// Sane limits: a claimed count or length above them is corruption, whatever the bytes left.
constexpr uint32_t kMapFileMaxString = 1024;
constexpr uint32_t kMapFileMaxKeyframes = 1u << 20;  // point ids hold 2^43 keyframes; far more
constexpr uint32_t kMapFileMaxMeasurements = kProvisionalPointsPerKeyframe;
constexpr uint32_t kMapFileMaxPoints = 1u << 28;
constexpr int kMapFileMaxImageSide = 1 << 14;  // [px]
constexpr double kMapFileMaxCoordinate = 1e6;  // [m]: beyond, a position is corrupt
constexpr double kMapFileQuaternionTolerance = 1e-6;
// A measurement's and a point's encoded size: counts claimed beyond bytes / size are corrupt.
constexpr size_t kMapFileMeasurementBytes = 8 + 16 + 4 + 8;
constexpr size_t kMapFilePointBytes = 8 + 24 + 8 + 4 + 16;

uint32_t mapFileCrc(const uint8_t* data, size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes at most 4 GB per call.
  while (size > 0) {
    const uInt chunk = static_cast<uInt>(std::min<size_t>(size, 1u << 30));
    crc = crc32(crc, data, chunk);
    data += chunk, size -= chunk;
  }
  return static_cast<uint32_t>(crc);
}

class MapFileWriter {
 public:
  void u8(uint8_t v) { bytes_.push_back(v); }
  void u32(uint32_t v) { little(v, 4); }
  void u64(uint64_t v) { little(v, 8); }
  void i32(int32_t v) { u32(static_cast<uint32_t>(v)); }
  void i64(int64_t v) { u64(static_cast<uint64_t>(v)); }
  void f64(double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, 8);
    u64(bits);
  }
  void blob(const std::vector<uint8_t>& data) {
    u32(static_cast<uint32_t>(data.size()));
    bytes_.insert(bytes_.end(), data.begin(), data.end());
  }
  void str(const std::string& s) { blob(std::vector<uint8_t>(s.begin(), s.end())); }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  void little(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) bytes_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  std::vector<uint8_t> bytes_;
};

// Reads the payload; every read is held to the bytes left. The first failure sticks: later
// reads return zeros, and error() says what failed at which byte of the file.
class MapFileReader {
 public:
  MapFileReader(const uint8_t* data, size_t size, size_t file_offset)
      : data_(data), size_(size), base_(file_offset) {}

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  size_t left() const { return size_ - pos_; }
  size_t fileOffset() const { return base_ + pos_; }
  void fail(const std::string& what) { failAt(fileOffset(), what); }
  // 'file_offset': where the bad field starts.
  void failAt(size_t file_offset, const std::string& what) {
    if (ok()) error_ = "corrupt at byte " + std::to_string(file_offset) + ": " + what;
  }

  uint64_t unsignedLE(int n) {
    if (!ok()) return 0;
    if (left() < static_cast<size_t>(n)) {
      fail("ends inside a field");
      return 0;
    }
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(data_[pos_ + i]) << (8 * i);
    pos_ += static_cast<size_t>(n);
    return v;
  }
  uint8_t u8() { return static_cast<uint8_t>(unsignedLE(1)); }
  uint32_t u32() { return static_cast<uint32_t>(unsignedLE(4)); }
  int32_t i32() { return static_cast<int32_t>(u32()); }
  int64_t i64() { return static_cast<int64_t>(unsignedLE(8)); }
  double f64(const char* what) {
    const uint64_t bits = unsignedLE(8);
    double v;
    std::memcpy(&v, &bits, 8);
    if (ok() && !std::isfinite(v)) fail(std::string(what) + " is not finite");
    return ok() ? v : 0.0;
  }
  // A count whose entries take at least 'entry_bytes' each, at most 'limit'.
  uint32_t count(const char* what, uint32_t limit, size_t entry_bytes) {
    const size_t at = fileOffset();
    const uint32_t n = u32();
    if (ok() && (n > limit || static_cast<uint64_t>(n) * entry_bytes > left())) {
      failAt(at, std::string(what) + " count " + std::to_string(n) + " exceeds the bytes left");
      return 0;
    }
    return ok() ? n : 0;
  }
  // A length-prefixed byte range, as a pointer into the payload.
  std::pair<const uint8_t*, size_t> blob(const char* what, size_t limit) {
    const size_t at = fileOffset();
    const uint32_t n = u32();
    if (ok() && (n > limit || n > left())) {
      failAt(at, std::string(what) + " length " + std::to_string(n) + " exceeds the bytes left");
    }
    if (!ok()) return {nullptr, 0};
    const uint8_t* p = data_ + pos_;
    pos_ += n;
    return {p, n};
  }
  std::string str(const char* what) {
    const auto [p, n] = blob(what, kMapFileMaxString);
    return p ? std::string(reinterpret_cast<const char*>(p), n) : std::string();
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  size_t base_;  // the payload's offset in the file, for messages
  std::string error_;
};

void writeSavedCamera(MapFileWriter* w, const PinholeCamera& c) {
  w->str(c.name);
  w->i32(c.width), w->i32(c.height);
  for (double v : {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3, c.depth_factor}) w->f64(v);
}

PinholeCamera readSavedCamera(MapFileReader* r) {
  PinholeCamera c;
  c.name = r->str("camera name");
  c.width = r->i32(), c.height = r->i32();
  if (r->ok() && (c.width <= 0 || c.height <= 0 || c.width > kMapFileMaxImageSide || c.height > kMapFileMaxImageSide)) {
    r->fail("camera size " + std::to_string(c.width) + "x" + std::to_string(c.height));
  }
  for (double* v : {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2, &c.p1, &c.p2, &c.k3, &c.depth_factor}) {
    *v = r->f64("a camera parameter");
  }
  if (r->ok() && (c.fx <= 0 || c.fy <= 0 || c.depth_factor <= 0)) r->fail("camera focal length or depth factor <= 0");
  return c;
}

void writeSavedPose(MapFileWriter* w, const SE3& T) {
  for (int i = 0; i < 3; ++i) w->f64(T.translation()[i]);
  const Eigen::Quaterniond& q = T.rotation();
  for (double v : {q.x(), q.y(), q.z(), q.w()}) w->f64(v);
}

SE3 readSavedPose(MapFileReader* r) {
  Vec3 t;
  for (int i = 0; i < 3; ++i) t[i] = r->f64("a keyframe position");
  double q[4];
  for (double& v : q) v = r->f64("a keyframe rotation");
  const Eigen::Quaterniond quaternion(q[3], q[0], q[1], q[2]);
  if (r->ok() && (t.cwiseAbs().maxCoeff() > kMapFileMaxCoordinate ||
                  std::abs(quaternion.norm() - 1.0) > kMapFileQuaternionTolerance)) {
    r->fail("keyframe pose out of range or rotation not a unit quaternion");
  }
  return r->ok() ? SE3(quaternion, t) : SE3();
}

// The keyframe's depth in metres (KeyframeDepth::metres(), NaN = none) back in raw units:
// exact for readings that came from raw units at this scale (float holds raw / scale to far
// better than half a unit).
cv::Mat metricDepthToRaw(const cv::Mat& metres, double scale) {
  cv::Mat raw(metres.size(), CV_16UC1);
  for (int v = 0; v < metres.rows; ++v) {
    const float* in = metres.ptr<float>(v);
    uint16_t* out = raw.ptr<uint16_t>(v);
    for (int u = 0; u < metres.cols; ++u) {
      const double units = std::isfinite(in[u]) ? std::round(in[u] * scale) : 0.0;
      out[u] = units > 0.0 && units <= 65535.0 ? static_cast<uint16_t>(units) : 0;
    }
  }
  return raw;
}

Status writeSavedKeyframe(MapFileWriter* w, const Keyframe& kf, const PinholeCamera& camera) {
  if (kf.cold()) return Error{"keyframe " + std::to_string(kf.id) + " holds no image (a cold tracker keyframe)"};
  w->i64(kf.id), w->i64(kf.utime);
  writeSavedPose(w, kf.T_w_c);
  w->f64(kf.median_depth);
  w->blob(encodePng(kf.grey()));
  w->u8(kf.depth.empty() ? 0 : 1);
  if (!kf.depth.empty()) {
    w->f64(camera.depth_factor);
    w->blob(compressDepth(metricDepthToRaw(kf.depth.metres(), camera.depth_factor)));
  }
  // Id order, so that equal maps give equal files.
  std::map<PointId, Measurement> sorted(kf.measurements().begin(), kf.measurements().end());
  w->u32(static_cast<uint32_t>(sorted.size()));
  for (const auto& [id, m] : sorted) {
    w->i64(m.point_id), w->f64(m.uv.x()), w->f64(m.uv.y()), w->i32(m.level), w->f64(m.depth);
  }
  return Status{};
}

bool savedPixelInImage(const Eigen::Vector2d& uv, const PinholeCamera& camera) {
  return uv.x() >= 0 && uv.y() >= 0 && uv.x() <= camera.width - 1 && uv.y() <= camera.height - 1;
}

void readSavedMeasurements(MapFileReader* r, const PinholeCamera& camera, KeyframeData* kf) {
  const uint32_t n = r->count("measurement", kMapFileMaxMeasurements, kMapFileMeasurementBytes);
  kf->measurements.reserve(n);
  for (uint32_t i = 0; i < n && r->ok(); ++i) {
    Measurement m;
    m.point_id = r->i64();
    m.uv.x() = r->f64("a measurement pixel"), m.uv.y() = r->f64("a measurement pixel");
    m.level = r->i32();
    m.depth = r->f64("a measurement depth");
    if (r->ok() && (m.point_id < 0 || m.level < 0 || m.level >= kMaxLevels || m.depth < 0 ||
                    !savedPixelInImage(m.uv, camera))) {
      r->fail("measurement of point " + std::to_string(m.point_id) + " in keyframe " +
              std::to_string(kf->id) + " out of range");
    }
    kf->measurements.push_back(m);
  }
}

// One keyframe; 'previous' is the last keyframe's id (ids increase).
void readSavedKeyframe(MapFileReader* r, const PinholeCamera& camera, KeyframeId previous, LoadedMap* map) {
  KeyframeData kf;
  kf.id = r->i64();
  if (r->ok() && (kf.id <= previous || kf.id >= int64_t{1} << 40)) {
    r->fail("keyframe id " + std::to_string(kf.id) + " not increasing or out of range");
  }
  kf.utime = r->i64();
  kf.T_w_c = readSavedPose(r);
  const double median_depth = r->f64("a keyframe's median depth");
  const size_t grey_at = r->fileOffset();
  const auto [grey, grey_size] = r->blob("grey image", r->left());
  if (r->ok()) {
    auto image = decodeImage(grey, grey_size, 1, camera.width, camera.height);
    if (!image) r->fail("keyframe " + std::to_string(kf.id) + " grey image (byte " + std::to_string(grey_at) + "): " + image.error());
    else kf.grey = *image;
  }
  const uint8_t has_depth = r->u8();
  if (r->ok() && has_depth > 1) r->fail("keyframe " + std::to_string(kf.id) + " depth flag " + std::to_string(has_depth));
  if (r->ok() && has_depth == 1) {
    kf.depth_scale = r->f64("a depth scale");
    if (r->ok() && kf.depth_scale <= 0) r->fail("depth scale <= 0");
    const auto [depth, depth_size] = r->blob("depth image", r->left());
    if (r->ok()) {
      auto image = decompressDepth(depth, depth_size, camera.width, camera.height);
      if (!image) r->fail("keyframe " + std::to_string(kf.id) + " depth: " + image.error());
      else kf.depth = *image;
    }
  }
  readSavedMeasurements(r, camera, &kf);
  if (!r->ok()) return;
  map->keyframes.push_back(std::move(kf));
  map->median_depths.push_back(median_depth);
}

void readSavedPoints(MapFileReader* r, const PinholeCamera& camera, LoadedMap* map) {
  const uint32_t n = r->count("point", kMapFileMaxPoints, kMapFilePointBytes);
  map->points.reserve(n);
  // Source keyframes are looked up by id: keyframes are in id order.
  auto hasKeyframe = [&](KeyframeId id) {
    const auto it = std::lower_bound(map->keyframes.begin(), map->keyframes.end(), id,
                                     [](const KeyframeData& k, KeyframeId v) { return k.id < v; });
    return it != map->keyframes.end() && it->id == id;
  };
  for (uint32_t i = 0; i < n && r->ok(); ++i) {
    const size_t at = r->fileOffset();
    MapPointData p;
    p.id = r->i64();
    for (int k = 0; k < 3; ++k) p.p_w[k] = r->f64("a point position");
    p.source_keyframe = r->i64();
    p.level = r->i32();
    p.uv.x() = r->f64("a point's pixel"), p.uv.y() = r->f64("a point's pixel");
    if (!r->ok()) return;
    const bool increasing = map->points.empty() || p.id > map->points.back().id;
    if (p.id < 0 || !increasing || p.level < 0 || p.level >= kMaxLevels || !savedPixelInImage(p.uv, camera) ||
        p.p_w.cwiseAbs().maxCoeff() > kMapFileMaxCoordinate || !hasKeyframe(p.source_keyframe)) {
      r->failAt(at, "point " + std::to_string(p.id) + " out of range, not in id order, or its source keyframe " +
              std::to_string(p.source_keyframe) + " is missing");
      return;
    }
    map->points.push_back(p);
  }
}

// Every measurement names a point of the file.
void checkSavedMeasuredPoints(MapFileReader* r, const LoadedMap& map) {
  for (const KeyframeData& kf : map.keyframes) {
    for (const Measurement& m : kf.measurements) {
      const auto it = std::lower_bound(map.points.begin(), map.points.end(), m.point_id,
                                       [](const MapPointData& p, PointId v) { return p.id < v; });
      const bool known = it != map.points.end() && it->id == m.point_id;
      if (!known) {
        r->fail("keyframe " + std::to_string(kf.id) + " measures point " + std::to_string(m.point_id) +
                ", which the file does not hold");
        return;
      }
    }
  }
}

Expected<std::vector<uint8_t>> readMapFileBytes(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return Error{"cannot open map file " + path + ": " + std::strerror(errno)};
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    return Error{path + ": not a map file (not a regular file)"};
  }
  std::vector<uint8_t> bytes;
  bytes.reserve(static_cast<size_t>(info.st_size));
  uint8_t chunk[1 << 16];
  for (ssize_t n; (n = ::read(fd, chunk, sizeof chunk)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string error = "cannot read map file " + path + ": " + std::strerror(errno);
      ::close(fd);
      return Error{error};
    }
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  ::close(fd);
  return bytes;
}

Status writeMapFileBytes(int fd, const std::vector<uint8_t>& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return Error{std::strerror(errno)};
    done += static_cast<size_t>(n);
  }
  return Status{};
}

}  // namespace

std::unique_ptr<Keyframe> LoadedMap::buildKeyframe(size_t i, const KeyframeBuildOptions& options) const {
  std::unique_ptr<Keyframe> keyframe = makeKeyframe(keyframes.at(i), options);
  keyframe->median_depth = median_depths.at(i);
  return keyframe;
}

bool sameCamera(const PinholeCamera& a, const PinholeCamera& b) {
  auto close = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x)); };
  return a.width == b.width && a.height == b.height && close(a.fx, b.fx) && close(a.fy, b.fy) &&
         close(a.cx, b.cx) && close(a.cy, b.cy) && close(a.k1, b.k1) && close(a.k2, b.k2) &&
         close(a.p1, b.p1) && close(a.p2, b.p2) && close(a.k3, b.k3) && close(a.depth_factor, b.depth_factor);
}

std::string describeCamera(const PinholeCamera& c) {
  std::ostringstream out;
  out << "'" << c.name << "' " << c.width << "x" << c.height << " fx " << c.fx << " fy " << c.fy
      << " cx " << c.cx << " cy " << c.cy << " k1 " << c.k1 << " k2 " << c.k2 << " p1 " << c.p1
      << " p2 " << c.p2 << " k3 " << c.k3 << " depth factor " << c.depth_factor;
  return out.str();
}

Expected<std::vector<uint8_t>> encodeMapFile(const Map& map, const PinholeCamera& camera, SlamMode mode) {
  MapFileWriter payload;
  writeSavedCamera(&payload, camera);
  payload.str(slamModeName(mode));
  payload.u32(static_cast<uint32_t>(map.numKeyframes()));
  for (const auto& [id, kf] : map.keyframes()) {
    if (Status s = writeSavedKeyframe(&payload, *kf, camera); !s) return Error{s.error()};
  }
  std::map<PointId, const MapPoint*> points;
  for (const auto& [id, p] : map.points()) points[id] = &p;
  payload.u32(static_cast<uint32_t>(points.size()));
  for (const auto& [id, p] : points) {
    payload.i64(p->id);
    for (int k = 0; k < 3; ++k) payload.f64(p->p_w[k]);
    payload.i64(p->source_keyframe), payload.i32(p->source_level);
    payload.f64(p->source_uv.x()), payload.f64(p->source_uv.y());
  }
  MapFileWriter file;
  for (char c : kMapFileMagic) file.u8(static_cast<uint8_t>(c));
  file.u32(kMapFileVersion);
  file.u64(payload.bytes().size());
  file.u32(mapFileCrc(payload.bytes().data(), payload.bytes().size()));
  file.bytes().insert(file.bytes().end(), payload.bytes().begin(), payload.bytes().end());
  return std::move(file.bytes());
}

Expected<LoadedMap> decodeMapFile(const std::vector<uint8_t>& bytes, const std::string& name) {
  if (bytes.size() < sizeof kMapFileMagic || std::memcmp(bytes.data(), kMapFileMagic, sizeof kMapFileMagic) != 0) {
    return Error{name + ": not a map file (no RGBDSMAP magic)"};
  }
  if (bytes.size() < kMapFileHeaderBytes) return Error{name + ": truncated at byte " + std::to_string(bytes.size()) + " (in the header)"};
  MapFileReader header(bytes.data(), kMapFileHeaderBytes, 0);
  header.unsignedLE(8);  // the magic
  const uint32_t version = header.u32();
  const uint64_t length = header.unsignedLE(8);
  const uint32_t crc = header.u32();
  if (version != kMapFileVersion) {
    return Error{name + ": map file version " + std::to_string(version) + " not supported (this build reads version " +
                 std::to_string(kMapFileVersion) + ")"};
  }
  const size_t present = bytes.size() - kMapFileHeaderBytes;
  if (length > present) {
    return Error{name + ": truncated at byte " + std::to_string(bytes.size()) + " (the header says " +
                 std::to_string(kMapFileHeaderBytes + length) + " bytes)"};
  }
  if (length < present) {
    return Error{name + ": " + std::to_string(present - length) + " bytes after the end of the map at byte " +
                 std::to_string(kMapFileHeaderBytes + length) + " (corrupt)"};
  }
  const uint8_t* payload = bytes.data() + kMapFileHeaderBytes;
  if (mapFileCrc(payload, present) != crc) return Error{name + ": checksum mismatch (the file is corrupt)"};

  MapFileReader r(payload, present, kMapFileHeaderBytes);
  LoadedMap map;
  map.camera = readSavedCamera(&r);
  const std::string mode = r.str("mode");
  if (r.ok()) {
    if (auto parsed = parseSlamMode(mode)) map.mode = *parsed;
    else r.fail("unknown mode '" + mode + "'");
  }
  const uint32_t keyframes = r.count("keyframe", kMapFileMaxKeyframes, 8 + 8 + 56 + 8 + 4 + 1 + 4);
  for (uint32_t i = 0; i < keyframes && r.ok(); ++i) {
    readSavedKeyframe(&r, map.camera, map.keyframes.empty() ? -1 : map.keyframes.back().id, &map);
  }
  readSavedPoints(&r, map.camera, &map);
  if (r.ok()) checkSavedMeasuredPoints(&r, map);
  if (r.ok() && r.left() != 0) r.fail(std::to_string(r.left()) + " bytes after the points");
  if (!r.ok()) return Error{name + ": " + r.error()};
  return map;
}

Status saveMap(const Map& map, const PinholeCamera& camera, SlamMode mode, const std::string& path) {
  auto bytes = encodeMapFile(map, camera, mode);
  if (!bytes) return Error{"cannot save map to " + path + ": " + bytes.error()};
  const std::string temporary = path + ".tmp-" + std::to_string(::getpid());
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Error{"cannot create " + temporary + ": " + std::strerror(errno)};
  Status written = writeMapFileBytes(fd, *bytes);
  if (written && ::fsync(fd) != 0) written = Error{std::strerror(errno)};
  if (::close(fd) != 0 && written) written = Error{std::strerror(errno)};
  if (written && ::rename(temporary.c_str(), path.c_str()) != 0) written = Error{std::strerror(errno)};
  if (!written) {
    ::unlink(temporary.c_str());
    return Error{"cannot save map to " + path + ": " + written.error()};
  }
  return Status{};
}

Expected<LoadedMap> loadMap(const std::string& path, const PinholeCamera& expected) {
  auto bytes = readMapFileBytes(path);
  if (!bytes) return Error{bytes.error()};
  auto map = decodeMapFile(*bytes, path);
  if (!map) return map;
  if (!sameCamera(map->camera, expected)) {
    return Error{path + ": made with camera " + describeCamera(map->camera) + "; this run's camera is " +
                 describeCamera(expected)};
  }
  return map;
}

}  // namespace rgbdslam
