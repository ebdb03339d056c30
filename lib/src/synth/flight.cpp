// The flight (synth:flight): three rooms joined in a loop by corridors and doors, and a
// scripted micro-aerial-vehicle flight through them for as long as asked.
//
// Floor plan (x east, y north, z up from the floor at 0; metres):
//   A   "lab"    [0, 8] x [0, 7],      3.0 m high: textured walls, furniture; doors east
//                                      (to C1) and north (to C3b)
//   C1           [8, 20] x [2.5, 4.5], 2.6 m: A to B, the fast stretch (2 m/s)
//   B   "hall"   [20, 32] x [-1, 11],  4.0 m: walls 6-12 m away (beyond the depth range),
//                                      pillars, glass cabinets, a dark corner
//   C2           [21, 23] x [11, 16],  2.6 m: B to C
//   C   "store"  [12, 24] x [16, 23],  3.0 m: shelves, a glass wall, a plain east wall; a
//                                      figure of eight is flown here
//   C3a          [3, 12] x [18, 20],   2.6 m: C westwards, then
//   C3b          [3, 5] x [7, 18],     2.6 m: southwards into A through its north door
// The corridors have weakly textured walls with posters, doors and glass cabinets.
// Decision: A, where the flight starts and spins, has no plain wall: a 90 deg/s spin that
// meets a plain wall filling the view loses a tracker without depth-aided tracking before
// any map exists to relocalise into; the plain walls are in C (seen on the figure of eight)
// and C3a's dark dead end.
//
// The flight: tours of the loop, A -> B -> C -> A, then the other way round (so every room
// is entered again through another door), and so on until the duration is flown. Each tour
// has its own height offset and speed factor from the seed (C1 is always flown at 2 m/s);
// the first starts with a hover and a slow move-off (map initialisation), and each spins
// once in A (90 deg/s) and half a turn high in B. The script is sampled at 100 Hz and smoothed (Gaussian, 0.25 s), so
// starts, stops and turns are smooth; the camera rolls into turns like a banking vehicle.
// The script does not depend on the duration: a short flight is the start of a long one.
#include <algorithm>
#include <cmath>

#include "world.h"

