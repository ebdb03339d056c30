#pragma once
// Writes poses to a TUM trajectory ("t tx ty tz qx qy qz qw") and a CSV with state, quality
// and latency. Each line goes to the file in one write(2) on an O_APPEND descriptor, so a
// SIGKILL loses at most the line being written and never leaves a partial line.
// The TUM file holds only poses the tracker vouches for (tracking, dodgy, relocalised);
// the CSV holds every pose, including initialising and lost ones.
#include <string>

#include "rgbdslam/tracking/pose_estimate.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class PoseLogWriter {
 public:
  static Expected<PoseLogWriter> open(const std::string& trajectory_path, const std::string& csv_path);
  PoseLogWriter(PoseLogWriter&& other) noexcept;
  PoseLogWriter& operator=(PoseLogWriter&&) = delete;
  ~PoseLogWriter();

  Status write(const PoseEstimate& pose);
  long trajectoryLines() const { return trajectory_lines_; }
  long csvLines() const { return csv_lines_; }

 private:
  PoseLogWriter(int trajectory_fd, int csv_fd, std::string trajectory_path, std::string csv_path);
  int trajectory_fd_ = -1, csv_fd_ = -1;
  std::string trajectory_path_, csv_path_;
  long trajectory_lines_ = 0, csv_lines_ = 0;
};

// "TRAJ.txt" -> "TRAJ.csv" (or TRAJ + ".csv" when there is no extension).
std::string defaultCsvPath(const std::string& trajectory_path);

}  // namespace rgbdslam
