#pragma once
// Writes poses to a TUM trajectory ("t tx ty tz qx qy qz qw") and a CSV with state, quality
// and latency. Each line goes to the file in one write(2) on an O_APPEND descriptor, so a
// SIGKILL loses at most the line being written and never leaves a partial line.
// The TUM file holds only poses the tracker vouches for (tracking, dodgy, relocalised);
// the CSV holds every pose, including initialising and lost ones, with both the published
// pose and the pose in the map (pose_estimate.h) and the part of the map. A second TUM file,
// if asked for, holds the vouched-for poses in the map (what the map's accuracy is measured
// on; the published poses take corrections in slowly). Lines are as long as their
// numbers need; a pose with a value that is not finite is refused with an error.
#include <cstdint>
#include <optional>
#include <set>
#include <string>

#include "rgbdslam/tracking/pose_estimate.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class PoseLogWriter {
 public:
  // map_trajectory_path empty: no trajectory of map poses.
  static Expected<PoseLogWriter> open(const std::string& trajectory_path, const std::string& csv_path,
                                      const std::string& map_trajectory_path = "");
  PoseLogWriter(PoseLogWriter&& other) noexcept;
  PoseLogWriter& operator=(PoseLogWriter&&) = delete;
  ~PoseLogWriter();

  Status write(const PoseEstimate& pose);
  long trajectoryLines() const { return trajectory_lines_; }
  long csvLines() const { return csv_lines_; }

 private:
  PoseLogWriter(int trajectory_fd, int csv_fd, int map_fd, std::string trajectory_path, std::string csv_path,
                std::string map_path);
  int trajectory_fd_ = -1, csv_fd_ = -1, map_fd_ = -1;
  std::string trajectory_path_, csv_path_, map_path_;
  long trajectory_lines_ = 0, csv_lines_ = 0;
};

// Keeps one map's poses: the map given, or else the first one seen. Each map has its own
// world frame, so two trackers' poses in one trajectory would be meaningless; poses of any
// other map are refused and counted (the first kMaxListedMaps other ids are listed).
class MapFilter {
 public:
  static constexpr size_t kMaxListedMaps = 8;
  explicit MapFilter(std::optional<int64_t> map_id = std::nullopt);
  bool accept(int64_t map_id);  // true: this pose belongs to the logged map
  std::optional<int64_t> mapId() const { return map_id_; }
  long otherPoses() const { return other_poses_; }
  std::string describeOthers() const;  // "N poses of other maps (id id ...)"

 private:
  std::optional<int64_t> map_id_;
  long other_poses_ = 0;
  std::set<int64_t> other_maps_;
};

// "TRAJ.txt" -> "TRAJ.csv" (or TRAJ + ".csv" when there is no extension).
std::string defaultCsvPath(const std::string& trajectory_path);

}  // namespace rgbdslam
