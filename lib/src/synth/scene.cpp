// The public face of the synthetic renderer: options and their spec string, the scene
// (trajectory, timestamps, rendering), TUM export and the FrameSource.
#include "rgbdslam/synth/scene.h"

#include <cassert>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <tuple>

#include "rgbdslam/image/codec.h"
#include "world.h"

namespace rgbdslam {
namespace {

constexpr int64_t kEpochUs = 1700000000LL * 1000000LL;  // time of frame 0 [us]
constexpr double kRoomDefaultSeconds = 20.0;             // 600 frames at 30 Hz
constexpr double kCorridorDefaultSeconds = 110.0;        // 3300 frames at 30 Hz, 110 m
constexpr double kFlightDefaultSeconds = 600.0;          // a ten-minute flight
constexpr double kTwinsDefaultSeconds = 60.0;            // the lookalike rooms' flight, 1800 frames
constexpr double kMaxMinutes = 120.0;                    // limit of the minutes key
constexpr double kMaxRangeLimitM = 13.0;                 // uint16 at 5000 per metre: 13.1 m
constexpr int kMinImageSidePx = 32, kMaxImageSidePx = 4096;  // limits of the size key [px]
constexpr int kCoveredGreyLevel = 8;                     // a covered lens' image [grey level]
constexpr double kOfficeDefaultSeconds = 1240.0 / 30.0;   // 1240 frames at 30 Hz
constexpr double kMaxAutoExposureLagS = 10.0;            // limit of auto_exposure [s]
constexpr double kMaxShotNoise = 10.0;                   // limit of shot_noise [grey levels]
constexpr int kMaxEdgeHolesPx = 10;                      // limit of edge_holes [px]
constexpr const char* kKnownKeys =
    "seed, frames, minutes, rate, depth_fraction, depth, depth_frames, min_range, max_range, "
    "noise_sigma, depth_sigma, quantise, drop, every, cover, distortion, size, intrinsics, "
    "effects, exposure, auto_exposure, vignetting, shot_noise, depth_noise, edge_holes, "
    "ir_shadow, dark_holes, shiny_holes";

PinholeCamera syntheticCamera() {
  PinholeCamera camera;
  camera.name = "synthetic";
  camera.width = 640, camera.height = 480;
  camera.fx = 525.0, camera.fy = 525.0, camera.cx = 319.5, camera.cy = 239.5;
  camera.depth_factor = 5000.0;
  return camera;
}

// The synthetic camera with the options' size, intrinsics and lens distortion.
PinholeCamera distortedCamera(const SyntheticOptions& o) {
  PinholeCamera camera = syntheticCamera();
  camera.width = o.width, camera.height = o.height;
  camera.fx = o.intrinsics[0], camera.fy = o.intrinsics[1];
  camera.cx = o.intrinsics[2], camera.cy = o.intrinsics[3];
  camera.k1 = o.distortion[0], camera.k2 = o.distortion[1], camera.p1 = o.distortion[2];
  camera.p2 = o.distortion[3], camera.k3 = o.distortion[4];
  return camera;
}

std::string trim(const std::string& s) {
  const size_t first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

bool parseDouble(const std::string& text, double* out) {
  if (text.empty()) return false;
  char* end = nullptr;
  *out = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(*out);
}

template <typename Int>
bool parseInteger(const std::string& text, Int* out) {
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, *out);
  return !text.empty() && result.ec == std::errc() && result.ptr == end;
}

std::string formatDouble(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

Status badValue(const std::string& key, const std::string& value, const char* expected) {
  return Error{"bad value '" + value + "' for key '" + key + "' (expected " + expected + ")"};
}

// Parses "A:B:C..." into out[0..max); returns the count, or 0 if anything is not a number
// or there are more than max.
size_t parseColonList(const std::string& value, double* out, size_t max) {
  size_t count = 0, begin = 0;
  while (begin <= value.size()) {
    const size_t end = std::min(value.find(':', begin), value.size());
    if (count == max || !parseDouble(value.substr(begin, end - begin), &out[count])) return 0;
    ++count;
    begin = end + 1;
  }
  return count;
}

// Applies one key=value of the sensor effects; false if 'key' is not an effects key.
bool applyEffectsKey(const std::string& key, const std::string& value, SensorEffects* e,
                     Status* status) {
  double number = 0;
  const bool is_number = parseDouble(value, &number);
  auto flag = [&](bool* target) {
    if (value != "0" && value != "1") *status = badValue(key, value, "0 or 1");
    *target = value == "1";
  };
  if (key == "effects") {
    if (value != "all" && value != "none") *status = badValue(key, value, "all or none");
    *e = value == "all" ? SensorEffects::all() : SensorEffects{};
  } else if (key == "depth_noise") {
    if (value != "kinect" && value != "nguyen") *status = badValue(key, value, "kinect or nguyen");
    e->nguyen_depth = value == "nguyen";
  } else if (key == "ir_shadow") {
    flag(&e->ir_shadow);
  } else if (key == "shiny_holes") {
    flag(&e->shiny_holes);
  } else if (key == "edge_holes") {
    if (!parseInteger(value, &e->edge_holes_px)) *status = badValue(key, value, "pixels, an integer");
  } else if (key == "exposure" || key == "auto_exposure" || key == "vignetting" ||
             key == "shot_noise" || key == "dark_holes") {
    if (!is_number) *status = badValue(key, value, "a number");
    double* target = key == "exposure"        ? &e->exposure_ms
                     : key == "auto_exposure" ? &e->auto_exposure_s
                     : key == "vignetting"    ? &e->vignetting
                     : key == "shot_noise"    ? &e->shot_noise
                                              : &e->dark_holes;
    *target = number;
  } else {
    return false;
  }
  return true;
}

// Applies one key=value of a spec; range checks are left to validateSyntheticOptions.
Status applyKey(const std::string& key, const std::string& value, SyntheticOptions* o) {
  KinectNoiseOptions& n = o->noise;
  double number = 0;
  const bool is_number = parseDouble(value, &number);
  if (key == "seed") {
    if (!parseInteger(value, &o->seed)) return badValue(key, value, "an unsigned integer");
  } else if (key == "frames") {
    if (!parseInteger(value, &o->num_frames)) return badValue(key, value, "an integer");
  } else if (key == "depth_frames") {
    if (!parseInteger(value, &n.depth_frames)) return badValue(key, value, "an integer");
  } else if (key == "depth") {
    if (value == "on") {
      n.depth_enabled = true;
    } else if (value == "off") {
      n.depth_enabled = false;
    } else if (value == "first") {
      n.depth_enabled = true, n.depth_frames = 1;
    } else {
      return badValue(key, value, "on, off or first");
    }
  } else if (key == "drop" || key == "cover") {  // FIRST-LAST or N
    const size_t dash = value.find('-');
    const std::string first = value.substr(0, dash);
    const std::string last = dash == std::string::npos ? first : value.substr(dash + 1);
    int* first_target = key == "drop" ? &o->drop_first : &o->cover_first;
    int* last_target = key == "drop" ? &o->drop_last : &o->cover_last;
    if (!parseInteger(first, first_target) || !parseInteger(last, last_target)) {
      return badValue(key, value, "FIRST-LAST frame indices or one index");
    }
  } else if (key == "distortion") {  // K1:K2:P1:P2[:K3]
    std::array<double, 5> d{};
    const size_t count = parseColonList(value, d.data(), d.size());
    if (count != 4 && count != 5) return badValue(key, value, "K1:K2:P1:P2 or K1:K2:P1:P2:K3");
    o->distortion = d;
  } else if (key == "intrinsics") {  // FX:FY:CX:CY
    if (parseColonList(value, o->intrinsics.data(), 4) != 4) return badValue(key, value, "FX:FY:CX:CY");
  } else if (key == "size") {  // WxH
    const size_t x = value.find('x');
    if (x == std::string::npos || !parseInteger(value.substr(0, x), &o->width) ||
        !parseInteger(value.substr(x + 1), &o->height)) {
      return badValue(key, value, "WIDTHxHEIGHT");
    }
  } else if (key == "every") {
    if (!parseInteger(value, &o->every)) return badValue(key, value, "an integer >= 1");
  } else if (key == "quantise") {
    if (value != "0" && value != "1") return badValue(key, value, "0 or 1");
    n.quantise = value == "1";
  } else if (key == "minutes") {
    if (!is_number) return badValue(key, value, "a number of minutes");
    o->minutes = number;
  } else if (key == "rate" || key == "depth_fraction" || key == "min_range" ||
             key == "max_range" || key == "noise_sigma" || key == "depth_sigma") {
    if (!is_number) return badValue(key, value, "a number");
    double* target = key == "rate"             ? &o->rate_hz
                     : key == "depth_fraction" ? &n.depth_fraction
                     : key == "min_range"      ? &n.min_range_m
                     : key == "max_range"      ? &n.max_range_m
                     : key == "noise_sigma"    ? &n.image_noise_sigma
                                               : &n.sigma_coefficient;
    *target = number;
  } else if (Status status; applyEffectsKey(key, value, &o->effects, &status)) {
    return status;
  } else {
    return Error{"unknown key '" + key + "' (known: " + kKnownKeys + ")"};
  }
  return {};
}

// The effects keys of 'e' that differ from 'base' (the scene's default), for the spec.
std::string formatEffects(const SensorEffects& e, const SensorEffects& base) {
  if (e == base) return "";
  if (e == SensorEffects::all()) return ",effects=all";
  if (e == SensorEffects{}) return ",effects=none";
  std::string spec;
  auto add = [&spec](const char* key, const std::string& value) {
    spec += std::string(",") + key + "=" + value;
  };
  if (e.exposure_ms != base.exposure_ms) add("exposure", formatDouble(e.exposure_ms));
  if (e.auto_exposure_s != base.auto_exposure_s) {
    add("auto_exposure", formatDouble(e.auto_exposure_s));
  }
  if (e.vignetting != base.vignetting) add("vignetting", formatDouble(e.vignetting));
  if (e.shot_noise != base.shot_noise) add("shot_noise", formatDouble(e.shot_noise));
  if (e.nguyen_depth != base.nguyen_depth) add("depth_noise", e.nguyen_depth ? "nguyen" : "kinect");
  if (e.edge_holes_px != base.edge_holes_px) add("edge_holes", std::to_string(e.edge_holes_px));
  if (e.ir_shadow != base.ir_shadow) add("ir_shadow", e.ir_shadow ? "1" : "0");
  if (e.dark_holes != base.dark_holes) add("dark_holes", formatDouble(e.dark_holes));
  if (e.shiny_holes != base.shiny_holes) add("shiny_holes", e.shiny_holes ? "1" : "0");
  return spec;
}

Status validateEffects(const SensorEffects& e, double rate_hz) {
  if (!(e.exposure_ms >= 0 && e.exposure_ms <= 1000.0 / rate_hz)) {
    return Error{"exposure must be in [0, 1000 / rate] ms (at most the frame period), got " +
                 formatDouble(e.exposure_ms)};
  }
  if (!(e.auto_exposure_s >= 0 && e.auto_exposure_s <= kMaxAutoExposureLagS)) {
    return Error{"auto_exposure must be in [0, 10] s, got " + formatDouble(e.auto_exposure_s)};
  }
  if (!(e.vignetting >= 0 && e.vignetting <= 1)) {
    return Error{"vignetting must be in [0, 1], got " + formatDouble(e.vignetting)};
  }
  if (!(e.shot_noise >= 0 && e.shot_noise <= kMaxShotNoise)) {
    return Error{"shot_noise must be in [0, 10] grey levels, got " + formatDouble(e.shot_noise)};
  }
  if (e.edge_holes_px < 0 || e.edge_holes_px > kMaxEdgeHolesPx) {
    return Error{"edge_holes must be in [0, 10] px, got " + std::to_string(e.edge_holes_px)};
  }
  if (!(e.dark_holes >= 0 && e.dark_holes <= 1)) {
    return Error{"dark_holes must be in [0, 1], got " + formatDouble(e.dark_holes)};
  }
  return {};
}

const char* sceneName(SyntheticSceneKind scene) {
  switch (scene) {
    case SyntheticSceneKind::kRoom: return "room";
    case SyntheticSceneKind::kCorridor: return "corridor";
    case SyntheticSceneKind::kFlight: return "flight";
    case SyntheticSceneKind::kOffice: return "office";
    case SyntheticSceneKind::kTwins: return "twins";
  }
  return "room";
}

std::string stampSeconds(int64_t utime) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%lld.%06lld", static_cast<long long>(utime / 1000000),
                static_cast<long long>(utime % 1000000));
  return buffer;
}

class SyntheticSource : public FrameSource {
 public:
  explicit SyntheticSource(const SyntheticOptions& options) : scene_(options) {}
  FrameResult next() override {
    FrameResult result;
    while (next_ < scene_.numFrames() && scene_.options().dropped(next_)) ++next_;
    if (next_ >= scene_.numFrames()) return result;  // kEnd
    result.status = FrameResult::Status::kFrame;
    result.frame = scene_.render(next_++);
    return result;
  }
  double nominalRateHz() const override { return scene_.options().rate_hz; }
  std::optional<size_t> size() const override {
    size_t kept = 0;
    for (size_t i = 0; i < scene_.numFrames(); ++i) kept += scene_.options().dropped(i) ? 0 : 1;
    return kept;
  }
  std::string describe() const override {
    const size_t dropped = scene_.numFrames() - *size();
    return "synthetic:" + formatSyntheticSpec(scene_.options()) + " (" +
           std::to_string(scene_.numFrames()) + " frames" +
           (dropped > 0 ? ", " + std::to_string(dropped) + " dropped" : "") + ")";
  }

