// pose-logger: subscribes SLAM_POSE and writes a TUM trajectory and a CSV. See --help.
#include <iostream>
#include <limits>
#include <optional>

#include "common/cli.h"
#include "common/lcm_conversions.h"
#include "common/process.h"
#include "common/process_options.h"
#include "pose-logger/pose_log_writer.h"

using namespace rgbdslam;

namespace {

constexpr int kHandleTimeoutMs = 100;  // [ms] how often the stop flag is checked

// Converts each message and hands it to the writer; bad messages and poses of another map
// (a second tracker on the bus) are counted and reported, not fatal.
class PoseLogger {
 public:
  PoseLogger(PoseLogWriter writer, MapFilter filter) : writer_(std::move(writer)), filter_(filter) {}
  void onMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    auto msg = decodeMessage<rgbdslam::pose_t>(buffer->data, buffer->data_size);
    auto pose = msg ? fromLcm(*msg) : Expected<MapPose>(Error{msg.error()});
    if (!pose) {
      ++bad_messages_;
      std::cerr << "pose-logger: ignoring a bad message on " << channel << ": " << pose.error() << "\n";
      return;
    }
    if (!filter_.accept(pose->map_id)) {
      if (filter_.otherPoses() == 1 || filter_.otherPoses() % 1000 == 0) {
        std::cerr << "pose-logger: ignoring poses of map " << pose->map_id << " (logging map "
                  << *filter_.mapId() << "): " << filter_.describeOthers() << " so far\n";
      }
      return;
    }
    if (Status written = writer_.write(pose->pose); !written) {
      ++write_errors_;
      std::cerr << "pose-logger: error: " << written.error() << "\n";
    }
  }
  void printSummary() const {
    std::cerr << "pose-logger: " << writer_.csvLines() << " poses (" << writer_.trajectoryLines()
              << " in the trajectory) of map "
              << (filter_.mapId() ? std::to_string(*filter_.mapId()) : "(none)") << ", "
              << bad_messages_ << " bad messages, " << filter_.describeOthers() << ", "
              << write_errors_ << " write errors\n";
  }
  int exitStatus() const { return write_errors_ > 0 ? 1 : 0; }

 private:
  PoseLogWriter writer_;
  MapFilter filter_;
  long bad_messages_ = 0, write_errors_ = 0;
};

CommandLine makeCommandLine() {
  CommandLine cli("pose-logger", "Writes the poses on SLAM_POSE to a TUM trajectory and a CSV.");
  cli.option("output", "TRAJ.txt", "TUM trajectory file: 't tx ty tz qx qy qz qw' per tracked pose");
  cli.option("csv", "FILE", "CSV of every pose with state, points, quality, latency, the pose in the map and its part", "TRAJ with .csv");
  cli.option("map-output", "FILE", "TUM trajectory of the same poses in the map as it was then (pose_t.map_position): corrections at once, not taken in slowly", "none");
  cli.option("channel", "NAME", "LCM channel to subscribe (the suite's channels.pose)", ChannelOptions{}.pose);
  cli.option("map-id", "ID", "log this map's poses (pose_t.map_id >= 0); poses of other maps are counted and reported", "the first map seen");
  addLcmUrlOption(cli);
  return cli;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli = makeCommandLine();
  if (Status parsed = cli.parse(argc, argv); !parsed) return usageError("pose-logger", parsed.error());
  if (cli.helpRequested()) {
    std::cout << cli.helpText();
    return 0;
  }
  if (!cli.has("output")) return usageError("pose-logger", "--output is required (see --help)");
  const std::string output = cli.get("output");
  const std::string csv = cli.has("csv") ? cli.get("csv") : defaultCsvPath(output);
  std::optional<int64_t> map_id;
  if (cli.has("map-id")) {
    auto id = cli.getInt("map-id", 0, std::numeric_limits<long>::max());
    if (!id) return usageError("pose-logger", id.error());
    map_id = *id;
  }
  const std::string map_output = cli.has("map-output") ? cli.get("map-output") : "";
  auto writer = PoseLogWriter::open(output, csv, map_output);
  if (!writer) return usageError("pose-logger", writer.error());
  auto lcm = openLcm(cli.get("lcm-url"));
  if (!lcm) return usageError("pose-logger", lcm.error());
  std::cerr << "pose-logger configuration:\n  output " << output << "\n  csv " << csv << "\n  map-output " << (map_output.empty() ? "none" : map_output)
            << "\n  channel " << cli.get("channel") << "\n  map-id " << (map_id ? std::to_string(*map_id) : "the first map seen")
            << "\n  lcm-url " << cli.get("lcm-url") << "\n";

  PoseLogger logger(std::move(*writer), MapFilter(map_id));
  auto subscription = subscribeRaw(lcm->get(), cli.get("channel"), &logger, &PoseLogger::onMessage);
  const std::atomic<bool>& stop = installStopHandlers();
  while (!stop) (*lcm)->handleTimeout(kHandleTimeoutMs);
  logger.printSummary();
  return logger.exitStatus();
}
