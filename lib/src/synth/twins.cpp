// The lookalike rooms (synth:twins): two identical rooms joined by a corridor, and a flight
// that looks around the first, crosses into the second and looks around it from the same
// spot, then flies back. A place recogniser sees the second room as the first one again
// (perceptual aliasing): only odometry can tell them apart. Issue 11 asks that no loop is
// closed between them, and that a lost tracker does not come back in the wrong one.
//
// Floor plan (x east, y north, z up from the floor at 0; metres):
//   closet      [-1.5, 0] x [2.5, 4.5]  behind A's west door
//   A           [0, 8] x [0, 7],   3.0 m high: textured walls, furniture; doors west and east
//   corridor    [8, 14] x [2.5, 4.5], 2.6 m: weakly textured, posters, doors, glass cabinets
//   B           [14, 22] x [0, 7]: A again, texture for texture (WorldBuilder::repeat)
//   closet      [22, 23.5] x [2.5, 4.5] behind B's east door
// So A and B differ only in what is seen through their doors (a closet or the corridor).
// The flight: take-off in A facing its west wall, a full turn at (4, 3.5), east through the
// corridor at 1 m/s, the same full turn at (18, 3.5) in B (the very views of A's turn where
// no door is in sight), back to A at 1 m/s and a hover at (4, 3.5) until the end (59 s in
// all; the scene's default length is 60 s).
#include <cmath>

#include "floor_plan.h"

namespace rgbdslam::synthetic {
namespace {

using S = SyntheticSurface;

constexpr double kTexelM = 0.01;
constexpr double kTwinShiftM = 14.0;     // B is A moved this far east [m]
constexpr double kCruiseZ = 1.4;         // flight height [m]
constexpr double kCorridorSpeed = 1.0;   // [m/s]

// Room A; the first boxes of the world (B repeats them).
void addRoomA(WorldBuilder& b) {
  const TextureStyle rich = richStyle();
  Space room = makeSpace(0, 0, 8, 7, kRoomH, rich);
  room.openings[kWest] = room.openings[kEast] = {{2.5, 4.5, kCorridorH}};
  addSpace(b, room);
  addLabFurniture(b, room);
  addOnWall(b, room, kEast, 0.6, 2.0, 0.5, 0, 1.2, S::kDiffuse, rich, false);    // crates
}

void buildTwinsFloorPlan(WorldBuilder& b) {
  addRoomA(b);
  b.repeat(0, Vec3(kTwinShiftM, 0, 0));  // B
  const TextureStyle weak = weakWallStyle();
  Space corridor = makeSpace(8, 2.5, kTwinShiftM, 4.5, kCorridorH, weak);
  corridor.open[kWest] = corridor.open[kEast] = true;
  addSpace(b, corridor);
  for (const int side : {kSouth, kNorth}) addCorridorFixtures(b, corridor, side);
  addCorridorLamps(b, corridor);
  Space west_closet = makeSpace(-1.5, 2.5, 0, 4.5, kCorridorH, weak);
  west_closet.open[kEast] = true;
  addSpace(b, west_closet);
  Space east_closet = makeSpace(kTwinShiftM + 8, 2.5, kTwinShiftM + 9.5, 4.5, kCorridorH, weak);
  east_closet.open[kWest] = true;
  addSpace(b, east_closet);
}

}  // namespace

World buildTwins(uint64_t seed, double /*duration_s*/) {
  WorldBuilder b(seed, kTexelM);
  buildTwinsFloorPlan(b);
  FlightScript f(PathState{2.6, 5.2, 1.3, M_PI, kPitch, 0});
  f.hover(2.0);
  f.flyTo(1.8, 5.0, 1.35, 0.3);
  f.flyTo(4.0, 3.5, kCruiseZ, 0.6);
  f.spin(2 * M_PI, kSpinRate);  // A, all round
  f.flyTo(6.5, 3.5, kCruiseZ, 0.8);
  f.flyTo(kTwinShiftM + 1.5, 3.5, kCruiseZ, kCorridorSpeed);
  f.flyTo(kTwinShiftM + 4.0, 3.5, kCruiseZ, 0.6);
  f.spin(2 * M_PI, kSpinRate);  // B, all round from A's spot
  f.flyTo(kTwinShiftM + 1.5, 3.5, kCruiseZ, 0.6);
  f.flyTo(6.5, 3.5, kCruiseZ, kCorridorSpeed);
  f.flyTo(4.0, 3.5, kCruiseZ, 0.6);
  f.hover(2.0);
  TrajectoryModel trajectory;
  trajectory.path = f.smoothed();
  return b.build(trajectory);
}

}  // namespace rgbdslam::synthetic