 private:
  SyntheticScene scene_;
  size_t next_ = 0;
};

}  // namespace

Expected<SyntheticOptions> parseSyntheticSpec(const std::string& spec) {
  const std::string where = "synthetic spec '" + spec + "': ";
  SyntheticOptions options;
  size_t start = 0;
  for (bool first = true; start <= spec.size(); first = false) {
    size_t comma = spec.find(',', start);
    if (comma == std::string::npos) comma = spec.size();
    const std::string item = trim(spec.substr(start, comma - start));
    start = comma + 1;
    if (first) {
      bool known = false;
      for (const auto kind : {SyntheticSceneKind::kRoom, SyntheticSceneKind::kCorridor,
                              SyntheticSceneKind::kFlight, SyntheticSceneKind::kOffice,
                              SyntheticSceneKind::kTwins}) {
        if (item == sceneName(kind)) options.scene = kind, known = true;
      }
      if (!known) {
        return Error{where + "unknown scene '" + item +
                     "' (expected room, corridor, flight, office or twins)"};
      }
      options.effects = defaultEffects(options.scene);
      continue;
    }
    const size_t equals = item.find('=');
    if (equals == std::string::npos) return Error{where + "expected key=value, got '" + item + "'"};
    const Status applied = applyKey(trim(item.substr(0, equals)), trim(item.substr(equals + 1)),
                                    &options);
    if (!applied) return Error{where + applied.error()};
  }
  const Status valid = validateSyntheticOptions(options);
  if (!valid) return Error{where + valid.error()};
  return options;
}

