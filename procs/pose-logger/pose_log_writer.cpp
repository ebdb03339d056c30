#include "pose-logger/pose_log_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "rgbdslam/io/trajectory_io.h"

namespace rgbdslam {
namespace {

constexpr const char* kCsvHeader =
    "utime,seq,state,points_tracked,quality,latency_ms,tx,ty,tz,qx,qy,qz,qw,"
    "map_tx,map_ty,map_tz,map_qx,map_qy,map_qz,map_qw,part\n";

// One write(2) per line; a short write (disk full, signal) is continued, and reported if it fails.
Status writeLine(int fd, const std::string& line, const std::string& path) {
  size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(fd, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return Error{path + ": write failed: " + std::strerror(errno)};
    done += static_cast<size_t>(n);
  }
  return {};
}

bool vouchedFor(TrackingState state) {
  return state == TrackingState::kTracking || state == TrackingState::kDodgy ||
         state == TrackingState::kRelocalised;
}

}  // namespace

std::string defaultCsvPath(const std::string& trajectory_path) {
  const size_t dot = trajectory_path.rfind('.');
  const size_t slash = trajectory_path.rfind('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return trajectory_path + ".csv";
  return trajectory_path.substr(0, dot) + ".csv";
}

Expected<PoseLogWriter> PoseLogWriter::open(const std::string& trajectory_path, const std::string& csv_path,
                                            const std::string& map_trajectory_path) {
  const int flags = O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC;
  int fds[3] = {-1, -1, -1};
  const std::string* paths[3] = {&trajectory_path, &csv_path, &map_trajectory_path};
  for (int i = 0; i < 3; ++i) {
    if (paths[i]->empty() && i == 2) break;
    fds[i] = ::open(paths[i]->c_str(), flags, 0644);
    if (fds[i] < 0) {
      const std::string error = *paths[i] + ": cannot create: " + std::strerror(errno);
      for (int j = 0; j < i; ++j) ::close(fds[j]);
      return Error{error};
    }
  }
  PoseLogWriter writer(fds[0], fds[1], fds[2], trajectory_path, csv_path, map_trajectory_path);
  if (Status s = writeLine(fds[1], kCsvHeader, csv_path); !s) return Error{s.error()};
  return writer;
}

PoseLogWriter::PoseLogWriter(int trajectory_fd, int csv_fd, int map_fd, std::string trajectory_path,
                             std::string csv_path, std::string map_path)
    : trajectory_fd_(trajectory_fd), csv_fd_(csv_fd), map_fd_(map_fd), trajectory_path_(std::move(trajectory_path)),
      csv_path_(std::move(csv_path)), map_path_(std::move(map_path)) {}

PoseLogWriter::PoseLogWriter(PoseLogWriter&& other) noexcept
    : trajectory_fd_(other.trajectory_fd_), csv_fd_(other.csv_fd_), map_fd_(other.map_fd_),
      trajectory_path_(std::move(other.trajectory_path_)), csv_path_(std::move(other.csv_path_)),
      map_path_(std::move(other.map_path_)), trajectory_lines_(other.trajectory_lines_),
      csv_lines_(other.csv_lines_) {
  other.trajectory_fd_ = other.csv_fd_ = other.map_fd_ = -1;
}

PoseLogWriter::~PoseLogWriter() {
  for (int fd : {trajectory_fd_, csv_fd_, map_fd_}) {
    if (fd >= 0) ::close(fd);
  }
}

Status PoseLogWriter::write(const PoseEstimate& pose) {
  const Vec3& t = pose.T_w_c.translation();
  const Eigen::Quaterniond& q = pose.T_w_c.rotation();
  const Vec3& mt = pose.map_T_w_c.translation();
  const Eigen::Quaterniond& mq = pose.map_T_w_c.rotation();
  if (!t.allFinite() || !q.coeffs().allFinite() || !mt.allFinite() || !mq.coeffs().allFinite() ||
      !std::isfinite(pose.quality) || !std::isfinite(pose.latency_ms)) {
    return Error{"pose " + std::to_string(pose.seq) + " has a value that is not finite: not written"};
  }
  // Sized by a first pass, so no line is ever cut (a position of 1e200 m prints 200 digits).
  const auto print = [&](char* out, size_t size) {
    return std::snprintf(out, size,
                         "%lld,%lld,%s,%d,%.4f,%.3f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,"
                         "%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%lld\n",
                         static_cast<long long>(pose.utime), static_cast<long long>(pose.seq),
                         toString(pose.state), pose.points_tracked, pose.quality, pose.latency_ms,
                         t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(), mt.x(), mt.y(), mt.z(), mq.x(),
                         mq.y(), mq.z(), mq.w(), static_cast<long long>(pose.part));
  };
  std::string csv(static_cast<size_t>(print(nullptr, 0)), '\0');
  print(csv.data(), csv.size() + 1);
  if (Status s = writeLine(csv_fd_, csv, csv_path_); !s) return s;
  ++csv_lines_;
  if (!vouchedFor(pose.state)) return {};
  const std::string line = formatTumLine({pose.utime * 1e-6, pose.T_w_c});
  if (Status s = writeLine(trajectory_fd_, line, trajectory_path_); !s) return s;
  ++trajectory_lines_;
  if (map_fd_ < 0) return {};
  return writeLine(map_fd_, formatTumLine({pose.utime * 1e-6, pose.map_T_w_c}), map_path_);
}

MapFilter::MapFilter(std::optional<int64_t> map_id) : map_id_(map_id) {}

bool MapFilter::accept(int64_t map_id) {
  if (!map_id_) map_id_ = map_id;
  if (map_id == *map_id_) return true;
  ++other_poses_;
  if (other_maps_.size() < kMaxListedMaps) other_maps_.insert(map_id);
  return false;
}

std::string MapFilter::describeOthers() const {
  std::string ids;
  for (int64_t id : other_maps_) ids += (ids.empty() ? "" : " ") + std::to_string(id);
  if (other_poses_ > 0 && other_maps_.size() == kMaxListedMaps) ids += " ...";
  return std::to_string(other_poses_) + " poses of other maps" + (ids.empty() ? "" : " (" + ids + ")");
}

}  // namespace rgbdslam
