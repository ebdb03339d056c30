#include "rgbd-slam/batch_runner.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <iostream>

#include "common/frame_log.h"
#include "common/link_budget.h"
#include "common/map_start.h"
#include "common/process.h"
#include "common/source_factory.h"
#include "rgbdslam/camera/calibration_io.h"
#include "rgbdslam/eval/loop_audit.h"
#include "rgbdslam/eval/trajectory_eval.h"

namespace rgbdslam {
namespace {

constexpr long kProgressEveryFrames = 100;  // progress line period when not on a terminal

bool hasPose(TrackResult::Status status) {
  return status == TrackResult::Status::kInitialised || status == TrackResult::Status::kTracked ||
         status == TrackResult::Status::kRelocalised;
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The map to start from; none without --load-map.
Expected<std::optional<LoadedMap>> startMapIfAsked(const BatchOptions& options, const PinholeCamera& camera,
                                                   double* load_ms) {
  if (options.load_map.empty()) return std::optional<LoadedMap>();
  const auto start = std::chrono::steady_clock::now();
  auto loaded = loadStartMap(options.load_map, camera, *parseSlamMode(options.config.slam->mode));
  if (!loaded) return Error{loaded.error()};
  *load_ms = msSince(start);
  return std::optional<LoadedMap>(std::move(*loaded));
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(q * (values.size() - 1))];
}

}  // namespace

Expected<BatchOptions> BatchOptions::fromCommandLine(const CommandLine& cli) {
  BatchOptions o;
  auto config = loadSlamConfig(cli);
  if (!config) return Error{config.error()};
  o.config = std::move(*config);
  if (cli.has("print-config")) return o;
  if (!cli.has("source")) return Error{"--source is required (see --help)"};
  if (!cli.has("output")) return Error{"--output is required (see --help)"};
  o.source = cli.get("source");
  o.camera_path = cli.has("camera") ? cli.get("camera") : "";
  o.output = cli.get("output");
  o.frame_log = cli.has("frame-log") ? cli.get("frame-log") : "";
  o.deterministic = cli.has("deterministic");
  o.quiet = cli.has("quiet");
  o.groundtruth_path = cli.has("groundtruth") ? cli.get("groundtruth") : "";
  auto max_frames = cli.getInt("max-frames", 0, std::numeric_limits<long>::max());
  if (!max_frames) return Error{max_frames.error()};
  o.max_frames = *max_frames;
  auto loss = cli.getDouble("link-loss");
  if (!loss || !(*loss >= 0.0 && *loss <= 1.0)) return Error{"--link-loss must be a fraction from 0 to 1"};
  auto delay = cli.getDouble("link-delay-ms");
  if (!delay || !(*delay >= 0.0 && *delay <= 60000.0)) return Error{"--link-delay-ms must be 0 to 60000 ms"};
  auto seed = cli.getInt("link-seed");
  if (!seed || *seed < 0 || *seed > 0xffffffffL) return Error{"--link-seed must be 0 to 4294967295"};
  o.link.loss = *loss, o.link.delay_ms = *delay, o.link.seed = static_cast<uint32_t>(*seed);
  if (o.link.imperfect() && !o.deterministic) return Error{"--link-loss and --link-delay-ms need --deterministic"};
  o.save_map = cli.has("save-map") ? cli.get("save-map") : "";
  o.load_map = cli.has("load-map") ? cli.get("load-map") : "";
  o.localise_only = cli.has("localise-only");
  if (o.localise_only && o.load_map.empty()) return Error{"--localise-only needs --load-map FILE (the map to localise in)"};
  const TrackerProcessOptions& node = o.config.procs->tracker_node;
  const std::vector<KeyframeEncoding> ladder = encodingLadder(node.bestEncoding(), node.link_budget.min_jpeg_quality);
  const auto rungs = static_cast<long>(ladder.size());
  auto rung = cli.getInt("keyframe-rung", -1, rungs - 1);
  if (!rung) return Error{rung.error() + " (this configuration's ladder has " + std::to_string(rungs) + " rungs)"};
  o.keyframe_rung = static_cast<int>(*rung);
  if (o.keyframe_rung >= 0) o.keyframe_encoding = ladder[static_cast<size_t>(o.keyframe_rung)];
  // Found out at the start, not after the whole run.
  const std::filesystem::path save_dir = std::filesystem::path(o.save_map).parent_path();
  if (!o.save_map.empty() && !save_dir.empty() && !std::filesystem::is_directory(save_dir)) {
    return Error{"the folder of --save-map " + o.save_map + " does not exist"};
  }
  return o;
}

Expected<std::unique_ptr<BatchRunner>> BatchRunner::create(BatchOptions options) {
  PinholeCamera camera;
  std::optional<PinholeCamera> given;
  if (!options.camera_path.empty()) {
    auto loaded = loadCamera(options.camera_path);
    if (!loaded) return Error{loaded.error()};
    camera = *loaded;
    given = camera;
  } else {
    auto spec = parseSourceSpec(options.source);
    if (!spec) return Error{"--source: " + spec.error()};
    if (spec->kind != "synth") return Error{"--camera is required for " + spec->kind + ": sources (see --help)"};
    auto synthetic = syntheticCamera(options.source);
    if (!synthetic) return Error{"--source " + options.source + ": " + synthetic.error()};
    camera = *synthetic;
  }
  auto source = openSource(options.source, given);
  if (!source) return Error{source.error()};
  std::optional<Trajectory> groundtruth;
  if (!options.groundtruth_path.empty()) {
    auto read = readTumTrajectory(options.groundtruth_path);
    if (!read) return Error{read.error()};
    groundtruth = *read;
  } else {
    groundtruth = groundTruthFor(options.source);
  }
  FrameLog frame_log;
  if (!options.frame_log.empty()) {
    auto opened = FrameLog::open(options.frame_log);
    if (!opened) return Error{opened.error()};
    frame_log = std::move(*opened);
  }
  double load_ms = 0.0;
  auto start_map = startMapIfAsked(options, camera, &load_ms);
  if (!start_map) return Error{start_map.error()};
  const LoadedMap* loaded = *start_map ? &**start_map : nullptr;
  auto runner = std::unique_ptr<BatchRunner>(
      new BatchRunner(std::move(options), camera, std::move(*source), std::move(groundtruth), loaded));
  runner->map_load_ms_ = load_ms;
  runner->frame_log_ = std::move(frame_log);
  return runner;
}

BatchRunner::BatchRunner(BatchOptions options, PinholeCamera camera,
                         std::unique_ptr<FrameSource> source, std::optional<Trajectory> groundtruth,
                         const LoadedMap* start_map)
    : options_(std::move(options)), camera_(std::move(camera)), source_(std::move(source)),
      groundtruth_(std::move(groundtruth)) {
  std::cerr << "rgbd-slam: " << source_->describe() << ", camera " << camera_.name << ", "
            << (options_.deterministic ? "deterministic" : "concurrent mapper") << "\n"
            << "configuration:\n" << options_.config.registry->describe();
  if (start_map) {
    std::cerr << "rgbd-slam: starting from " << options_.load_map << " (" << start_map->keyframes.size()
              << " keyframes, " << start_map->points.size() << " points)"
              << (options_.localise_only ? ", localising only" : "") << "\n";
  }
  const auto start = std::chrono::steady_clock::now();
  SlamStart slam_start{start_map, options_.localise_only, {}};
  if (options_.keyframe_rung >= 0) {
    slam_start.keyframe_wire = [this](const KeyframeData& k) { return throughWire(k, options_.keyframe_encoding); };
  }
  slam_ = std::make_unique<SlamSystem>(camera_, *options_.config.slam, options_.deterministic, options_.link,
                                       slam_start);
  map_start_ms_ = msSince(start);
}

// The keyframe as rgbd-mapper would decode it from rgbd-tracker's message (re-sends over a
// lossy simulated link are encoded and counted again, as on the radio). A message that
// does not decode is counted and reported, and the keyframe goes on as it was: a codec
// fault must show in the figures, not end the run.
KeyframeData BatchRunner::throughWire(const KeyframeData& keyframe, const KeyframeEncoding& encoding) {
  const rgbdslam::keyframe_t message = toLcm(keyframe, encoding);
  ++wire_keyframes_;
  wire_bytes_ += message.getEncodedSize();
  Expected<KeyframeData> decoded = fromLcm(message);
  if (decoded) return std::move(*decoded);
  if (wire_errors_++ == 0) std::cerr << "rgbd-slam: keyframe " << keyframe.id << " does not decode: " << decoded.error() << "\n";
  return keyframe;
}

void BatchRunner::showProgress(const TrackResult& result, bool final_line) {
  const SlamStats stats = slam_->stats();
  const bool tty = isatty(STDERR_FILENO);
  if (options_.quiet || (!tty && !final_line && stats.frames % kProgressEveryFrames != 0)) return;
  char line[200];
  std::snprintf(line, sizeof(line), "frame %ld  keyframes %ld  lost %ld  points %d  %.1f ms",
                stats.frames, stats.keyframes, stats.lost_frames, result.pose.points_tracked,
                result.track_ms);
  std::cerr << (tty ? "\r" : "") << line << (tty && !final_line ? "" : "\n") << std::flush;
}

int BatchRunner::run(const std::atomic<bool>& stop) {
  if (const Status& store = slam_->tracker().keyframeStoreStatus(); !store) {
    std::cerr << "rgbd-slam: " << store.error() << "\n";
    return 2;
  }
  warnIfStoreInMemory("rgbd-slam", slam_->tracker().keyframeStore());
  Trajectory trajectory;
  TrackResult last;
  long frames = 0;
  const auto run_start = std::chrono::steady_clock::now();
  while (!stop && (options_.max_frames == 0 || frames < options_.max_frames)) {
    FrameResult input = source_->next();
    if (input.status == FrameResult::Status::kEnd) break;
    if (input.status == FrameResult::Status::kFailed) {
      std::cerr << "\nrgbd-slam: error: " << input.error << "\n";
      ++bad_frames_;
      break;
    }
    if (input.status == FrameResult::Status::kBadFrame) {
      std::cerr << "\nrgbd-slam: error: " << input.error << " (frame skipped)\n";
      ++bad_frames_;
      continue;
    }
    ++frames;
    last = slam_->process(input.frame);
    track_ms_.push_back(last.track_ms);
    frame_log_.write(last, last.new_keyframe.has_value());
    if (last.status == TrackResult::Status::kBadFrame) {
      std::cerr << "\nrgbd-slam: error: frame " << input.frame.seq << ": " << last.error << "\n";
      ++bad_frames_;
    }
    if (last.status != TrackResult::Status::kBadFrame) ++state_frames_[last.pose.state];
    inconsistent_frames_ += last.inconsistent;
    max_correction_m_ = std::max(max_correction_m_, last.correction_m);
    depth_aided_frames_ += last.depth_aided;
    new_parts_ += last.new_part;
    if (hasPose(last.status) && first_pose_ms_ < 0) {
      first_pose_frame_ = frames;
      first_pose_ms_ = msSince(run_start);
    }
    if (hasPose(last.status)) {
      trajectory.push_back({last.pose.utime * 1e-6, last.pose.T_w_c});
      map_trajectory_.push_back({last.pose.utime * 1e-6, last.pose.map_T_w_c});
      part_trajectories_[last.pose.part].push_back({last.pose.utime * 1e-6, last.pose.map_T_w_c});
      anchored_.push_back({last.pose.utime * 1e-6, last.anchor, last.T_anchor_c, last.pose.part, last.pose.map_T_w_c});
      pose_states_.push_back(last.pose.state);
    }
    if (const std::string event = loss_.update(last); !event.empty()) {
      std::cerr << "\nrgbd-slam: " << event << "\n";
    }
    if (slam_->tracker().rejoins() > rejoins_) {
      rejoins_ = slam_->tracker().rejoins();
      std::cerr << "\nrgbd-slam: frame " << last.pose.seq << ": back in a part of the map it had left\n";
    }
    showProgress(last, false);
  }
  slam_->finish();
  showProgress(last, true);
  const Status written = writeTumTrajectory(options_.output, trajectory);
  if (!written) std::cerr << "rgbd-slam: error: " << written.error() << "\n";
  const bool saved = saveMapIfAsked();
  printSummary(trajectory);
  return (!written || !saved || bad_frames_ > 0) ? 1 : 0;
}

bool BatchRunner::saveMapIfAsked() {
  if (options_.save_map.empty()) return true;
  const auto start = std::chrono::steady_clock::now();
  const Status saved = saveMap(slam_->mapper().map(), camera_, *parseSlamMode(options_.config.slam->mode),
                               options_.save_map);
  map_save_ms_ = msSince(start);
  if (!saved) {
    std::cerr << "rgbd-slam: error: " << saved.error() << "\n";
    return false;
  }
  std::error_code error;
  map_saved_bytes_ = static_cast<long>(std::filesystem::file_size(options_.save_map, error));
  return true;
}

void BatchRunner::printMapFileSummary() const {
  if (!options_.load_map.empty()) {
    std::printf("map_load_ms %.1f\nmap_start_ms %.1f\nfirst_pose_frame %ld\nfirst_pose_ms %.1f\n", map_load_ms_,
                map_start_ms_, first_pose_frame_, first_pose_ms_);
  }
  if (!options_.save_map.empty()) std::printf("map_saved_bytes %ld\nmap_save_ms %.1f\n", map_saved_bytes_, map_save_ms_);
}

// Each posed frame in the map as it ends: its anchor keyframe's final pose times the pose
// relative to it then (as ORB-SLAM2 writes its camera trajectory), so loop closures and joins
// made after the frame count. A frame whose anchor was culled goes with the nearest frame
// within kFinalMapReach frames, tracked in the same part, whose anchor stayed, by the relative
// pose the map gave the two then; farther, it is left out (counted).
Trajectory BatchRunner::finalMapTrajectory(long* left_out) const {
  constexpr long kFinalMapReach = 300;  // [frames]
  const Map& map = slam_->mapper().map();
  const long n = static_cast<long>(anchored_.size());
  std::vector<std::optional<SE3>> direct(anchored_.size());
  for (long i = 0; i < n; ++i) {
    const Keyframe* kf = anchored_[i].anchor >= 0 ? map.keyframe(anchored_[i].anchor) : nullptr;
    if (kf) direct[i] = kf->T_w_c * anchored_[i].T_anchor_c;
  }
  Trajectory out;
  *left_out = 0;
  for (long i = 0; i < n; ++i) {
    std::optional<SE3> pose = direct[i];
    for (long d = 1; !pose && d <= kFinalMapReach; ++d) {
      for (const long j : {i - d, i + d}) {
        if (j < 0 || j >= n || !direct[j] || anchored_[j].part != anchored_[i].part) continue;
        pose = *direct[j] * anchored_[j].map_T_w_c.inverse() * anchored_[i].map_T_w_c;
        break;
      }
    }
    if (pose) out.push_back({anchored_[i].t_s, *pose});
    else ++*left_out;
  }
  return out;
}

void BatchRunner::printSummary(const Trajectory& trajectory) const {
  const SlamStats stats = slam_->stats();
  std::printf("frames %ld\nposes %zu\nkeyframes %ld\nmap_points %ld\nlost_frames %ld\nbad_frames %ld\n",
              stats.frames, trajectory.size(), stats.keyframes, stats.points, stats.lost_frames, bad_frames_);
  std::printf("keyframe_sends %ld\nmaps_applied %ld\nmaps_missing_delta %ld\nmaps_stale %ld\nsnapshots %ld\nlink_lost %ld\n",
              stats.keyframe_sends, stats.maps_applied, stats.maps_missing_delta, stats.maps_stale,
              stats.snapshots, stats.link_lost);
  std::printf("lost_episodes %ld\nrelocalisations %ld\n", loss_.episodes(), loss_.relocalisations());
  std::printf("tracker_points %zu\ntracker_points_on_storage %zu\n", slam_->tracker().numPoints(),
              slam_->tracker().pointsOnStorage());
  if (options_.keyframe_rung >= 0) {
    std::printf("keyframe_rung %d\nkeyframe_wire_kb_mean %.1f\nkeyframe_wire_errors %ld\n", options_.keyframe_rung,
                wire_keyframes_ > 0 ? static_cast<double>(wire_bytes_) / wire_keyframes_ / 1000.0 : 0.0, wire_errors_);
  }
  for (TrackingState state : {TrackingState::kInitialising, TrackingState::kTracking, TrackingState::kDodgy,
                              TrackingState::kLost, TrackingState::kRelocalised}) {
    const auto it = state_frames_.find(state);
    std::printf("frames_%s %ld\n", toString(state), it == state_frames_.end() ? 0L : it->second);
  }
  std::printf("frames_inconsistent %ld\n", inconsistent_frames_);
  std::printf("frames_depth_aided %ld\n", depth_aided_frames_);
  std::printf("lost_frames_reckoned %ld\n", slam_->tracker().framesReckoned());
  std::printf("new_parts %ld\nparts_rejoined %ld\n", new_parts_, slam_->tracker().rejoins());
  std::printf("map_correction_max_m %.4f\n", max_correction_m_);
  printLoopClosures(slam_->mapper().loopClosures());  // the mapper has finished
  printMapParts(slam_->mapper().parts());
  printAnchors(slam_->mapper().anchors());
  std::printf("keyframes_culled %ld\nkeyframes_in_map %zu\n", slam_->mapper().keyframesCulled(),
              slam_->mapper().map().numKeyframes());
  printKeyframesKept(slam_->mapper().keyframesKept());
  if (loss_.lost()) std::printf("lost_at_end_since_frame %ld\n", loss_.lostSinceSeq());
  printMapFileSummary();
  printPeakRss();
  std::printf("track_ms_median %.3f\ntrack_ms_p95 %.3f\ntrack_ms_p99 %.3f\ntrack_ms_max %.3f\n", percentile(track_ms_, 0.5),
              percentile(track_ms_, 0.95), percentile(track_ms_, 0.99), percentile(track_ms_, 1.0));
  if (!groundtruth_) {
    std::printf("ate_rmse_m unknown (no ground truth)\n");
    return;
  }
  // Each recognised place's loop edge against the truth: wrong closures (eval/loop_audit.h).
  const LoopAuditOptions audit;
  const auto& recognised = slam_->mapper().loopsRecognised();
  std::printf("%s", toKeyValueText(auditLoops(*groundtruth_, recognised, audit), audit).c_str());
  std::printf("loop_audit_past_cap %ld\n",  // recognised after LoopCloser::kMaxRecognisedKept: not audited
              slam_->mapper().loopClosures().recognised - static_cast<long>(recognised.size()));
  EvalOptions eval;
  eval.num_frames = static_cast<size_t>(stats.frames);
  auto result = evaluateTrajectory(*groundtruth_, trajectory, eval);
  if (!result) {
    std::printf("ate_rmse_m unknown (%s)\n", result.error().c_str());
    return;
  }
  std::printf("%s", toKeyValueText(*result).c_str());
  // The map pose as it was at each frame (a correction taken in at once, tracker.h's
  // map_T_w_c): what the published pose converges to.
  if (const auto map_result = evaluateTrajectory(*groundtruth_, map_trajectory_, eval)) {
    std::printf("ate_map_pose_rmse_m %.6f\n", map_result->ate_m.rmse);
  }
  // The map as it ends, loops closed and parts joined: what the run's map says each pose was.
  long left_out = 0;
  const Trajectory final_map = finalMapTrajectory(&left_out);
  if (const auto final_result = evaluateTrajectory(*groundtruth_, final_map, eval)) {
    std::printf("ate_final_map_rmse_m %.6f\n", final_result->ate_m.rmse);
  }
  std::printf("final_map_poses %zu\nfinal_map_left_out %ld\n", final_map.size(), left_out);
  // The final map's keyframes alone (rgbd-mapper --keyframes-out in a split run), all parts
  // under one alignment: metres while a part is unjoined (map_parts says how many).
  if (const auto keyframes = evaluateTrajectory(*groundtruth_, keyframeTrajectory(slam_->mapper().map()), EvalOptions{})) {
    std::printf("ate_keyframes_rmse_m %.6f\nkeyframes_evaluated %zu\n", keyframes->ate_m.rmse, keyframes->num_associated);
  }
  // Each part of the map on its own (map poses of the frames tracked in it, each part aligned
  // alone): how right the poses are where they are, whatever a part's guessed start.
  if (part_trajectories_.size() > 1) {
    for (const auto& [part, poses] : part_trajectories_) {
      EvalOptions alone;
      const auto part_result = evaluateTrajectory(*groundtruth_, poses, alone);
      std::printf("part_%ld_poses %zu\npart_%ld_ate_rmse_m %s\n", static_cast<long>(part), poses.size(),
                  static_cast<long>(part), part_result ? std::to_string(part_result->ate_m.rmse).c_str() : "unknown");
    }
  }
  // The jumps a flight controller would have followed: reported as tracking (good).
  long jumps_tracking = 0;
  for (size_t k : result->jump_pairs) {
    if (pose_states_[result->pairs[k].est_index] == TrackingState::kTracking) ++jumps_tracking;
  }
  std::printf("jumps_while_tracking %ld\n", jumps_tracking);
  // The paper's Table I: where the run ends, relative to where it started (as slam-eval).
  if (const auto end = endPointError(*groundtruth_, trajectory, eval.max_dt_s)) {
    std::printf("%s", toKeyValueText(*end).c_str());
  }
}

}  // namespace rgbdslam