std::string formatSyntheticSpec(const SyntheticOptions& o) {
  const SyntheticOptions d;
  const KinectNoiseOptions& n = o.noise;
  std::string spec = sceneName(o.scene);
  auto add = [&spec](const char* key, const std::string& value) {
    spec += std::string(",") + key + "=" + value;
  };
  if (o.seed != d.seed) add("seed", std::to_string(o.seed));
  if (o.num_frames != d.num_frames) add("frames", std::to_string(o.num_frames));
  if (o.minutes != d.minutes) add("minutes", formatDouble(o.minutes));
  if (o.rate_hz != d.rate_hz) add("rate", formatDouble(o.rate_hz));
  if (n.depth_fraction != d.noise.depth_fraction) {
    add("depth_fraction", formatDouble(n.depth_fraction));
  }
  if (!n.depth_enabled) add("depth", "off");
  if (n.depth_frames != d.noise.depth_frames) add("depth_frames", std::to_string(n.depth_frames));
  if (n.min_range_m != d.noise.min_range_m) add("min_range", formatDouble(n.min_range_m));
  if (n.max_range_m != d.noise.max_range_m) add("max_range", formatDouble(n.max_range_m));
  if (n.image_noise_sigma != d.noise.image_noise_sigma) {
    add("noise_sigma", formatDouble(n.image_noise_sigma));
  }
  if (n.sigma_coefficient != d.noise.sigma_coefficient) {
    add("depth_sigma", formatDouble(n.sigma_coefficient));
  }
  if (n.quantise != d.noise.quantise) add("quantise", n.quantise ? "1" : "0");
  if (o.drop_first >= 0) {
    add("drop", std::to_string(o.drop_first) + "-" + std::to_string(o.drop_last));
  }
  if (o.every != d.every) add("every", std::to_string(o.every));
  auto colonList = [](const auto& values) {
    std::string list;
    for (const double k : values) list += (list.empty() ? "" : ":") + formatDouble(k);
    return list;
  };
  if (o.distortion != d.distortion) add("distortion", colonList(o.distortion));
  if (o.width != d.width || o.height != d.height) {
    add("size", std::to_string(o.width) + "x" + std::to_string(o.height));
  }
  if (o.intrinsics != d.intrinsics) add("intrinsics", colonList(o.intrinsics));
  if (o.cover_first >= 0) {
    add("cover", std::to_string(o.cover_first) + "-" + std::to_string(o.cover_last));
  }
  return spec + formatEffects(o.effects, defaultEffects(o.scene));
}

