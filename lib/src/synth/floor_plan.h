#pragma once
// Building blocks of the scenes built from rooms and corridors (flight.cpp, twins.cpp): a
// floor plan of axis-aligned spaces with doors, the fixtures along corridor walls, and a
// scripted flight sampled at 100 Hz and smoothed like a micro aerial vehicle's.
#include <array>
#include <vector>

#include "world.h"

namespace rgbdslam::synthetic {

constexpr double kCorridorH = 2.6, kRoomH = 3.0;  // heights [m]

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

Space makeSpace(double x0, double y0, double x1, double y1, double h, const TextureStyle& walls);
// Floor, ceiling and the walls of 's' (with their doors and lintels).
void addSpace(WorldBuilder& b, const Space& s);
// A box against the inside of wall 'side' of 's', from a to b along the wall, 'depth' into
// the space, from z0 to z1. 'front_only': only the face towards the space is textured.
void addOnWall(WorldBuilder& b, const Space& s, int side, double a, double b_, double depth,
               double z0, double z1, SyntheticSurface surface, const TextureStyle& style,
               bool front_only);
// The lab's furniture in room 'a' (8 x 7 m, doors clear of it on the west wall's middle
// and the east and north walls): a cupboard, a desk, a chest, a low box and a board.
void addLabFurniture(WorldBuilder& b, const Space& a);
// Posters, doors and glass cabinets along a corridor wall, clear of its openings.
void addCorridorFixtures(WorldBuilder& b, const Space& s, int side);
void addCorridorLamps(WorldBuilder& b, const Space& s);

// ---- the flight script
constexpr double kScriptDt = 0.01;        // sampling of the script [s]
constexpr double kSmoothingS = 0.25;      // Gaussian smoothing of the script [s]
constexpr double kTurnRate = M_PI / 3;    // turns at corners: 60 deg/s
constexpr double kSpinRate = M_PI / 2;    // look-around spins: 90 deg/s
constexpr double kPitch = -0.12;          // looking slightly down [rad]

class FlightScript {
 public:
  explicit FlightScript(const PathState& start) { samples_.push_back(start); }
  double seconds() const { return (samples_.size() - 1) * kScriptDt; }
  void hover(double seconds) { move(last(), seconds); }
  // Turns on the spot by 'angle' (signed; may exceed a full turn) at 'rate'.
  void spin(double angle, double rate);
  // Flies straight to (x, y, z) at 'speed', looking along the way: turns on the spot first
  // where the heading is more than 30 deg off, else turns while flying.
  void flyTo(double x, double y, double z, double speed);
  // Smoothed, with the roll of a banking vehicle.
  SampledPath smoothed() const;

 private:
  const PathState& last() const { return samples_.back(); }
  void move(PathState to, double seconds);  // by value: to may be last()
  std::vector<PathState> samples_;
};

}  // namespace rgbdslam::synthetic
