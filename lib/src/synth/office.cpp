// The office (synth:office): two rooms with large plain walls and a hand-held walk through
// them, the case that breaks trackers: few or no corners, depth everywhere.
//
// Floor plan (x east, y north, z up from the floor at 0; metres), 2.8 m high:
//   A  "office"   [0, 6] x [0, 5]: matte white walls, two desks with screens (glossy) along
//                 the north wall, bookshelves (textured) on the west and north walls, a
//                 poster, a notice board by the doors, a plain cabinet;
//   B  "meeting"  [6.2, 10.2] x [0, 5]: plain east and south walls, a whiteboard (glossy) on
//                 the north wall, a notice board by the doors, one textured crate in the
//                 north-east corner;
//   two doors (1.2 m wide, 2.1 m high) in the wall between them, at y in [0.6, 1.8] and
//   [3.2, 4.4]; the floor is a grey carpet with faint grain.
// The walk: a closed loop A -> lower door -> B -> upper door -> A (18 m), smoothed by
// corner cutting, walked at 0.21 m/s +- 0.04 m/s (5.7-8.3 mm per frame at 30 Hz) with a
// slight bob, turning the head (yaw) towards the desks, the plain walls and the whiteboard;
// it stays >= 0.6 m from walls and furniture. The default 1240 frames (41 s, ~8.7 m) walk
// through A and turn in B facing its plain east and south walls with the floor.
#include <algorithm>
#include <cmath>

#include "world.h"