Status validateSyntheticOptions(const SyntheticOptions& o) {
  const KinectNoiseOptions& n = o.noise;
  if (o.num_frames < 0) return Error{"frames must be >= 0 (0: the scene's default)"};
  if (!(o.minutes >= 0 && o.minutes <= kMaxMinutes)) {
    return Error{"minutes must be in (0, 120], got " + formatDouble(o.minutes)};
  }
  if (o.minutes > 0 && o.num_frames > 0) {
    return Error{"give frames or minutes, not both (frames " + std::to_string(o.num_frames) +
                 ", minutes " + formatDouble(o.minutes) + ")"};
  }
  if (!(o.rate_hz > 0) || !std::isfinite(o.rate_hz)) return Error{"rate must be > 0 Hz"};
  if (!(n.depth_fraction > 0 && n.depth_fraction <= 1)) {
    return Error{"depth_fraction must be in (0, 1], got " + formatDouble(n.depth_fraction)};
  }
  if (n.depth_frames < -1) return Error{"depth_frames must be >= -1 (-1: all frames)"};
  for (const auto& [name, first, last] : {std::make_tuple("drop", o.drop_first, o.drop_last),
                                           std::make_tuple("cover", o.cover_first, o.cover_last)}) {
    const bool unset = first == -1 && last == -1;
    if (!unset && !(first >= 0 && last >= first)) {
      return Error{std::string(name) + " must be FIRST-LAST with 0 <= FIRST <= LAST, got " +
                   std::to_string(first) + "-" + std::to_string(last)};
    }
  }
  if (o.every < 1) return Error{"every must be >= 1, got " + std::to_string(o.every)};
  for (const double k : o.distortion) {
    if (!std::isfinite(k)) return Error{"distortion coefficients must be finite"};
  }
  if (o.width < kMinImageSidePx || o.height < kMinImageSidePx || o.width > kMaxImageSidePx ||
      o.height > kMaxImageSidePx) {
    return Error{"size must be between 32x32 and 4096x4096, got " + std::to_string(o.width) + "x" +
                 std::to_string(o.height)};
  }
  const auto& [fx, fy, cx, cy] = o.intrinsics;
  if (!(fx > 0 && fy > 0 && std::isfinite(fx) && std::isfinite(fy))) {
    return Error{"intrinsics: focal lengths must be > 0"};
  }
  if (!(cx >= 0 && cx <= o.width - 1 && cy >= 0 && cy <= o.height - 1)) {
    return Error{"intrinsics: the principal point must lie in the image"};
  }
  if (Status lens = synthetic::checkLens(distortedCamera(o)); !lens) {
    return Error{"distortion: " + lens.error()};
  }
  if (!(n.min_range_m > 0)) return Error{"min_range must be > 0 m"};
  if (!(n.max_range_m > n.min_range_m && n.max_range_m <= kMaxRangeLimitM)) {
    return Error{"max_range must be in (min_range, 13] m, got " + formatDouble(n.max_range_m)};
  }
  if (!(n.image_noise_sigma >= 0 && n.image_noise_sigma <= 255)) {
    return Error{"noise_sigma must be in [0, 255] grey levels"};
  }
  if (!(n.sigma_coefficient >= 0 && std::isfinite(n.sigma_coefficient))) {
    return Error{"depth_sigma must be >= 0"};
  }
  if (!(n.disparity_focal_px > 0 && n.baseline_m > 0 && n.disparity_step_px > 0)) {
    return Error{"disparity quantisation parameters must be > 0"};
  }
  return validateEffects(o.effects, o.rate_hz);
}

