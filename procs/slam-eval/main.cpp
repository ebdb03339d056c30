// slam-eval: absolute trajectory error (ATE) and relative pose error (RPE) of an estimated
// trajectory against ground truth, both in TUM format. Offline tool: it does not use LCM.
// Exit codes: 0 success, 1 evaluation or output failed, 2 bad arguments or input files.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "common/cli.h"
#include "rgbdslam/eval/trajectory_eval.h"
#include "rgbdslam/io/trajectory_io.h"

namespace {

using rgbdslam::Error;
using rgbdslam::Expected;
using rgbdslam::Status;

constexpr int kExitOk = 0;
constexpr int kExitEvalFailed = 1;
constexpr int kExitBadInput = 2;

struct CliOptions {
  std::string groundtruth_path;  // TUM trajectory file
  std::string estimate_path;     // TUM trajectory file
  bool print_json = false;       // print JSON instead of "key value" lines
  std::string json_out;          // also write the JSON here, if not empty
  std::string plot_path;         // write a PNG plot here, if not empty
  std::string errors_out;        // write per-pose ATE errors (CSV) here, if not empty
  std::string frames_from;       // count frames in this rgb.txt, if not empty
  rgbdslam::EvalOptions eval;
};

std::string formatDefault(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%g", value);
  return buffer;
}

rgbdslam::CommandLine makeCommandLine() {
  const rgbdslam::EvalOptions defaults;
  rgbdslam::CommandLine cli(
      "slam-eval",
      "Evaluates an estimated trajectory against ground truth, both in TUM format ('t tx ty tz qx\n"
      "qy qz qw' per line, t in s, position in m, T_w_c). Each estimated pose is associated\n"
      "one-to-one with the ground-truth pose nearest in time, the estimate is aligned to the "
      "ground\n"
      "truth (Umeyama), and ATE [m] and RPE per second and per metre [m, deg] are printed as\n"
      "'key value' lines (ate_rmse_m, ate_mean_m, ate_median_m, ate_max_m, scale,\n"
      "rpe_per_s_trans_rmse_m, rpe_per_s_rot_rmse_deg, rpe_per_m_*, num_estimate, "
      "num_groundtruth,\n"
      "num_associated, coverage, alignment; the frame-to-frame error between consecutive posed\n"
      "frames after the alignment, f2f_median_m, f2f_max_m and its time f2f_max_t_s, and 'jumps',\n"
      "how many exceed --jump-threshold-m: the figure a flight controller feels). Works on files only: --lcm-url is accepted like\n"
      "in every process, and nothing is sent or received. Exit codes: 0 success, 1 evaluation or output failed, 2 bad arguments or\n"
      "input files.");
  cli.positional("GROUNDTRUTH", "ground-truth trajectory (TUM format)");
  cli.positional("TRAJ", "estimated trajectory (TUM format)");
  cli.flag("json", "print the results as JSON instead of 'key value' lines");
  cli.option("json-out", "FILE", "also write the JSON to FILE (default: none)");
  cli.option(
      "plot", "FILE.png",
      "write a 1200x600 PNG: top view in the ground truth's plane of largest extent, and the "
      "remaining axis over time (default: none)");
  cli.option("errors-out", "FILE.csv",
             "write each associated pose's time [s] and position error after alignment [m] "
             "(default: none)");
  cli.flag("similarity",
           "align with scale, rotation and translation (monocular runs); default: rigid (scale 1)");
  cli.option("max-dt", "S",
             "largest time difference [s] for associating an estimated pose with a "
             "ground-truth pose",
             formatDefault(defaults.max_dt_s));
  cli.option("rpe-delta-s", "S", "time step [s] of the per-second RPE",
             formatDefault(defaults.rpe_delta_s));
  cli.option("rpe-delta-m", "M", "travelled ground-truth distance [m] of the per-metre RPE",
             formatDefault(defaults.rpe_delta_m));
  cli.option("jump-threshold-m", "M", "frame-to-frame errors above this count as jumps (key 'jumps') [m]",
             formatDefault(defaults.jump_threshold_m));
  cli.option("frames", "N",
             "number of input frames, for coverage = num_associated / N "
             "(default: unknown, coverage null)");
  rgbdslam::addLcmUrlOption(cli);  // accepted for uniformity; slam-eval uses no network
  cli.option("frames-from", "RGB_TXT",
             "count the frames in a TUM rgb.txt instead of giving --frames");
  return cli;
}

Expected<double> positiveDouble(const rgbdslam::CommandLine& cli, const std::string& name) {
  auto value = cli.getDouble(name);
  if (!value) return value;
  if (!std::isfinite(*value) || *value <= 0.0) {
    return Error{"--" + name + ": expected a positive number, got '" + cli.get(name) + "'"};
  }
  return value;
}

// Reads the parsed command line into options; errors name the option.
Expected<CliOptions> readOptions(const rgbdslam::CommandLine& cli) {
  CliOptions options;
  options.groundtruth_path = cli.positionalValue(0);
  options.estimate_path = cli.positionalValue(1);
  options.print_json = cli.has("json");
  options.json_out = cli.get("json-out");
  options.plot_path = cli.get("plot");
  options.errors_out = cli.get("errors-out");
  options.frames_from = cli.get("frames-from");
  options.eval.similarity = cli.has("similarity");
  for (const auto& [name, field] : {std::pair{"max-dt", &options.eval.max_dt_s},
                                    std::pair{"rpe-delta-s", &options.eval.rpe_delta_s},
                                    std::pair{"rpe-delta-m", &options.eval.rpe_delta_m},
                                    std::pair{"jump-threshold-m", &options.eval.jump_threshold_m}}) {
    auto value = positiveDouble(cli, name);
    if (!value) return Error{value.error()};
    *field = *value;
  }
  if (cli.has("frames")) {
    if (cli.has("frames-from")) return Error{"--frames and --frames-from are mutually exclusive"};
    auto frames = cli.getInt("frames");
    if (!frames) return Error{frames.error()};
    if (*frames <= 0)
      return Error{"--frames: expected a positive whole number, got '" + cli.get("frames") + "'"};
    options.eval.num_frames = static_cast<size_t>(*frames);
  }
  return options;
}

// Number of frames listed in a TUM rgb.txt ("timestamp filename" lines, '#' comments).
Expected<size_t> countFrames(const std::string& rgb_txt) {
  std::ifstream file(rgb_txt);
  if (!file) return Error{rgb_txt + ": cannot open frame list"};
  size_t frames = 0;
  std::string line;
  for (int number = 1; std::getline(file, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    char* end = nullptr;
    std::strtod(line.c_str() + first, &end);
    if (end == line.c_str() + first) {
      return Error{rgb_txt + ":" + std::to_string(number) + ": expected 'timestamp filename'"};
    }
    ++frames;
  }
  if (frames == 0) return Error{rgb_txt + ": no frames listed"};
  return frames;
}

Expected<rgbdslam::Trajectory> loadTrajectory(const std::string& path) {
  auto trajectory = rgbdslam::readTumTrajectory(path);
  if (trajectory && trajectory->empty()) return Error{path + ": no poses in trajectory file"};
  return trajectory;
}

Status writeTextFile(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  if (!file) return Error{path + ": cannot write file"};
  return {};
}

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "slam-eval: %s\n", message.c_str());
  return code;
}

