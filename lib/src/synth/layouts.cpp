// The room and the corridor and their trajectories (the flight: flight.cpp). World frame z-up, metres.
//  room:     x in [0, 6], y in [0, 5], z in [0, 3]; boxes along the walls; the camera moves
//            in the middle (>= 0.8 m from walls and boxes) and looks around the room.
//  corridor: 2 m wide, 2.6 m high along +x (y in [-1, 1]); a 6 x 6 m room, 3 m high, in the
//            middle; weakly textured walls, glass cabinets and black doors (no depth),
//            posters and ceiling lamps; the camera flies forward at 1 m/s.
#include <algorithm>
#include <cmath>

#include "world.h"

namespace rgbdslam::synthetic {

// ---- styles (world.h)
TextureStyle richStyle() {  // strongly textured: room surfaces, boxes, posters
  TextureStyle s;
  s.base_grey = 135, s.base_spread = 35, s.tint_spread = 0.25;
  s.octaves = {{0.6, 25}, {0.15, 18}, {0.04, 10}, {0.012, 5}};
  s.shapes = {{1.5, 0.25, 0.6, 80}, {12, 0.07, 0.25, 90}, {70, 0.02, 0.07, 90}};
  return s;
}
TextureStyle weakWallStyle() {  // corridor walls: low contrast, a few marks
  TextureStyle s;
  s.base_grey = 185, s.base_spread = 8, s.tint_spread = 0.08;
  s.octaves = {{1.0, 6}, {0.2, 4}, {0.03, 3}};
  s.shapes = {{2.0, 0.02, 0.08, 35}, {0.15, 0.1, 0.3, 45}};
  return s;
}
TextureStyle floorStyle() {  // speckled linoleum
  TextureStyle s;
  s.base_grey = 110, s.base_spread = 5, s.tint_spread = 0.05;
  s.octaves = {{0.5, 12}, {0.1, 8}, {0.02, 8}};
  s.shapes = {{25, 0.015, 0.05, 55}, {0.5, 0.1, 0.4, 40}};
  return s;
}
TextureStyle ceilingStyle() {
  TextureStyle s;
  s.base_grey = 205, s.base_spread = 8, s.tint_spread = 0.05;
  s.octaves = {{0.8, 5}, {0.05, 4}};
  s.shapes = {{1.0, 0.02, 0.1, 30}};
  return s;
}
TextureStyle glassStyle() {  // dark glass with objects behind it
  TextureStyle s;
  s.base_grey = 75, s.base_spread = 15, s.tint_spread = 0.3;
  s.octaves = {{0.3, 20}, {0.05, 10}};
  s.shapes = {{15, 0.05, 0.3, 70}, {30, 0.02, 0.06, 60}};
  return s;
}
TextureStyle blackStyle() {
  TextureStyle s;
  s.base_grey = 22, s.base_spread = 6, s.tint_spread = 0.1;
  s.octaves = {{0.2, 3}, {0.02, 3}};
  return s;
}
TextureStyle lampStyle() {
  TextureStyle s;
  s.base_grey = 250, s.tint_spread = 0.02;
  return s;
}

namespace {

using S = SyntheticSurface;


Channel channel(double offset, double slope, std::vector<Wave> waves, std::mt19937_64& rng) {
  for (Wave& w : waves) w.phase = uniform(rng, 0, 2 * M_PI);
  return Channel{offset, slope, std::move(waves)};
}

// ---- room
constexpr double kRoomX = 6.0, kRoomY = 5.0, kRoomZ = 3.0;  // [m]
constexpr double kRoomTexelM = 0.0075;

// Floor, ceiling and four walls as slabs around the box [lo, hi], inner faces textured.
void addEnclosure(WorldBuilder& b, const Vec3& lo, const Vec3& hi, const TextureStyle& walls,
                  const TextureStyle& floor, const TextureStyle& ceiling) {
  const double t = kWallThickness;
  b.add(Vec3(lo.x() - t, lo.y() - t, lo.z() - t), Vec3(hi.x() + t, hi.y() + t, lo.z()),
        S::kDiffuse, floor, kFaceZHi);
  b.add(Vec3(lo.x() - t, lo.y() - t, hi.z()), Vec3(hi.x() + t, hi.y() + t, hi.z() + t),
        S::kDiffuse, ceiling, kFaceZLo);
  b.add(Vec3(lo.x() - t, lo.y(), lo.z()), Vec3(lo.x(), hi.y(), hi.z()), S::kDiffuse, walls,
        kFaceXHi);
  b.add(Vec3(hi.x(), lo.y(), lo.z()), Vec3(hi.x() + t, hi.y(), hi.z()), S::kDiffuse, walls,
        kFaceXLo);
  b.add(Vec3(lo.x(), lo.y() - t, lo.z()), Vec3(hi.x(), lo.y(), hi.z()), S::kDiffuse, walls,
        kFaceYHi);
  b.add(Vec3(lo.x(), hi.y(), lo.z()), Vec3(hi.x(), hi.y() + t, hi.z()), S::kDiffuse, walls,
        kFaceYLo);
}

TrajectoryModel roomTrajectory(std::mt19937_64& rng) {
  // Position stays in x [1.85, 4.15], y [1.65, 3.25], z [1.25, 1.75]: >= 0.8 m from the
  // walls and the boxes. Peak speed ~0.35 m/s; yaw turns once per ~30 s plus a sweep,
  // peak rate 0.2 + 0.45 * 0.35 = 0.36 rad/s (~21 deg/s); looking 8-22 deg down.
  TrajectoryModel m;
  m.x = channel(3.0, 0, {{0.8, 0.21, 0}, {0.35, 0.53, 0}}, rng);
  m.y = channel(2.45, 0, {{0.55, 0.27, 0}, {0.25, 0.61, 0}}, rng);
  m.z = channel(1.5, 0, {{0.18, 0.33, 0}, {0.07, 0.9, 0}}, rng);
  m.yaw = channel(uniform(rng, 0, 2 * M_PI), 0.2, {{0.45, 0.35, 0}}, rng);
  m.pitch = channel(-0.25, 0, {{0.12, 0.29, 0}}, rng);
  m.roll = channel(0, 0, {{0.06, 0.41, 0}}, rng);
  return m;
}

// ---- corridor
constexpr double kCorridorHalfWidth = 1.0, kCorridorHeight = 2.6;  // [m]
constexpr double kHallSize = 6.0, kHallHeight = 3.0;               // the room in the middle [m]
constexpr double kCorridorSpeed = 1.0;                             // [m/s]
constexpr double kCorridorStartX = 2.0;                            // first camera x [m]
constexpr double kCorridorEndMargin = 4.0;  // last camera x to the end wall [m]
constexpr double kSegmentM = 5.0;           // wall/floor pieces (texture size) [m]
constexpr double kCorridorTexelM = 0.01;

// Walls, floor and ceiling of the corridor between x0 and x1 (segments of kSegmentM).
void addCorridorPart(WorldBuilder& b, double x0, double x1) {
  const double w = kCorridorHalfWidth, h = kCorridorHeight, t = kWallThickness;
  for (double xa = x0; xa < x1 - 1e-9; xa += kSegmentM) {
    const double xb = std::min(x1, xa + kSegmentM);
    b.add(Vec3(xa, -w, -t), Vec3(xb, w, 0), S::kDiffuse, floorStyle(), kFaceZHi);
    b.add(Vec3(xa, -w, h), Vec3(xb, w, h + t), S::kDiffuse, ceilingStyle(), kFaceZLo);
    b.add(Vec3(xa, -w - t, 0), Vec3(xb, -w, h), S::kDiffuse, weakWallStyle(), kFaceYHi);
    b.add(Vec3(xa, w, 0), Vec3(xb, w + t, h), S::kDiffuse, weakWallStyle(), kFaceYLo);
  }
}

// The hall [hx0, hx0 + 6] x [-3, 3]: enclosure with openings to the corridor, boxes.
void addHall(WorldBuilder& b, double hx0) {
  const double hx1 = hx0 + kHallSize, hy = kHallSize / 2, w = kCorridorHalfWidth;
  const double t = kWallThickness, h = kHallHeight, hc = kCorridorHeight;
  b.add(Vec3(hx0, -hy, -t), Vec3(hx1, hy, 0), S::kDiffuse, floorStyle(), kFaceZHi);
  b.add(Vec3(hx0, -hy, h), Vec3(hx1, hy, h + t), S::kDiffuse, ceilingStyle(), kFaceZLo);
  b.add(Vec3(hx0, -hy - t, 0), Vec3(hx1, -hy, h), S::kDiffuse, richStyle(), kFaceYHi);
  b.add(Vec3(hx0, hy, 0), Vec3(hx1, hy + t, h), S::kDiffuse, richStyle(), kFaceYLo);
  for (const double x : {hx0, hx1}) {  // end walls with a corridor-sized opening
    const double xa = x == hx0 ? x - t : x, xb = xa + t;
    const unsigned face = x == hx0 ? kFaceXHi : kFaceXLo;
    b.add(Vec3(xa, -hy, 0), Vec3(xb, -w, h), S::kDiffuse, richStyle(), face);
    b.add(Vec3(xa, w, 0), Vec3(xb, hy, h), S::kDiffuse, richStyle(), face);
    b.add(Vec3(xa, -w, hc), Vec3(xb, w, h), S::kDiffuse, richStyle(), face | kFaceZLo);
  }
  // Furniture along the side walls, >= 1.3 m from the centre line.
  b.add(Vec3(hx0 + 0.5, -hy, 0), Vec3(hx0 + 2.0, -hy + 0.6, 1.8), S::kDiffuse, richStyle());
  b.add(Vec3(hx0 + 3.5, -hy + 0.3, 0), Vec3(hx0 + 4.7, -hy + 1.2, 0.75), S::kDiffuse,
        richStyle());
  b.add(Vec3(hx0 + 1.0, hy - 1.5, 0), Vec3(hx0 + 2.2, hy - 0.4, 1.0), S::kDiffuse, richStyle());
  b.add(Vec3(hx0 + 4.0, hy - 0.5, 0), Vec3(hx0 + 5.5, hy, 2.0), S::kGlass, glassStyle());
  b.add(Vec3(hx0 + 3.0, hy - 0.02, 0.0), Vec3(hx0 + 3.9, hy, 2.05), S::kBlack, blackStyle(),
        kFaceYLo);
}

// Things on one corridor wall (side -1: y = -1, +1: y = +1) between x0 and x1.
void addWallFixtures(WorldBuilder& b, double x0, double x1, int side) {
  const double w = kCorridorHalfWidth;
  const unsigned inner = side > 0 ? kFaceYLo : kFaceYHi;
  auto across = [&](double depth) {  // y interval of something 'depth' deep on this wall
    return side > 0 ? std::make_pair(w - depth, w) : std::make_pair(-w, -w + depth);
  };
  std::mt19937_64& rng = b.rng();
  for (double x = x0 + uniform(rng, 1.0, 4.0); x < x1 - 2.0; x += uniform(rng, 2.5, 5.0)) {
    const double kind = uniform01(rng);
    if (kind < 0.3) {  // glass cabinet, 1.0-1.8 m long, 0.25 m deep
      const double len = uniform(rng, 1.0, 1.8);
      const auto [ya, yb] = across(0.25);
      b.add(Vec3(x, ya, 0), Vec3(x + len, yb, 1.9), S::kGlass, glassStyle());
      x += len;
    } else if (kind < 0.5) {  // black door
      const auto [ya, yb] = across(0.03);
      b.add(Vec3(x, ya, 0), Vec3(x + 0.9, yb, 2.05), S::kBlack, blackStyle(), inner);
      x += 0.9;
    } else if (kind < 0.7) {  // wooden door with its own texture
      const auto [ya, yb] = across(0.03);
      b.add(Vec3(x, ya, 0), Vec3(x + 0.9, yb, 2.05), S::kDiffuse, floorStyle(), inner);
      x += 0.9;
    } else {  // poster or notice board
      const double len = uniform(rng, 0.4, 1.2), z0 = uniform(rng, 0.9, 1.3);
      const auto [ya, yb] = across(0.01);
      b.add(Vec3(x, ya, z0), Vec3(x + len, yb, z0 + uniform(rng, 0.4, 0.9)), S::kDiffuse,
            richStyle(), inner);
      x += len;
    }
  }
}

void addLamps(WorldBuilder& b, double x0, double x1) {
  for (double x = x0 + 2.0; x < x1 - 1.0; x += 4.0) {
    b.add(Vec3(x, -0.3, kCorridorHeight - 0.03), Vec3(x + 1.2, 0.3, kCorridorHeight), S::kDiffuse,
          lampStyle(), kFaceZLo);
  }
}

TrajectoryModel corridorTrajectory(std::mt19937_64& rng) {
  // Forward at 1 m/s (+-0.05), sway |y| <= 0.28 m, height 1.3 +- 0.11 m, yaw within
  // +-0.16 rad (9 deg), slightly looking down.
  TrajectoryModel m;
  m.x = channel(kCorridorStartX, kCorridorSpeed, {{0.15, 0.31, 0}}, rng);
  m.y = channel(0, 0, {{0.2, 0.23, 0}, {0.08, 0.71, 0}}, rng);
  m.z = channel(1.3, 0, {{0.08, 0.37, 0}, {0.03, 1.3, 0}}, rng);
  m.yaw = channel(0, 0, {{0.12, 0.17, 0}, {0.04, 0.53, 0}}, rng);
  m.pitch = channel(-0.05, 0, {{0.03, 0.43, 0}}, rng);
  m.roll = channel(0, 0, {{0.02, 0.6, 0}}, rng);
  return m;
}

}  // namespace

double Channel::at(double t) const {
  double value = offset + slope * t;
  for (const Wave& w : waves) value += w.amplitude * std::sin(w.omega * t + w.phase);
  return value;
}

SE3 poseOf(const PathState& s) {
  const double psi = s.yaw, theta = s.pitch, phi = s.roll;
  const Vec3 forward(std::cos(theta) * std::cos(psi), std::cos(theta) * std::sin(psi),
                     std::sin(theta));
  const Vec3 right(std::sin(psi), -std::cos(psi), 0.0);
  const Vec3 down = forward.cross(right);
  Mat3 R_w_c0;
  R_w_c0.col(0) = right;
  R_w_c0.col(1) = down;
  R_w_c0.col(2) = forward;
  const Mat3 R_c0_c = Eigen::AngleAxisd(phi, Vec3::UnitZ()).toRotationMatrix();
  return SE3(Mat3(R_w_c0 * R_c0_c), Vec3(s.x, s.y, s.z));
}

PathState SampledPath::at(double t) const {
  const double f = std::max(0.0, t / dt);
  const size_t i = static_cast<size_t>(f);
  if (i + 1 >= samples.size()) return samples.back();
  const double w = f - static_cast<double>(i);
  const PathState& a = samples[i];
  const PathState& b = samples[i + 1];
  auto mix = [w](double u, double v) { return u + w * (v - u); };
  return PathState{mix(a.x, b.x),     mix(a.y, b.y),         mix(a.z, b.z),
                   mix(a.yaw, b.yaw), mix(a.pitch, b.pitch), mix(a.roll, b.roll)};
}

SE3 TrajectoryModel::pose(double t) const {
  if (!path.samples.empty()) return poseOf(path.at(t));
  return poseOf(PathState{x.at(t), y.at(t), z.at(t), yaw.at(t), pitch.at(t), roll.at(t)});
}

World buildRoom(uint64_t seed, double /*duration_s*/) {
  WorldBuilder b(seed, kRoomTexelM);
  addEnclosure(b, Vec3(0, 0, 0), Vec3(kRoomX, kRoomY, kRoomZ), richStyle(), richStyle(),
               richStyle());
  const TextureStyle rich = richStyle();
  b.add(Vec3(0, 0.5, 0), Vec3(0.6, 2.0, 1.8), S::kDiffuse, rich);        // cupboard
  b.add(Vec3(4.6, 3.6, 0), Vec3(5.6, 4.6, 0.75), S::kDiffuse, rich);     // table
  b.add(Vec3(4.8, 3.8, 0.75), Vec3(5.2, 4.3, 1.05), S::kDiffuse, rich);  // box on the table
  b.add(Vec3(2.5, 4.3, 0), Vec3(3.5, 5.0, 1.0), S::kDiffuse, rich);      // chest
  b.add(Vec3(0.3, 3.8, 0), Vec3(1.1, 4.7, 0.5), S::kDiffuse, rich);      // low box
  b.add(Vec3(5.2, 0.4, 0), Vec3(6.0, 1.4, 1.2), S::kDiffuse, rich);      // stack
  b.add(Vec3(2.0, 0.0, 0.9), Vec3(3.6, 0.02, 1.9), S::kDiffuse, rich, kFaceYHi);  // board
  std::mt19937_64 rng = makeEngine(seed, /*stream=*/2);
  return b.build(roomTrajectory(rng));
}

World buildCorridor(uint64_t seed, double duration_s) {
  WorldBuilder b(seed, kCorridorTexelM);
  std::mt19937_64 rng = makeEngine(seed, /*stream=*/2);
  const TrajectoryModel trajectory = corridorTrajectory(rng);
  // Long enough for the whole flight, with the hall half-way.
  const double travel = kCorridorSpeed * duration_s;
  const double length = kCorridorStartX + travel + kCorridorEndMargin;
  const double hall_x0 = std::max(kCorridorStartX + 4.0,
                                  kCorridorStartX + 0.5 * travel - kHallSize / 2);
  const double hall_x1 = hall_x0 + kHallSize;
  const double end_x = std::max(length, hall_x1 + kCorridorEndMargin);
  addCorridorPart(b, 0.0, hall_x0);
  addCorridorPart(b, hall_x1, end_x);
  addHall(b, hall_x0);
  for (const int side : {-1, 1}) {
    addWallFixtures(b, 0.0, hall_x0, side);
    addWallFixtures(b, hall_x1, end_x, side);
  }
  addLamps(b, 0.0, hall_x0);
  addLamps(b, hall_x1, end_x);
  const double w = kCorridorHalfWidth, h = kCorridorHeight, t = kWallThickness;
  b.add(Vec3(-t, -w, 0), Vec3(0, w, h), S::kDiffuse, richStyle(), kFaceXHi);
  b.add(Vec3(end_x, -w, 0), Vec3(end_x + t, w, h), S::kDiffuse, richStyle(), kFaceXLo);
  return b.build(trajectory);
}

}  // namespace rgbdslam::synthetic