SensorEffects SensorEffects::all() {
  SensorEffects e;
  e.exposure_ms = 20.0;
  e.auto_exposure_s = 0.5;
  e.vignetting = 0.5;
  e.shot_noise = 0.05;
  e.nguyen_depth = true;
  e.edge_holes_px = 1;
  e.ir_shadow = true;
  e.dark_holes = 0.01;
  e.shiny_holes = true;
  return e;
}

bool SensorEffects::operator==(const SensorEffects& o) const {
  return std::tie(exposure_ms, auto_exposure_s, vignetting, shot_noise, nguyen_depth,
                  edge_holes_px, ir_shadow, dark_holes, shiny_holes) ==
         std::tie(o.exposure_ms, o.auto_exposure_s, o.vignetting, o.shot_noise, o.nguyen_depth,
                  o.edge_holes_px, o.ir_shadow, o.dark_holes, o.shiny_holes);
}

SensorEffects defaultEffects(SyntheticSceneKind scene) {
  return scene == SyntheticSceneKind::kOffice ? SensorEffects::all() : SensorEffects{};
}

SyntheticScene::SyntheticScene(const SyntheticOptions& options)
    : options_(options), camera_(distortedCamera(options)) {
  assert(validateSyntheticOptions(options).ok());
  const double default_s = options.scene == SyntheticSceneKind::kRoom       ? kRoomDefaultSeconds
                           : options.scene == SyntheticSceneKind::kCorridor ? kCorridorDefaultSeconds
                           : options.scene == SyntheticSceneKind::kFlight   ? kFlightDefaultSeconds
                           : options.scene == SyntheticSceneKind::kTwins    ? kTwinsDefaultSeconds
                                                                            : kOfficeDefaultSeconds;
  const double seconds = options.minutes > 0 ? 60.0 * options.minutes : default_s;
  num_frames_ = options.num_frames > 0
                    ? static_cast<size_t>(options.num_frames)
                    : static_cast<size_t>(std::lround(seconds * options.rate_hz));
  num_frames_ = std::max<size_t>(num_frames_, 1);
  const double duration_s = (num_frames_ - 1) / options.rate_hz;
  switch (options.scene) {
    case SyntheticSceneKind::kRoom:
      world_ = std::make_shared<const synthetic::World>(synthetic::buildRoom(options.seed, duration_s));
      break;
    case SyntheticSceneKind::kCorridor:
      world_ = std::make_shared<const synthetic::World>(
          synthetic::buildCorridor(options.seed, duration_s));
      break;
    case SyntheticSceneKind::kFlight:
      world_ = std::make_shared<const synthetic::World>(
          synthetic::buildFlight(options.seed, duration_s));
      break;
    case SyntheticSceneKind::kOffice:
      world_ = std::make_shared<const synthetic::World>(
          synthetic::buildOffice(options.seed, duration_s));
      break;
    case SyntheticSceneKind::kTwins:
      world_ = std::make_shared<const synthetic::World>(
          synthetic::buildTwins(options.seed, duration_s));
      break;
  }
  if (camera_.hasDistortion()) {
    lens_ = std::make_shared<const synthetic::LensResampling>(synthetic::makeLensResampling(camera_));
  }
}