// Prints the result and writes the optional JSON file and plot.
int report(const CliOptions& options, const rgbdslam::Trajectory& groundtruth,
           const rgbdslam::Trajectory& estimate, const rgbdslam::EvalResult& result) {
  const std::string json = rgbdslam::toJson(result);
  std::fputs(options.print_json ? json.c_str() : rgbdslam::toKeyValueText(result).c_str(), stdout);
  // The paper's Table I: where the run ends, relative to where it started.
  if (const auto end = rgbdslam::endPointError(groundtruth, estimate, result.options.max_dt_s); end && !options.print_json) {
    std::fputs(rgbdslam::toKeyValueText(*end).c_str(), stdout);
  }
  if (!options.json_out.empty()) {
    if (Status written = writeTextFile(options.json_out, json); !written) {
      return fail(kExitEvalFailed, written.error());
    }
  }
  if (!options.errors_out.empty()) {
    std::string csv = "t_s,error_m\n";
    char line[64];
    for (const auto& pair : result.pairs) {
      const rgbdslam::Vec3 p_est = result.S_gt_est * estimate[pair.est_index].T_w_c.translation();
      const double error = (p_est - groundtruth[pair.gt_index].T_w_c.translation()).norm();
      std::snprintf(line, sizeof(line), "%.6f,%.6f\n", estimate[pair.est_index].t, error);
      csv += line;
    }
    if (Status written = writeTextFile(options.errors_out, csv); !written) {
      return fail(kExitEvalFailed, written.error());
    }
  }
  if (!options.plot_path.empty()) {
    if (Status plotted =
            rgbdslam::writeTrajectoryPlot(options.plot_path, groundtruth, estimate, result);
        !plotted) {
      return fail(kExitEvalFailed, plotted.error());
    }
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  rgbdslam::CommandLine cli = makeCommandLine();
  if (Status parsed = cli.parse(argc, argv); !parsed) return fail(kExitBadInput, parsed.error());
  if (cli.helpRequested()) {
    std::fputs(cli.helpText().c_str(), stdout);
    return kExitOk;
  }
  auto options = readOptions(cli);
  if (!options) return fail(kExitBadInput, options.error() + " (see --help)");
  if (!options->frames_from.empty()) {
    auto frames = countFrames(options->frames_from);
    if (!frames) return fail(kExitBadInput, frames.error());
    options->eval.num_frames = *frames;
  }
  const auto groundtruth = loadTrajectory(options->groundtruth_path);
  if (!groundtruth) return fail(kExitBadInput, groundtruth.error());
  const auto estimate = loadTrajectory(options->estimate_path);
  if (!estimate) return fail(kExitBadInput, estimate.error());

  const auto result = rgbdslam::evaluateTrajectory(*groundtruth, *estimate, options->eval);
  if (!result) return fail(kExitEvalFailed, result.error());
  return report(*options, *groundtruth, *estimate, *result);
}
