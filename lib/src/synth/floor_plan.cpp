// Building blocks of the room-and-corridor scenes (floor_plan.h).
#include "floor_plan.h"

#include <algorithm>
#include <cmath>

namespace rgbdslam::synthetic {
namespace {

using S = SyntheticSurface;

constexpr double kWall = kWallThickness;
constexpr double kBankFactor = 0.5;  // camera roll = this * the coordinated-turn bank
constexpr double kGravity = 9.81;    // [m/s^2]

double wrapToPi(double a) { return std::remainder(a, 2 * M_PI); }

// The wall slab of 'side' between a and b along it, from z0 to z1, textured on 'faces'
// besides its inner face.
void addWallPiece(WorldBuilder& b, const Space& s, int side, double a, double b_, double z0,
                  double z1, const TextureStyle& style, unsigned faces) {
  switch (side) {
    case kWest:
      b.add(Vec3(s.x0 - kWall, a, z0), Vec3(s.x0, b_, z1), S::kDiffuse, style, kFaceXHi | faces);
      break;
    case kEast:
      b.add(Vec3(s.x1, a, z0), Vec3(s.x1 + kWall, b_, z1), S::kDiffuse, style, kFaceXLo | faces);
      break;
    case kSouth:
      b.add(Vec3(a, s.y0 - kWall, z0), Vec3(b_, s.y0, z1), S::kDiffuse, style, kFaceYHi | faces);
      break;
    default:
      b.add(Vec3(a, s.y1, z0), Vec3(b_, s.y1 + kWall, z1), S::kDiffuse, style, kFaceYLo | faces);
  }
}

}  // namespace

Space makeSpace(double x0, double y0, double x1, double y1, double h, const TextureStyle& walls) {
  Space s{x0, y0, x1, y1, h, {walls, walls, walls, walls}};
  return s;
}

void addSpace(WorldBuilder& b, const Space& s) {
  b.add(Vec3(s.x0, s.y0, -kWall), Vec3(s.x1, s.y1, 0), S::kDiffuse, s.floor, kFaceZHi);
  b.add(Vec3(s.x0, s.y0, s.h), Vec3(s.x1, s.y1, s.h + kWall), S::kDiffuse, s.ceiling, kFaceZLo);
  for (int side = 0; side < 4; ++side) {
    if (s.open[side]) continue;
    const bool along_y = side == kWest || side == kEast;
    // The ends reach over the neighbouring walls' thickness where those are walls.
    const int lo_side = along_y ? kSouth : kWest, hi_side = along_y ? kNorth : kEast;
    const double lo = (along_y ? s.y0 : s.x0) - (s.open[lo_side] ? 0 : kWall);
    const double hi = (along_y ? s.y1 : s.x1) + (s.open[hi_side] ? 0 : kWall);
    const unsigned jambs = along_y ? (kFaceYLo | kFaceYHi) : (kFaceXLo | kFaceXHi);
    std::vector<Opening> doors = s.openings[side];
    std::sort(doors.begin(), doors.end(), [](const Opening& p, const Opening& q) { return p.a < q.a; });
    double from = lo;
    for (const Opening& door : doors) {
      if (door.a > from) addWallPiece(b, s, side, from, door.a, 0, s.h, s.walls[side], jambs);
      if (door.top < s.h) {
        addWallPiece(b, s, side, door.a, door.b, door.top, s.h, s.walls[side], kFaceZLo);
      }
      from = door.b;
    }
    if (hi > from) addWallPiece(b, s, side, from, hi, 0, s.h, s.walls[side], jambs);
  }
}

void addOnWall(WorldBuilder& b, const Space& s, int side, double a, double b_, double depth,
               double z0, double z1, S surface, const TextureStyle& style, bool front_only) {
  const unsigned front[4] = {kFaceXHi, kFaceXLo, kFaceYHi, kFaceYLo};
  const unsigned faces = front_only ? front[side] : kAllFaces;
  switch (side) {
    case kWest: b.add(Vec3(s.x0, a, z0), Vec3(s.x0 + depth, b_, z1), surface, style, faces); break;
    case kEast: b.add(Vec3(s.x1 - depth, a, z0), Vec3(s.x1, b_, z1), surface, style, faces); break;
    case kSouth: b.add(Vec3(a, s.y0, z0), Vec3(b_, s.y0 + depth, z1), surface, style, faces); break;
    default: b.add(Vec3(a, s.y1 - depth, z0), Vec3(b_, s.y1, z1), surface, style, faces);
  }
}

void addLabFurniture(WorldBuilder& b, const Space& a) {
  const TextureStyle rich = richStyle();
  const double x = a.x0, y = a.y0;
  addOnWall(b, a, kWest, y + 0.8, y + 2.4, 0.6, 0, 1.9, S::kDiffuse, rich, false);    // cupboard
  addOnWall(b, a, kSouth, x + 5.5, x + 7.5, 0.8, 0, 0.75, S::kDiffuse, rich, false);  // desk
  addOnWall(b, a, kNorth, x + 6.0, x + 7.6, 0.7, 0, 1.1, S::kDiffuse, rich, false);   // chest
  addOnWall(b, a, kWest, y + 4.8, y + 6.6, 0.5, 0, 0.5, S::kDiffuse, rich, false);    // low box
  addOnWall(b, a, kNorth, x + 0.6, x + 2.2, 0.02, 0.9, 1.9, S::kDiffuse, rich, true);  // board
}

void addCorridorFixtures(WorldBuilder& b, const Space& s, int side) {
  const bool along_y = side == kWest || side == kEast;
  const double lo = along_y ? s.y0 : s.x0, hi = along_y ? s.y1 : s.x1;
  auto clear = [&](double a, double c) {
    for (const Opening& o : s.openings[side]) {
      if (a < o.b + 0.3 && c > o.a - 0.3) return false;
    }
    return true;
  };
  std::mt19937_64& rng = b.rng();
  for (double x = lo + uniform(rng, 0.8, 3.0); x < hi - 1.5; x += uniform(rng, 1.5, 3.5)) {
    const double kind = uniform01(rng);
    double len = 0.9;
    if (kind < 0.25) {  // glass cabinet
      len = uniform(rng, 1.0, 1.6);
      if (clear(x, x + len)) addOnWall(b, s, side, x, x + len, 0.25, 0, 1.9, S::kGlass, glassStyle(), false);
    } else if (kind < 0.4) {  // black door
      if (clear(x, x + len)) addOnWall(b, s, side, x, x + len, 0.03, 0, 2.05, S::kBlack, blackStyle(), true);
    } else if (kind < 0.55) {  // wooden door
      if (clear(x, x + len)) addOnWall(b, s, side, x, x + len, 0.03, 0, 2.05, S::kDiffuse, floorStyle(), true);
    } else {  // poster or notice board
      len = uniform(rng, 0.4, 1.2);
      const double z0 = uniform(rng, 0.9, 1.3), z1 = z0 + uniform(rng, 0.4, 0.9);
      if (clear(x, x + len)) addOnWall(b, s, side, x, x + len, 0.01, z0, z1, S::kDiffuse, richStyle(), true);
    }
    x += len;
  }
}

void addCorridorLamps(WorldBuilder& b, const Space& s) {
  const bool along_x = s.x1 - s.x0 > s.y1 - s.y0;
  const double lo = along_x ? s.x0 : s.y0, hi = along_x ? s.x1 : s.y1;
  const double cx = 0.5 * (s.x0 + s.x1), cy = 0.5 * (s.y0 + s.y1);
  for (double t = lo + 1.5; t < hi - 1.0; t += 4.0) {
    const Vec3 lo3 = along_x ? Vec3(t, cy - 0.3, s.h - 0.03) : Vec3(cx - 0.3, t, s.h - 0.03);
    const Vec3 hi3 = along_x ? Vec3(t + 1.2, cy + 0.3, s.h) : Vec3(cx + 0.3, t + 1.2, s.h);
    b.add(lo3, hi3, S::kDiffuse, lampStyle(), kFaceZLo);
  }
}

void FlightScript::spin(double angle, double rate) {
  PathState to = last();
  to.yaw += angle;
  move(to, std::abs(angle) / rate);
}

void FlightScript::flyTo(double x, double y, double z, double speed) {
  const PathState from = last();
  const double dx = x - from.x, dy = y - from.y;
  const double distance = std::sqrt(dx * dx + dy * dy + (z - from.z) * (z - from.z));
  if (distance < 1e-6) return;
  double yaw = from.yaw;
  if (std::hypot(dx, dy) > 0.05) {
    const double turn = wrapToPi(std::atan2(dy, dx) - from.yaw);
    if (std::abs(turn) > M_PI / 6) spin(turn, kTurnRate);
    yaw = from.yaw + turn;
  }
  move(PathState{x, y, z, yaw, kPitch, 0}, distance / speed);
}

void FlightScript::move(PathState to, double seconds) {
  const PathState from = last();
  const int steps = std::max(1, static_cast<int>(std::lround(seconds / kScriptDt)));
  for (int k = 1; k <= steps; ++k) {
    const double w = static_cast<double>(k) / steps;
    auto mix = [w](double u, double v) { return u + w * (v - u); };
    samples_.push_back(PathState{mix(from.x, to.x), mix(from.y, to.y), mix(from.z, to.z),
                                 mix(from.yaw, to.yaw), kPitch, 0});
  }
}

SampledPath FlightScript::smoothed() const {
  const int radius = static_cast<int>(std::ceil(3 * kSmoothingS / kScriptDt));
  std::vector<double> kernel(2 * radius + 1);
  double sum = 0;
  for (int k = -radius; k <= radius; ++k) {
    const double s = k * kScriptDt / kSmoothingS;
    sum += kernel[k + radius] = std::exp(-0.5 * s * s);
  }
  const int n = static_cast<int>(samples_.size());
  SampledPath path;
  path.dt = kScriptDt;
  path.samples.resize(n);
  for (int i = 0; i < n; ++i) {
    PathState& out = path.samples[i];
    out = PathState{0, 0, 0, 0, kPitch, 0};
    for (int k = -radius; k <= radius; ++k) {
      const PathState& in = samples_[std::clamp(i + k, 0, n - 1)];
      const double w = kernel[k + radius] / sum;
      out.x += w * in.x, out.y += w * in.y, out.z += w * in.z, out.yaw += w * in.yaw;
    }
  }
  for (int i = 0; i < n; ++i) {  // bank into turns: tan(bank) = v * yaw rate / g
    const PathState& p = path.samples[std::max(0, i - 1)];
    const PathState& q = path.samples[std::min(n - 1, i + 1)];
    const double dt = (std::min(n - 1, i + 1) - std::max(0, i - 1)) * kScriptDt;
    if (dt <= 0) continue;
    const double v = std::hypot(q.x - p.x, q.y - p.y) / dt, rate = (q.yaw - p.yaw) / dt;
    path.samples[i].roll = -kBankFactor * std::atan(v * rate / kGravity);
  }
  return path;
}

}  // namespace rgbdslam::synthetic