SyntheticScene::~SyntheticScene() = default;

int64_t SyntheticScene::frameUtime(size_t i) const {
  return kEpochUs + std::llround(static_cast<double>(i) * 1e6 / options_.rate_hz);
}

SE3 SyntheticScene::groundTruthPose(size_t i) const {
  return world_->trajectory.pose(static_cast<double>(i) / options_.rate_hz);
}

Trajectory SyntheticScene::groundTruth() const {
  Trajectory trajectory;
  trajectory.reserve(num_frames_);
  for (size_t i = 0; i < num_frames_; ++i) {
    trajectory.push_back(TimedPose{frameUtime(i) * 1e-6, groundTruthPose(i)});
  }
  return trajectory;
}

RgbdFrame SyntheticScene::render(size_t i) const {
  RgbdFrame frame = renderPose(groundTruthPose(i), i);
  if (options_.covered(i)) {  // a hand over the lens: dark, noisy, no depth
    frame.colour.setTo(cv::Scalar::all(kCoveredGreyLevel));
    addImageNoise(i, &frame.colour);
    frame.depth.setTo(0);
  }
  return frame;
}

double SyntheticScene::meteredGain(size_t i) const {
  synthetic::CleanFrame small;
  synthetic::castRays(*world_, synthetic::meteringCamera(camera_), groundTruthPose(i), &small);
  return synthetic::meteredGainOf(small.colour);
}