namespace rgbdslam::synthetic {
namespace {

using S = SyntheticSurface;

constexpr double kTexelM = 0.01;
constexpr double kWall = kWallThickness;
constexpr double kCorridorH = 2.6, kRoomH = 3.0, kHallH = 4.0;  // heights [m]

// ---- styles of the flight's own surfaces
TextureStyle plainWallStyle() {  // painted wall: almost nothing to track
  TextureStyle s;
  s.base_grey = 200, s.base_spread = 6, s.tint_spread = 0.04;
  s.octaves = {{1.5, 2}, {0.05, 1}};
  return s;
}
TextureStyle darkStyle() {  // an unlit corner: textured, but 5-10x darker (depth works)
  TextureStyle s = richStyle();
  s.base_grey = 28, s.base_spread = 6;
  for (NoiseOctave& o : s.octaves) o.amplitude *= 0.2;
  for (ShapeLayer& l : s.shapes) l.contrast *= 0.2;
  return s;
}

// ---- floor plan
enum Side { kWest = 0, kEast = 1, kSouth = 2, kNorth = 3 };

struct Opening {
  double a, b;  // along the side [m]
  double top;   // up to this height [m]; a lintel fills the wall above it
};

// A room or a corridor: floor, ceiling and four walls outside [x0, x1] x [y0, y1] x [0, h].
struct Space {
  double x0, y0, x1, y1, h;
  std::array<TextureStyle, 4> walls;                // per side
  std::array<std::vector<Opening>, 4> openings{};   // doors per side
  std::array<bool, 4> open{};                       // the whole side is open (corridor ends)
  TextureStyle floor = floorStyle(), ceiling = ceilingStyle();
};

Space makeSpace(double x0, double y0, double x1, double y1, double h, const TextureStyle& walls) {
  Space s{x0, y0, x1, y1, h, {walls, walls, walls, walls}};
  return s;
}

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

// A box against the inside of wall 'side' of 's', from a to b along the wall, 'depth' into
// the space, from z0 to z1. 'front_only': only the face towards the space is textured.
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

// Posters, doors and glass cabinets along a corridor wall, clear of its openings.
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

void buildFloorPlan(WorldBuilder& b) {
  const TextureStyle rich = richStyle(), weak = weakWallStyle();
  const Opening corridor_door_x{2.5, 4.5, kCorridorH};  // C1's end in A and B

  Space a = makeSpace(0, 0, 8, 7, kRoomH, rich);  // the lab
  a.openings[kEast] = {corridor_door_x};
  a.openings[kNorth] = {{3, 5, kCorridorH}};
  addSpace(b, a);
  addOnWall(b, a, kWest, 0.8, 2.4, 0.6, 0, 1.9, S::kDiffuse, rich, false);    // cupboard
  addOnWall(b, a, kSouth, 5.5, 7.5, 0.8, 0, 0.75, S::kDiffuse, rich, false);  // desk
  addOnWall(b, a, kNorth, 6.0, 7.6, 0.7, 0, 1.1, S::kDiffuse, rich, false);   // chest
  addOnWall(b, a, kWest, 4.8, 6.6, 0.5, 0, 0.5, S::kDiffuse, rich, false);    // low box
  addOnWall(b, a, kNorth, 0.6, 2.2, 0.02, 0.9, 1.9, S::kDiffuse, rich, true);  // board

  Space c1 = makeSpace(8, 2.5, 20, 4.5, kCorridorH, weak);
  c1.open[kWest] = c1.open[kEast] = true;
  addSpace(b, c1);

  Space hall = makeSpace(20, -1, 32, 11, kHallH, rich);
  hall.openings[kWest] = {corridor_door_x};
  hall.openings[kNorth] = {{21, 23, kCorridorH}};
  addSpace(b, hall);
  for (const auto& [px, py] : {std::pair{24.2, 0.6}, {24.2, 8.8}, {28.8, 0.6}, {28.8, 8.8}}) {
    b.add(Vec3(px, py, 0), Vec3(px + 0.6, py + 0.6, kHallH), S::kDiffuse, rich);  // pillars
  }
  addOnWall(b, hall, kSouth, 21.0, 23.5, 0.5, 0, 2.0, S::kGlass, glassStyle(), false);
  addOnWall(b, hall, kSouth, 25.5, 28.0, 0.5, 0, 2.0, S::kGlass, glassStyle(), false);
  addOnWall(b, hall, kEast, 1.0, 4.0, 0.6, 0, 1.2, S::kDiffuse, rich, false);  // crates
  // The dark corner (north-east): unlit panels on both walls and a dark cabinet.
  addOnWall(b, hall, kNorth, 28.0, 32.0, 0.02, 0, kHallH, S::kDiffuse, darkStyle(), true);
  addOnWall(b, hall, kEast, 7.0, 11.0, 0.02, 0, kHallH, S::kDiffuse, darkStyle(), true);
  addOnWall(b, hall, kEast, 9.0, 10.8, 0.8, 0, 1.6, S::kDiffuse, darkStyle(), false);

  Space c2 = makeSpace(21, 11, 23, 16, kCorridorH, weak);
  c2.open[kSouth] = c2.open[kNorth] = true;
  addSpace(b, c2);

  Space store = makeSpace(12, 16, 24, 23, kRoomH, rich);
  store.walls[kEast] = plainWallStyle();
  store.openings[kSouth] = {{21, 23, kCorridorH}};
  store.openings[kWest] = {{18, 20, kCorridorH}};
  addSpace(b, store);
  for (double x = 12.5; x < 20.5; x += 2.5) {  // shelves along the south wall
    addOnWall(b, store, kSouth, x, x + 2.0, 0.5, 0, 2.0, S::kDiffuse, rich, false);
  }
  // The glass wall: most of the north wall behind glass (colour, no depth).
  addOnWall(b, store, kNorth, 13.0, 20.0, 0.1, 0, 2.5, S::kGlass, glassStyle(), true);
  addOnWall(b, store, kNorth, 21.0, 23.5, 0.6, 0, 1.5, S::kDiffuse, rich, false);  // counter

  Space c3a = makeSpace(3, 18, 12, 20, kCorridorH, weak);
  c3a.open[kEast] = true;
  c3a.openings[kSouth] = {{3, 5, kCorridorH}};
  c3a.walls[kWest] = darkStyle();  // the dead end
  addSpace(b, c3a);
  Space c3b = makeSpace(3, 7, 5, 18, kCorridorH, weak);
  c3b.open[kSouth] = c3b.open[kNorth] = true;
  addSpace(b, c3b);

  for (const Space* s : {&c1, &c2, &c3a, &c3b}) {
    const bool along_x = s->x1 - s->x0 > s->y1 - s->y0;
    for (const int side : along_x ? std::array{kSouth, kNorth} : std::array{kWest, kEast}) {
      addCorridorFixtures(b, *s, side);
    }
    addCorridorLamps(b, *s);
  }
}

// ---- the flight script
constexpr double kScriptDt = 0.01;        // sampling of the script [s]
constexpr double kSmoothingS = 0.25;      // Gaussian smoothing of the script [s]
constexpr double kTurnRate = M_PI / 3;    // turns at corners: 60 deg/s
constexpr double kSpinRate = M_PI / 2;    // look-around spins: 90 deg/s
constexpr double kPitch = -0.12;          // looking slightly down [rad]
constexpr double kBankFactor = 0.5;       // camera roll = this * the coordinated-turn bank
constexpr double kGravity = 9.81;         // [m/s^2]
constexpr double kTopSpeed = 2.0;         // in C1 [m/s]

double wrapToPi(double a) { return std::remainder(a, 2 * M_PI); }

class FlightScript {
 public:
  explicit FlightScript(const PathState& start) { samples_.push_back(start); }
  double seconds() const { return (samples_.size() - 1) * kScriptDt; }
  void hover(double seconds) { move(last(), seconds); }
  // Turns on the spot by 'angle' (signed; may exceed a full turn) at 'rate'.
  void spin(double angle, double rate) {
    PathState to = last();
    to.yaw += angle;
    move(to, std::abs(angle) / rate);
  }
  // Flies straight to (x, y, z) at 'speed', looking along the way: turns on the spot first
  // where the heading is more than 30 deg off, else turns while flying.
  void flyTo(double x, double y, double z, double speed) {
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
  // Smoothed, with the roll of a banking vehicle.
  SampledPath smoothed() const;

 private:
  const PathState& last() const { return samples_.back(); }
  void move(PathState to, double seconds) {  // by value: to may be last()
    const PathState from = last();
    const int steps = std::max(1, static_cast<int>(std::lround(seconds / kScriptDt)));
    for (int k = 1; k <= steps; ++k) {
      const double w = static_cast<double>(k) / steps;
      auto mix = [w](double u, double v) { return u + w * (v - u); };
      samples_.push_back(PathState{mix(from.x, to.x), mix(from.y, to.y), mix(from.z, to.z),
                                   mix(from.yaw, to.yaw), kPitch, 0});
    }
  }
  std::vector<PathState> samples_;
};

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

// One tour of the loop from A: forward A -> B -> C -> A, else the other way round.
// 'dz' shifts the cruise height, 'pace' scales the speeds.
void flyTour(FlightScript& f, bool forward, double dz, double pace) {
  const double h = 1.4 + dz;
  auto eight = [&](bool ahead) {  // a figure of eight in C: x = 18 + 4 sin s, y = 19.5 + 1.5 sin 2s
    constexpr int kSteps = 48;
    for (int k = 1; k <= kSteps; ++k) {
      const double s = (ahead ? 1 : -1) * 2 * M_PI * k / kSteps;
      f.flyTo(18 + 4 * std::sin(s), 19.5 + 1.5 * std::sin(2 * s), h + 0.3 * std::sin(s), 1.0 * pace);
    }
  };
  if (forward) {
    f.spin(2 * M_PI, kSpinRate);  // look around A (the plain wall among the rest)
    f.flyTo(6.5, 3.5, h + 0.1, 0.8 * pace);
    f.flyTo(19.0, 3.5, h, kTopSpeed);  // C1 at full speed
    f.flyTo(23.0, 3.5, h + 0.2, 1.0 * pace);
    f.flyTo(26.0, 5.0, 2.6 + dz, 0.8 * pace);  // climb into the hall's open space
    f.spin(M_PI, kSpinRate / 2);
    f.flyTo(26.0, 5.0, h, 0.6 * pace);
    f.flyTo(22.0, 9.5, h, 1.0 * pace);
    f.flyTo(22.0, 15.0, h, 1.2 * pace);  // C2
    f.flyTo(22.0, 17.2, h, 0.8 * pace);
    f.flyTo(20.0, 18.0, h, 0.8 * pace);
    f.flyTo(18.0, 19.5, h, 0.8 * pace);
    eight(true);
    f.flyTo(14.5, 19.0, h, 0.8 * pace);
    f.flyTo(4.0, 19.0, h, 1.5 * pace);  // C3a
    f.flyTo(4.0, 8.0, h, 1.5 * pace);   // C3b
    f.flyTo(4.0, 5.0, h - 0.1, 0.8 * pace);  // into A again, through its other door
    f.flyTo(4.0, 3.5, h - 0.2, 0.5 * pace);
    f.hover(2.0);
  } else {
    f.flyTo(4.0, 5.5, h - 0.1, 0.6 * pace);
    f.flyTo(4.0, 19.0, h, 1.5 * pace);  // C3b
    f.flyTo(14.5, 19.0, h, 1.5 * pace);  // C3a into C
    f.flyTo(18.0, 19.5, h, 0.8 * pace);
    eight(false);
    f.flyTo(20.0, 18.0, h, 0.8 * pace);
    f.flyTo(22.0, 17.0, h, 0.8 * pace);
    f.flyTo(22.0, 9.5, h, 1.2 * pace);  // C2 into B
    f.flyTo(26.0, 5.0, 2.2 + dz, 0.8 * pace);
    f.spin(-M_PI, kSpinRate / 2);
    f.flyTo(23.0, 3.5, h + 0.1, 0.8 * pace);
    f.flyTo(19.0, 3.5, h, 1.0 * pace);
    f.flyTo(8.5, 3.5, h, kTopSpeed);  // C1 at full speed
    f.flyTo(4.0, 3.5, h - 0.1, 0.8 * pace);
    f.hover(3.0);
  }
}

}  // namespace

World buildFlight(uint64_t seed, double duration_s) {
  WorldBuilder b(seed, kTexelM);
  buildFloorPlan(b);
  std::mt19937_64 rng = makeEngine(seed, /*stream=*/2);
  // Take-off facing A's textured west wall (2.6 m away), then a slow move towards it.
  FlightScript script(PathState{2.6, 3.5, 1.3, M_PI, kPitch, 0});
  script.hover(2.0);
  script.flyTo(1.8, 3.3, 1.35, 0.3);
  for (int tour = 0; script.seconds() < duration_s + 3 * kSmoothingS; ++tour) {
    flyTour(script, tour % 2 == 0, uniform(rng, -0.2, 0.2), uniform(rng, 0.85, 1.0));
  }
  TrajectoryModel trajectory;
  trajectory.path = script.smoothed();
  return b.build(trajectory);
}

}  // namespace rgbdslam::synthetic
