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

#include "floor_plan.h"

namespace rgbdslam::synthetic {
namespace {

using S = SyntheticSurface;

constexpr double kTexelM = 0.01;
constexpr double kHallH = 4.0;     // the hall's height [m]
constexpr double kTopSpeed = 2.0;  // in C1 [m/s]

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

void buildFloorPlan(WorldBuilder& b) {
  const TextureStyle rich = richStyle(), weak = weakWallStyle();
  const Opening corridor_door_x{2.5, 4.5, kCorridorH};  // C1's end in A and B

  Space a = makeSpace(0, 0, 8, 7, kRoomH, rich);  // the lab
  a.openings[kEast] = {corridor_door_x};
  a.openings[kNorth] = {{3, 5, kCorridorH}};
  addSpace(b, a);
  addLabFurniture(b, a);

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