double SyntheticScene::exposureGain(size_t i) const {
  if (options_.effects.auto_exposure_s <= 0) return 1.0;
  return synthetic::laggedGain(i, options_.rate_hz, options_.effects.auto_exposure_s,
                               [this](size_t k) { return meteredGain(k); });
}

void SyntheticScene::addImageNoise(size_t i, cv::Mat* colour) const {
  if (options_.effects.shot_noise > 0) {
    synthetic::addSignalDependentNoise(options_.noise, options_.effects, options_.seed, i, colour);
  } else {
    synthetic::addImageNoise(options_.noise, options_.seed, i, colour);
  }
}

// Motion blur: the colour is the mean of the sub-frames along the camera's motion over the
// exposure, the trajectory's motion around frame i carried over to the pose T_w_c.
void SyntheticScene::blurColour(const PinholeCamera& cast_camera, const SE3& T_w_c, size_t i,
                                cv::Mat* colour) const {
  const double t = static_cast<double>(i) / options_.rate_hz;
  const SE3 T_c_w_frame = world_->trajectory.pose(t).inverse();
  cv::Mat sum;
  colour->convertTo(sum, CV_32FC3);  // the middle sub-frame (offset 0) is this pose
  for (const double offset : synthetic::blurOffsets(options_.effects.exposure_ms)) {
    if (offset == 0.0) continue;
    synthetic::CleanFrame sub;
    const SE3 T_w_sub = T_w_c * (T_c_w_frame * world_->trajectory.pose(t + offset));
    synthetic::castRays(*world_, cast_camera, T_w_sub, &sub);
    cv::Mat sub_float;
    sub.colour.convertTo(sub_float, CV_32FC3);
    sum += sub_float;
  }
  sum.convertTo(*colour, CV_8UC3, 1.0 / synthetic::kBlurSubFrames);
}