namespace rgbdslam::synthetic {
namespace {

constexpr double kOfficeTexelM = 0.01;
constexpr double kOfficeHeight = 2.8;                   // [m]
constexpr double kOfficeSplitX0 = 6.0, kOfficeSplitX1 = 6.2;  // the wall between A and B [m]
constexpr double kOfficeEastX = 10.2, kOfficeNorthY = 5.0;    // [m]
constexpr double kOfficeDoorTop = 2.1;                  // [m]
constexpr double kOfficeWalkSpeed = 0.21;               // mean walking speed [m/s]
constexpr double kOfficeSpeedSwing = 0.04;              // +- around it [m/s]
constexpr double kOfficeSpeedPeriodS = 6.0;             // period of the speed swing [s]
constexpr double kOfficeEyeHeight = 1.35;               // [m]
constexpr int kOfficeCornerCuts = 5;                    // Chaikin iterations on the loop
constexpr double kOfficePathDt = 0.01;                  // sampling of the walk [s]

using OfficeSurface = SyntheticSurface;

TextureStyle officeWallStyle() {  // matte white paint: no texture to speak of
  TextureStyle s;
  s.base_grey = 208, s.base_spread = 8, s.tint_spread = 0.04;
  s.octaves = {{2.0, 1.5}};
  return s;
}
TextureStyle officeCarpetStyle() {  // grey carpet: faint grain only
  TextureStyle s;
  s.base_grey = 110, s.base_spread = 4, s.tint_spread = 0.03;
  s.octaves = {{1.0, 3}, {0.03, 3}};
  return s;
}
TextureStyle officeFurnitureStyle() {  // plain grey laminate
  TextureStyle s;
  s.base_grey = 150, s.base_spread = 15, s.tint_spread = 0.06;
  s.octaves = {{0.8, 3}};
  return s;
}
TextureStyle officeScreenStyle() {  // a dark, glossy screen (returns depth, unless shiny_holes)
  TextureStyle s;
  s.base_grey = 45, s.base_spread = 5, s.tint_spread = 0.05;
  s.octaves = {{0.3, 3}};
  return s;
}
TextureStyle officeWhiteboardStyle() {  // glossy white with a few pen marks
  TextureStyle s;
  s.base_grey = 232, s.base_spread = 3, s.tint_spread = 0.03;
  s.octaves = {{1.0, 2}};
  s.shapes = {{4.0, 0.03, 0.2, 120}};
  return s;
}

void addOfficeShell(WorldBuilder& b) {
  const double t = kWallThickness, h = kOfficeHeight, e = kOfficeEastX, n = kOfficeNorthY;
  const TextureStyle wall = officeWallStyle();
  b.add(Vec3(-t, -t, -t), Vec3(e + t, n + t, 0), OfficeSurface::kDiffuse, officeCarpetStyle(),
        kFaceZHi);
  b.add(Vec3(-t, -t, h), Vec3(e + t, n + t, h + t), OfficeSurface::kDiffuse, ceilingStyle(),
        kFaceZLo);
  b.add(Vec3(-t, 0, 0), Vec3(0, n, h), OfficeSurface::kDiffuse, wall, kFaceXHi);
  b.add(Vec3(e, 0, 0), Vec3(e + t, n, h), OfficeSurface::kDiffuse, wall, kFaceXLo);
  b.add(Vec3(0, -t, 0), Vec3(e, 0, h), OfficeSurface::kDiffuse, wall, kFaceYHi);
  b.add(Vec3(0, n, 0), Vec3(e, n + t, h), OfficeSurface::kDiffuse, wall, kFaceYLo);
  // The wall between A and B: three pieces and two lintels over the doors.
  const double x0 = kOfficeSplitX0, x1 = kOfficeSplitX1;
  const unsigned sides = kFaceXLo | kFaceXHi | kFaceYLo | kFaceYHi;
  for (const auto& [y0, y1] : {std::pair{0.0, 0.6}, {1.8, 3.2}, {4.4, n}}) {
    b.add(Vec3(x0, y0, 0), Vec3(x1, y1, h), OfficeSurface::kDiffuse, wall, sides);
  }
  for (const auto& [y0, y1] : {std::pair{0.6, 1.8}, {3.2, 4.4}}) {
    b.add(Vec3(x0, y0, kOfficeDoorTop), Vec3(x1, y1, h), OfficeSurface::kDiffuse, wall,
          kFaceXLo | kFaceXHi | kFaceZLo);
  }
}

void addOfficeFurniture(WorldBuilder& b) {
  const TextureStyle plain = officeFurnitureStyle(), rich = richStyle();
  const double n = kOfficeNorthY;
  for (const double x : {0.8, 3.0}) {  // desks with a screen and a glossy top
    b.add(Vec3(x, n - 0.8, 0), Vec3(x + 1.6, n, 0.75), OfficeSurface::kShiny, plain);
    b.add(Vec3(x + 0.5, n - 0.4, 0.8), Vec3(x + 1.1, n - 0.35, 1.2), OfficeSurface::kShiny,
          officeScreenStyle());
  }
  b.add(Vec3(3.5, n - 0.6, 0.75), Vec3(3.9, n - 0.2, 1.0), OfficeSurface::kDiffuse, rich);  // box
  b.add(Vec3(0, 1.0, 0), Vec3(0.4, 2.6, 2.0), OfficeSurface::kDiffuse, rich);  // bookshelf
  b.add(Vec3(2.0, 0, 1.2), Vec3(3.0, 0.02, 1.9), OfficeSurface::kDiffuse, rich, kFaceYHi);
  b.add(Vec3(4.8, 0, 0), Vec3(5.8, 0.5, 1.1), OfficeSurface::kDiffuse, plain);  // cabinet
  b.add(Vec3(4.8, n - 0.4, 0), Vec3(5.8, n, 1.8), OfficeSurface::kDiffuse, rich);  // books
  // Notice boards on both faces of the wall between the rooms, between the doors.
  b.add(Vec3(kOfficeSplitX0 - 0.02, 2.0, 1.0), Vec3(kOfficeSplitX0, 3.0, 1.8),
        OfficeSurface::kDiffuse, rich, kFaceXLo);
  b.add(Vec3(kOfficeSplitX1, 2.1, 1.1), Vec3(kOfficeSplitX1 + 0.02, 2.9, 1.7),
        OfficeSurface::kDiffuse, rich, kFaceXHi);
  b.add(Vec3(7.0, n - 0.02, 0.9), Vec3(8.8, n, 2.0), OfficeSurface::kShiny,
        officeWhiteboardStyle(), kFaceYLo);
  b.add(Vec3(9.6, n - 0.6, 0), Vec3(kOfficeEastX, n, 1.2), OfficeSurface::kDiffuse, rich);
}

// A point of the walk: position [m] and where the head turns, relative to the direction of
// travel [rad] (positive: to the left).
struct OfficeWaypoint {
  double x, y, look;
};

// The closed loop, then corner cutting (Chaikin) on position and look together.
std::vector<OfficeWaypoint> officeLoop() {
  std::vector<OfficeWaypoint> loop = {
      {2.0, 1.2, 0.5},  {4.6, 1.2, -0.6}, {7.2, 1.2, 0.0},   {8.7, 1.3, -0.9},
      {9.1, 2.5, -1.0}, {8.7, 3.7, -0.2}, {7.2, 3.8, 0.0},   {5.6, 3.8, 0.3},
      {4.6, 3.3, -0.5}, {2.0, 3.3, 0.3},  {1.2, 2.3, 0.0}};
  for (int cut = 0; cut < kOfficeCornerCuts; ++cut) {
    std::vector<OfficeWaypoint> finer;
    for (size_t i = 0; i < loop.size(); ++i) {
      const OfficeWaypoint& p = loop[i];
      const OfficeWaypoint& q = loop[(i + 1) % loop.size()];
      auto at = [&](double w) {
        return OfficeWaypoint{p.x + w * (q.x - p.x), p.y + w * (q.y - p.y),
                              p.look + w * (q.look - p.look)};
      };
      finer.push_back(at(0.25));
      finer.push_back(at(0.75));
    }
    loop = std::move(finer);
  }
  return loop;
}

// The loop by arc length: cumulative length and unwrapped heading at each vertex.
struct OfficeLoopTable {
  std::vector<OfficeWaypoint> points;
  std::vector<double> s;        // arc length at points[i] [m]; s.back() closes the loop
  std::vector<double> heading;  // direction of travel at points[i] [rad], unwrapped
};

OfficeLoopTable officeLoopTable() {
  OfficeLoopTable table;
  table.points = officeLoop();
  const size_t n = table.points.size();
  table.points.push_back(table.points.front());  // closed
  table.s.push_back(0);
  for (size_t i = 1; i <= n; ++i) {
    const auto& p = table.points[i - 1];
    const auto& q = table.points[i];
    table.s.push_back(table.s.back() + std::hypot(q.x - p.x, q.y - p.y));
  }
  auto direction = [&](size_t i) {  // of the segment from vertex i to i + 1 (cyclic)
    const auto& p = table.points[i % n];
    const auto& q = table.points[(i + 1) % n];
    return std::atan2(q.y - p.y, q.x - p.x);
  };
  double previous = 0;
  for (size_t i = 0; i <= n; ++i) {
    // The mean of the directions of the segments meeting at the vertex, unwrapped.
    const double in = direction(i + n - 1), out = direction(i);
    double h = in + 0.5 * std::remainder(out - in, 2 * M_PI);
    if (i > 0) h = previous + std::remainder(h - previous, 2 * M_PI);
    table.heading.push_back(previous = h);
  }
  return table;
}

// The walk's state at arc length s (wrapped around the loop; each lap adds a full turn of
// heading, so yaw stays continuous).
PathState officeStateAt(const OfficeLoopTable& table, double s) {
  const double length = table.s.back();
  const double laps = std::floor(s / length);
  const double r = s - laps * length;
  const size_t i = std::min<size_t>(
      std::upper_bound(table.s.begin(), table.s.end(), r) - table.s.begin(), table.s.size() - 1);
  const size_t a = i - 1;
  const double w = (r - table.s[a]) / std::max(1e-12, table.s[i] - table.s[a]);
  const auto& p = table.points[a];
  const auto& q = table.points[i];
  const double turn = table.heading.back() - table.heading.front();  // one lap's heading change
  const double heading = laps * turn + table.heading[a] + w * (table.heading[i] - table.heading[a]);
  PathState state;
  state.x = p.x + w * (q.x - p.x);
  state.y = p.y + w * (q.y - p.y);
  state.yaw = heading + p.look + w * (q.look - p.look);
  return state;
}

SampledPath officeWalk(std::mt19937_64& rng, double duration_s) {
  const OfficeLoopTable table = officeLoopTable();
  const double phase = uniform(rng, 0, 2 * M_PI), bob_phase = uniform(rng, 0, 2 * M_PI);
  const double omega = 2 * M_PI / kOfficeSpeedPeriodS;
  SampledPath path;
  path.dt = kOfficePathDt;
  const int n = static_cast<int>(std::ceil((duration_s + 1.0) / kOfficePathDt)) + 1;
  for (int k = 0; k < n; ++k) {
    const double t = k * kOfficePathDt;
    // s' = speed + swing cos(omega t + phase) > 0: always walking.
    const double s = kOfficeWalkSpeed * t +
                     kOfficeSpeedSwing / omega * (std::sin(omega * t + phase) - std::sin(phase));
    PathState state = officeStateAt(table, s);
    state.z = kOfficeEyeHeight + 0.03 * std::sin(1.3 * t + bob_phase);
    state.pitch = -0.18 + 0.05 * std::sin(0.37 * t + phase);
    state.roll = 0.02 * std::sin(0.53 * t + bob_phase);
    path.samples.push_back(state);
  }
  return path;
}

}  // namespace

World buildOffice(uint64_t seed, double duration_s) {
  WorldBuilder b(seed, kOfficeTexelM);
  addOfficeShell(b);
  addOfficeFurniture(b);
  std::mt19937_64 rng = makeEngine(seed, /*stream=*/2);
  TrajectoryModel trajectory;
  trajectory.path = officeWalk(rng, duration_s);
  return b.build(trajectory);
}

}  // namespace rgbdslam::synthetic
