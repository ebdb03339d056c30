#include "rgbdslam/map/map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rgbdslam {

void KeyframeBuildOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "keyframe_min_depth_m", &min_depth_m, 0.0, 100.0, "m",
          "keyframe depth readings nearer than this are invalid");
  r->bind(s, "keyframe_max_depth_m", &max_depth_m, 0.1, 100.0, "m",
          "keyframe depth readings farther than this are invalid");
}

std::optional<double> Keyframe::depthAt(const Eigen::Vector2d& uv) const {
  if (depth.empty()) return std::nullopt;
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  if (u < 0 || v < 0 || u >= depth.cols() || v >= depth.rows()) return std::nullopt;
  const float d = depth.at(u, v);
  if (!std::isfinite(d)) return std::nullopt;
  return d;
}

void Keyframe::releaseMappingData() {
  depth.release();
  std::vector<LevelCorners>().swap(corners);
  std::unordered_map<PointId, Measurement>().swap(measurements_);
}

cv::Mat depthToMetres(const cv::Mat& raw, double depth_scale, double min_m, double max_m) {
  if (raw.empty()) return cv::Mat();
  cv::Mat out(raw.size(), CV_32FC1);
  const double inv = 1.0 / depth_scale;
  for (int v = 0; v < raw.rows; ++v) {
    const uint16_t* in = raw.ptr<uint16_t>(v);
    float* o = out.ptr<float>(v);
    for (int u = 0; u < raw.cols; ++u) o[u] = rawDepthToMetres(in[u], inv, min_m, max_m);
  }
  return out;
}

std::unique_ptr<Keyframe> makeKeyframe(const KeyframeData& data, const KeyframeBuildOptions& options) {
  auto keyframe = std::make_unique<Keyframe>();
  keyframe->id = data.id;
  keyframe->utime = data.utime;
  keyframe->T_w_c = data.T_w_c;
  keyframe->depth = KeyframeDepth(data.depth, data.depth_scale, options.min_depth_m, options.max_depth_m);
  buildPyramid(data.grey, kMaxLevels, &keyframe->pyramid);
  detectPyramidCorners(keyframe->pyramid, options.corners, /*with_maxima=*/true, &keyframe->corners);
  keyframe->sbi = makeSmallBlurryImage(keyframe->pyramid);
  for (const auto& m : data.measurements) keyframe->measurements_[m.point_id] = m;
  return keyframe;
}

Keyframe* Map::addKeyframe(std::unique_ptr<Keyframe> keyframe) {
  Keyframe* raw = keyframe.get();
  for (const auto& [point_id, m] : raw->measurements_) observers_[point_id].push_back(raw->id);
  keyframes_[raw->id] = std::move(keyframe);
  return raw;
}

void Map::removeKeyframe(KeyframeId id) {
  const auto it = keyframes_.find(id);
  if (it == keyframes_.end()) return;
  for (const auto& [point_id, m] : it->second->measurements_) {
    const auto obs = observers_.find(point_id);
    if (obs == observers_.end()) continue;
    std::vector<KeyframeId>& ids = obs->second;
    ids.erase(std::remove(ids.begin(), ids.end(), id), ids.end());
    if (ids.empty()) observers_.erase(obs);
  }
  keyframes_.erase(it);
  removed_keyframes_.insert(id);
}

Keyframe* Map::keyframe(KeyframeId id) {
  const auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : it->second.get();
}

const Keyframe* Map::keyframe(KeyframeId id) const {
  const auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : it->second.get();
}

MapPoint* Map::addPoint(const MapPoint& point) {
  auto [it, inserted] = points_.try_emplace(point.id, point);
  if (!inserted) {
    const int projected = it->second.times_projected, found = it->second.times_found;
    const DepthRecord record = it->second.depth_record;
    it->second = point;
    it->second.times_projected = projected;
    it->second.times_found = found;
    it->second.depth_record = record;
  }
  return &it->second;
}

MapPoint* Map::point(PointId id) {
  const auto it = points_.find(id);
  return it == points_.end() ? nullptr : &it->second;
}