cv::Mat SyntheticScene::trueDepth(const SE3& T_w_c) const {
  synthetic::CleanFrame clean;
  synthetic::castRays(*world_, lens_ ? lens_->canvas : camera_, T_w_c, &clean);
  if (lens_) synthetic::resampleThroughLens(*lens_, &clean);
  cv::Mat z = clean.hit_z.clone();  // 0 where nothing is hit
  z.setTo(std::numeric_limits<float>::quiet_NaN(), clean.hit_z <= 0.0f);
  return z;
}

RgbdFrame SyntheticScene::renderPose(const SE3& T_w_c, size_t i, cv::Mat* surfaces) const {
  const SensorEffects& effects = options_.effects;
  const PinholeCamera& cast_camera = lens_ ? lens_->canvas : camera_;
  synthetic::CleanFrame clean;
  synthetic::castRays(*world_, cast_camera, T_w_c, &clean);
  if (effects.exposure_ms > 0) blurColour(cast_camera, T_w_c, i, &clean.colour);
  if (effects.anyDepth()) {
    synthetic::removeGeometricDepth(effects, options_.noise, cast_camera.fx, &clean);
  }
  if (lens_) synthetic::resampleThroughLens(*lens_, &clean);
  RgbdFrame frame;
  frame.utime = frameUtime(i);
  frame.seq = static_cast<int64_t>(i);
  // The effects' material losses need the clean colour: the noisy one is a copy then.
  frame.colour = effects.any() ? clean.colour.clone() : clean.colour;
  synthetic::applyExposureAndVignetting(effects, camera_, exposureGain(i), &frame.colour);
  addImageNoise(i, &frame.colour);
  frame.depth = effects.anyDepth()
                    ? synthetic::kinectDepthWithEffects(options_.noise, effects, options_.seed, i,
                                                        clean, camera_.depth_factor)
                    : synthetic::kinectDepth(options_.noise, options_.seed, i, clean.depth_m,
                                             camera_.depth_factor);
  frame.depth_scale = camera_.depth_factor;
  frame.camera_name = camera_.name;
  if (surfaces) *surfaces = clean.surfaces;
  return frame;
}

Status SyntheticScene::writeTumDirectory(const std::string& dir) const {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "rgb", ec);
  if (!ec) fs::create_directories(fs::path(dir) / "depth", ec);
  if (ec) return Error{dir + ": cannot create directory (" + ec.message() + ")"};
  std::ofstream rgb_list(dir + "/rgb.txt"), depth_list(dir + "/depth.txt");
  if (!rgb_list || !depth_list) return Error{dir + ": cannot write rgb.txt / depth.txt"};
  const std::string spec = formatSyntheticSpec(options_);
  rgb_list << "# color images\n# file: 'synthetic:" << spec << "'\n# timestamp filename\n";
  depth_list << "# depth maps\n# file: 'synthetic:" << spec << "'\n# timestamp filename\n";
  for (size_t i = 0; i < num_frames_; ++i) {
    const RgbdFrame frame = render(i);
    const std::string stamp = stampSeconds(frame.utime);
    const std::string rgb_name = "rgb/" + stamp + ".png", depth_name = "depth/" + stamp + ".png";
    if (Status s = writePngFile(dir + "/" + rgb_name, frame.colour); !s) return s;
    if (Status s = writePngFile(dir + "/" + depth_name, frame.depth); !s) return s;
    rgb_list << stamp << ' ' << rgb_name << '\n';
    depth_list << stamp << ' ' << depth_name << '\n';
  }
  if (!rgb_list || !depth_list) return Error{dir + ": write failed for rgb.txt / depth.txt"};
  return writeTumTrajectory(dir + "/groundtruth.txt", groundTruth());
}

std::unique_ptr<FrameSource> makeSyntheticSource(const SyntheticOptions& options) {
  return std::make_unique<SyntheticSource>(options);
}

}  // namespace rgbdslam