const MapPoint* Map::point(PointId id) const {
  const auto it = points_.find(id);
  return it == points_.end() ? nullptr : &it->second;
}

void Map::removePoint(PointId id) {
  const auto obs = observers_.find(id);
  if (obs != observers_.end()) {
    for (KeyframeId kf : obs->second) {
      if (Keyframe* keyframe = this->keyframe(kf)) keyframe->measurements_.erase(id);
    }
    observers_.erase(obs);
  }
  points_.erase(id);
}

void Map::addMeasurement(KeyframeId keyframe_id, const Measurement& measurement) {
  Keyframe* keyframe = this->keyframe(keyframe_id);
  if (!keyframe || !point(measurement.point_id)) return;
  const bool is_new = keyframe->measurements_.count(measurement.point_id) == 0;
  keyframe->measurements_[measurement.point_id] = measurement;
  if (is_new) observers_[measurement.point_id].push_back(keyframe_id);
}

void Map::removeMeasurement(KeyframeId keyframe_id, PointId point_id) {
  Keyframe* keyframe = this->keyframe(keyframe_id);
  if (!keyframe || keyframe->measurements_.erase(point_id) == 0) return;
  const auto obs = observers_.find(point_id);
  if (obs == observers_.end()) return;
  std::vector<KeyframeId>& ids = obs->second;
  ids.erase(std::remove(ids.begin(), ids.end(), keyframe_id), ids.end());
  if (ids.empty()) observers_.erase(obs);
}

void Map::setMeasurementDepth(KeyframeId keyframe_id, PointId point_id, double depth) {
  Keyframe* keyframe = this->keyframe(keyframe_id);
  if (!keyframe) return;
  const auto it = keyframe->measurements_.find(point_id);
  if (it != keyframe->measurements_.end()) it->second.depth = depth;
}

std::vector<KeyframeId> Map::observers(PointId id) const {
  const auto it = observers_.find(id);
  return it == observers_.end() ? std::vector<KeyframeId>{} : it->second;
}

namespace {

std::vector<KeyframeId> nearestOf(const std::map<KeyframeId, std::unique_ptr<Keyframe>>& keyframes,
                                  const SE3& T_w_c, size_t n, double metres_per_radian,
                                  const std::optional<KeyframeId>& part) {
  std::vector<std::pair<double, KeyframeId>> scored;
  const Vec3 axis = T_w_c.rotation() * Vec3::UnitZ();
  for (const auto& [id, kf] : keyframes) {
    if (part && kf->part != *part) continue;
    const double distance = (kf->T_w_c.translation() - T_w_c.translation()).norm();
    const Vec3 kf_axis = kf->T_w_c.rotation() * Vec3::UnitZ();
    const double angle = std::acos(std::clamp(axis.dot(kf_axis), -1.0, 1.0));
    scored.emplace_back(distance + metres_per_radian * angle, id);
  }
  std::sort(scored.begin(), scored.end());
  std::vector<KeyframeId> out;
  for (size_t i = 0; i < scored.size() && i < n; ++i) out.push_back(scored[i].second);
  return out;
}

}  // namespace

std::vector<KeyframeId> Map::nearestKeyframes(const SE3& T_w_c, size_t n, double metres_per_radian) const {
  return nearestOf(keyframes_, T_w_c, n, metres_per_radian, std::nullopt);
}

std::vector<KeyframeId> Map::nearestKeyframesInPart(const SE3& T_w_c, size_t n, KeyframeId part) const {
  return nearestOf(keyframes_, T_w_c, n, 0.5, part);
}

KeyframeId Map::partOfPoint(const MapPoint& point) const {
  const Keyframe* source = keyframe(point.source_keyframe);
  return source ? source->part : -1;
}

std::vector<KeyframeId> Map::keyframesWithin(const SE3& T_w_c, double radius_m) const {
  std::vector<KeyframeId> out;
  for (const auto& [id, kf] : keyframes_) {
    if ((kf->T_w_c.translation() - T_w_c.translation()).norm() <= radius_m) out.push_back(id);
  }
  return out;
}

}  // namespace rgbdslam
