#include "rgbd-tracker/tracker_node.h"

#include <poll.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <utility>

#include "common/process.h"

namespace rgbdslam {
namespace {

constexpr int kLoopTimeoutMs = 20;  // [ms] longest wait for a message between timer checks
constexpr int kEncodingPollMs = 1;  // [ms] the same while a keyframe is being encoded (1-5 ms)
constexpr int kMaxHandlePerLoop = 64;  // messages handled before tracking the newest frame
// Map versions received while frames wait: applied once no frame waits (map versions come
// about once a keyframe and once a second), or after waiting this long, so that a tracker
// that stays behind still takes them (and acknowledges keyframes) within a few frames.
constexpr double kMaxMapWaitMs = 100.0;
// ...and when this many wait, the oldest is applied as the next arrives: a flood of map
// messages holds no more than this many decoded.
constexpr size_t kMaxPendingMaps = 8;
// With tracker_node.defer_cold_map_work, a map version's work on cold keyframes' points is
// held back (Tracker::applyMap) and done this many entries at a time (median 0.02-0.05 ms, at most 0.2 ms, on the benchmark)
// while no frame waits: a snapshot or a join's cull took 6-52 ms in one block between frames
// on the 10-minute flight.
constexpr size_t kDeferredMapEntries = 200;

double msBetween(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

int64_t steadyUs(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::microseconds>(t.time_since_epoch()).count();
}

bool elapsed(std::chrono::steady_clock::time_point since, std::chrono::steady_clock::time_point now,
             double period_s) {
  return since == std::chrono::steady_clock::time_point{} || msBetween(since, now) >= period_s * 1000;
}

bool hasPose(TrackResult::Status status) {
  return status == TrackResult::Status::kInitialised || status == TrackResult::Status::kTracked ||
         status == TrackResult::Status::kRelocalised;
}

// Keyframes of the local map that keep their pyramid (tracking/map_replica.h).
int64_t hotKeyframes(const Map& map) {
  int64_t hot = 0;
  for (const auto& [id, keyframe] : map.keyframes()) hot += keyframe->cold() ? 0 : 1;
  return hot;
}

}  // namespace

TrackerNode::TrackerNode(lcm::LCM* local, lcm::LCM* link, const PinholeCamera& camera,
                         const TrackerOptions& tracker_options, SlamMode mode, int64_t map_id,
                         TrackerNodeOptions options)
    : local_(local), link_(link), options_(std::move(options)),
      tracker_(camera, tracker_options, mode, map_id), map_id_(map_id),
      sync_(map_id, options_.sync.outbox), budget_(options_.process.link_budget),
      ladder_(encodingLadder(options_.process.bestEncoding(), options_.process.link_budget.min_jpeg_quality)),
      passed_(options_.process.follow_passed_frames) {
  if (tracker_options.local_map.store_dir.empty()) return;  // all in memory
  Expected<std::unique_ptr<KeyframeStore>> store = KeyframeStore::open(tracker_options.local_map.store_dir);
  if (!store) {
    std::cerr << "rgbd-tracker: warning: unacknowledged keyframes stay in memory: " << store.error() << "\n";
    return;
  }
  outbox_store_ = std::move(*store);
  outbox_spill_ = std::make_unique<StoreSpill>(outbox_store_.get());
  sync_.setSpill(outbox_spill_.get());
}

void TrackerNode::startFrom(const LoadedMap& map, bool localise_only) {
  tracker_.load(map, !localise_only);
  sync_.startAfter(map.nextKeyframeId());
}

int TrackerNode::run(const std::atomic<bool>& stop) {
  // tracker_node.realtime_priority: LCM's receive threads start with the first subscriptions
  // and carry every frame and map to this thread, so they inherit SCHED_FIFO; the threads
  // started after them (encoder, keyframe worker) run at the normal priority.
  const int priority = options_.process.realtime_priority;
  if (priority > 0) {
    if (Status set = setRealtimePriority(priority, /*reset_on_fork=*/false); !set) {
      std::cerr << "rgbd-tracker: warning: tracking at the normal priority: " << set.error() << "\n";
    }
  }
  auto frames = subscribeRaw(local_, options_.channels.frame, this, &TrackerNode::onFrame);
  auto maps = subscribeRaw(link_, options_.channels.map, this, &TrackerNode::onMap);
  if (priority > 0 && realtimePriority() == priority) (void)setRealtimePriority(priority, /*reset_on_fork=*/true);
  Clock::time_point finishing_since{};  // when the frames stopped; epoch: they have not
  while (!stop) {
    handleAvailable(encoding_.empty() ? kLoopTimeoutMs : kEncodingPollMs);
    const auto now = Clock::now();
    budget_.refill(steadyUs(now));
    sendEncoded(now);
    resendDue();
    if (elapsed(last_receipt_, now, options_.sync.receipt_period_s)) {
      last_receipt_ = now;
      publishReceipt();
    }
    if (elapsed(last_status_, now, options_.process.status_period_s)) {
      last_status_ = now;
      publishStatus();
    }
    if (options_.process.exit_after_idle_s <= 0 || counters_.frames == 0) continue;
    if (msBetween(last_frame_, now) < options_.process.exit_after_idle_s * 1000) {
      finishing_since = Clock::time_point{};
      continue;
    }
    if (finishing_since == Clock::time_point{}) {
      // A frame that took longer than the idle time (a stall of this loop) is not the
      // source's silence: what arrived meanwhile is read first. A 3.9-4.5 s stall once ended
      // a run's tracker 175 frames before its source did. (Once finishing, ack_wait_s bounds
      // the wait whatever arrives.)
      if (!backlog_.empty() || pollSockets(0, nullptr)) continue;
      finishing_since = now;
    }
    if (relocalising()) continue;  // its keyframe, if any, is still to be sent
    if ((sync_.outbox().empty() && encoding_.empty()) || msBetween(finishing_since, now) >= options_.process.ack_wait_s * 1000) break;
  }
  collectRelocalisation(/*wait=*/true);
  while (!pending_maps_.empty()) applyOldestMap();  // their acknowledgements count
  publishStatus();
  return sync_.outbox().empty() && encoding_.empty() ? 0 : 1;
}

// Handles everything that has arrived (frames into the backlog, map versions decoded and
// queued), then tracks the oldest frame of the backlog; map versions are applied when no
// frame waits, or once they have waited kMaxMapWaitMs (issue 10, item 6: a frame does not
// wait for a map update); with tracker_node.defer_cold_map_work their work on cold keyframes
// is held back and done kDeferredMapEntries at a time while no frame waits.
void TrackerNode::handleAvailable(int timeout_ms) {
  for (int round = 0; round < kMaxHandlePerLoop; ++round) {
    // Work held back from a map version goes on at once (not while the relocaliser thread
    // holds the tracker: the loop would only spin).
    const bool wait = round == 0 && backlog_.empty() && !(deferred_map_work_ && !relocalising());
    std::array<bool, 2> readable{};
    if (!pollSockets(wait ? timeout_ms : 0, &readable)) break;
    if (readable[0]) local_->handle();
    if (readable[1]) link_->handle();
  }
  collectRelocalisation(/*wait=*/false);
  if (!backlog_.empty()) {
    Received received = std::move(backlog_.front());
    backlog_.pop_front();
    trackFrame(received);
    recycle(std::move(received.bytes));
  }
  const auto now = Clock::now();
  while (!pending_maps_.empty() && !relocalising() &&
         (backlog_.empty() || msBetween(pending_maps_.front().received, now) >= kMaxMapWaitMs)) {
    applyOldestMap();
  }
  // Freezing and thawing leave work too (the keyframe store's holes), map versions or not.
  if (!deferred_map_work_ && !relocalising()) deferred_map_work_ = tracker_.hasDeferredMapWork();
  if (deferred_map_work_ && backlog_.empty() && pending_maps_.empty() && !relocalising()) {
    const auto start = Clock::now();
    deferred_map_work_ = tracker_.applyDeferredMap(kDeferredMapEntries);
    map_deferred_ms_.add(msBetween(start, Clock::now()));
  }
}

bool TrackerNode::pollSockets(int timeout_ms, std::array<bool, 2>* readable) const {
  const int count = local_ == link_ ? 1 : 2;
  pollfd fds[2] = {{local_->getFileno(), POLLIN, 0}, {link_->getFileno(), POLLIN, 0}};
  const bool any = ::poll(fds, count, timeout_ms) > 0;
  if (readable) {
    (*readable)[0] = any && (fds[0].revents & POLLIN) != 0;
    (*readable)[1] = any && count == 2 && (fds[1].revents & POLLIN) != 0;
  }
  return any;
}

void TrackerNode::applyOldestMap() {
  const MapUpdate update = std::move(pending_maps_.front().update);
  pending_maps_.pop_front();
  applyMap(update);
}

void TrackerNode::onFrame(const lcm::ReceiveBuffer* buffer, const std::string& /*channel*/) {
  last_frame_ = Clock::now();
  while (static_cast<int>(backlog_.size()) >= options_.process.max_backlog_frames) {
    recycle(std::move(backlog_.front().bytes));
    backlog_.pop_front();  // overtaken before it was tracked
    ++counters_.frames_skipped;
  }
  const auto* data = static_cast<const uint8_t*>(buffer->data);
  std::vector<uint8_t> bytes;
  if (!spare_bytes_.empty()) {
    bytes = std::move(spare_bytes_.back());
    spare_bytes_.pop_back();
  }
  bytes.assign(data, data + buffer->data_size);  // within the spare's capacity: no allocation
  backlog_.push_back(Received{std::move(bytes), buffer->recv_utime});
}

// At most one spare a frame the backlog can hold, and the one being tracked.
void TrackerNode::recycle(std::vector<uint8_t>&& bytes) {
  if (static_cast<int>(spare_bytes_.size()) <= options_.process.max_backlog_frames) spare_bytes_.push_back(std::move(bytes));
}

void TrackerNode::trackFrame(const Received& received) {
  const std::string channel = options_.channels.frame;
  if (Status decoded = decodeFrame(received.bytes.data(), received.bytes.size(), &frame_msg_, &frame_); !decoded) {
    ++counters_.bad_frame_messages;
    std::cerr << "rgbd-tracker: ignoring a bad message on " << channel << ": " << decoded.error() << "\n";
    return;
  }
  const RgbdFrame& frame = frame_;
  ++counters_.frames;
  TrackResult result;
  bool pass = false;        // answered without tracking it
  bool answered = false;    // ...without the tracker (answerLost)
  bool relocalise = false;  // answered lost now, relocalised on the relocaliser thread
  if (relocalising()) {
    result = answerLost(frame, "passed: frame " + std::to_string(relocalising_frame_.seq) + " is being relocalised");
    if (result.status == TrackResult::Status::kLost) {  // not a bad frame
      ++frames_while_relocalising_;
      if (!following_.load(std::memory_order_acquire)) passed_.offer(frame);
    }
    pass = answered = true;
  } else if (options_.process.relocalise_off_frame_path && counters_.poses > 0 && tracker_.lost()) {
    // The first pose (a loaded map's too) is found in line. A bad frame returns below,
    // before a relocalisation starts.
    result = answerLost(frame, "relocalising on the relocaliser thread");
    relocalise = answered = true;
  } else {
    // Lost with a newer frame waiting: the newer one is relocalised, this one is passed
    // (Tracker::passLost): relocalisation takes longer than a frame on a large map, and each
    // frame queued behind it would wait as long again.
    pass = tracker_.lost() && !backlog_.empty();
    result = pass ? tracker_.passLost(frame) : tracker_.trackPose(frame);
  }
  result.pose.utime = frame.utime;
  result.pose.seq = frame.seq;
  const bool keyframe_in_pose = result.new_keyframe.has_value();
  if (keyframe_in_pose) sendKeyframe(std::move(*result.new_keyframe));  // frame 0's, or one left unfinished
  if (result.status == TrackResult::Status::kBadFrame) {
    ++counters_.bad_frames;
    std::cerr << "rgbd-tracker: frame " << frame.seq << " skipped: " << result.error << "\n";
    frame_log_.write(result, false);
    return;
  }
  if (pass) ++counters_.frames_passed;  // not tracked: not in the tracker's own time either
  else if (!relocalise) track_ms_.add(result.track_ms);  // a relocalisation's when it is done
  if (result.status == TrackResult::Status::kLost) ++counters_.lost;
  if (hasPose(result.status)) ++counters_.poses;
  if (result.status != TrackResult::Status::kBadFrame) ++state_frames_[static_cast<size_t>(result.pose.state)];
  counters_.inconsistent += result.inconsistent;
  counters_.depth_aided += result.depth_aided;
  counters_.new_parts += result.new_part;
  state_ = result.pose.state;
  if (const std::string event = loss_.update(result); !event.empty()) {
    std::cerr << "rgbd-tracker: " << event << "\n";
  }
  const int64_t now_us = utimeNow();  // the pose's publication (within microseconds)
  result.pose.latency_ms = (now_us - frame.utime) * 1e-3;
  const rgbdslam::pose_t pose = toLcm(result.pose, map_id_);
  local_->publish(options_.channels.pose, &pose);
  last_published_ = result.pose;
  latency_ms_.add(result.pose.latency_ms);
  arrival_ms_.add((received.recv_utime - frame.utime) * 1e-3);
  frame_ms_.add((now_us - received.recv_utime) * 1e-3);
  if (answered) {  // the tracker has nothing to finish, and may be the relocaliser's
    frame_log_.write(result, keyframe_in_pose, FrameLog::Times{0.0, result.pose.latency_ms});
    if (relocalise) {
      // The frame is answered: map versions waiting go in now, while the tracker is this
      // thread's (else, lost, they would wait for a poll that finds no relocalisation running),
      // and the work held back from them (a lost tracker may relocalise for a long time).
      while (!pending_maps_.empty()) applyOldestMap();
      if (deferred_map_work_) deferred_map_work_ = tracker_.applyDeferredMap(SIZE_MAX);
      startRelocalisation();
    }
    return;
  }
  // After the pose is out: the keyframe, the local map (tracker.h, trackPose).
  const auto start = Clock::now();
  std::optional<KeyframeData> keyframe = tracker_.finishFrame(/*real_time=*/true);
  const double after_pose_ms = msBetween(start, Clock::now());
  after_pose_ms_.add(after_pose_ms);
  frame_log_.write(result, keyframe_in_pose || keyframe.has_value(), FrameLog::Times{after_pose_ms, result.pose.latency_ms});
  if (keyframe) sendKeyframe(std::move(*keyframe));
}

void TrackerNode::startRelocalisation() {
  std::swap(frame_, relocalising_frame_);
  frames_while_relocalising_ = 0;
  ++relocalisations_started_;
  // The frames passed during the last relocalisation first (their depth, in time order),
  // then this one.
  const size_t follow = passed_.size();
  frames_followed_ += static_cast<long>(follow);
  if (follow > 0) following_.store(true, std::memory_order_release);
  relocalisation_ = relocaliser_.submit([this, follow] {
    if (follow > 0) {
      const auto start = Clock::now();
      for (size_t i = 0; i < follow; ++i) tracker_.followLost(passed_.frame(i));
      followed_ms_ = msBetween(start, Clock::now());
      passed_.clear();
      following_.store(false, std::memory_order_release);
    }
    relocalised_ = tracker_.trackPose(relocalising_frame_);
    relocalised_keyframe_ = tracker_.finishFrame();
  });
}

void TrackerNode::collectRelocalisation(bool wait) {
  if (!relocalising()) return;
  if (!wait && relocalisation_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  const std::shared_future<void> done = std::exchange(relocalisation_, {});
  done.wait();
  // A job that threw while following left the flag set: its frames are not followed again.
  if (following_.exchange(false, std::memory_order_acq_rel)) passed_.clear();
  if (followed_ms_ >= 0.0) follow_ms_.add(std::exchange(followed_ms_, -1.0));
  done.get();  // the job's exception, if any, is this thread's now
  track_ms_.add(relocalised_.track_ms);
  relocalise_ms_.add(relocalised_.track_ms);
  if (relocalised_.new_keyframe) sendKeyframe(std::move(*relocalised_.new_keyframe));  // a new part's
  counters_.new_parts += relocalised_.new_part;
  if (relocalised_keyframe_) sendKeyframe(std::move(*relocalised_keyframe_));
  if (relocalised_.status == TrackResult::Status::kRelocalised) {
    ++relocalisations_recovered_;
    if (const std::string event = loss_.update(relocalised_); !event.empty()) {
      std::cerr << "rgbd-tracker: " << event << " (its pose not published: the next frame's is)\n";
    }
  } else {
    tracker_.countPassedFrames(frames_while_relocalising_);
    if (relocalised_.new_part) {
      if (const std::string event = loss_.update(relocalised_); !event.empty()) {
        std::cerr << "rgbd-tracker: " << event << " (its pose not published: the next frame's is)\n";
      }
    }
  }
  relocalised_ = TrackResult{};
  relocalised_keyframe_.reset();
  if (!tracker_.lost()) passed_.clear();  // back on the map or a new part: nothing to follow
}

void TrackerNode::readTrackerFigures() {
  const KeyframeStore* store = tracker_.keyframeStore();
  tracker_figures_ = TrackerFigures{static_cast<int64_t>(tracker_.numPoints()),
                                    static_cast<int64_t>(tracker_.pointsOnStorage()),
                                    tracker_.pointsLostOnStorage(),
                                    hotKeyframes(tracker_.map()),
                                    store ? static_cast<int64_t>(store->entries()) : 0,
                                    store ? store->bytes() / 1024 : 0,
                                    store ? store->diskBytes() / 1024 : 0,
                                    store ? store->errors() : 0};
}

TrackResult TrackerNode::answerLost(const RgbdFrame& frame, const std::string& reason) const {
  const auto start = Clock::now();
  TrackResult result;
  result.pose.state = TrackingState::kLost;
  result.pose.T_w_c = last_published_.T_w_c;
  result.pose.map_T_w_c = last_published_.map_T_w_c;
  result.pose.part = last_published_.part;
  result.pose.utime = frame.utime;
  result.pose.seq = frame.seq;
  result.error = tracker_.frameError(frame);
  if (result.error.empty()) {
    result.status = TrackResult::Status::kLost;
    result.lost_reason = reason;
  }
  result.track_ms = msBetween(start, Clock::now());
  return result;
}

// The rung is chosen now, from the bucket as it is; the encoding (JPEG, zlib, LCM: a few ms)
// runs on the encoder thread, and sendEncoded() sends it when it is done, in creation order.
void TrackerNode::sendKeyframe(KeyframeData keyframe) {
  const auto now = Clock::now();
  budget_.refill(steadyUs(now));
  const int rung = ladderRung(budget_.fill(), static_cast<int>(ladder_.size()));
  ++counters_.keyframes;
  counters_.keyframes_coarser += rung > 0;
  counters_.last_rung = rung;
  created_[keyframe.id] = now;
  const KeyframeId id = keyframe.id;
  const KeyframeEncoding encoding = ladder_[static_cast<size_t>(rung)];
  encoding_.push_back({id, encoder_.submit([keyframe = std::move(keyframe), encoding]() {
                         const auto start = Clock::now();
                         const rgbdslam::keyframe_t msg = toLcm(keyframe, encoding);
                         Encoded encoded;
                         encoded.bytes.resize(static_cast<size_t>(msg.getEncodedSize()));
                         msg.encode(encoded.bytes.data(), 0, static_cast<int>(encoded.bytes.size()));
                         encoded.ms = msBetween(start, Clock::now());
                         return encoded;
                       })});
}

// Keyframes whose encoding is done, oldest first: sent at once, whatever the budget's fill
// (link_budget.h: the budget chose their rung; a keyframe late at the mapper costs more).
void TrackerNode::sendEncoded(Clock::time_point now) {
  while (!encoding_.empty() &&
         encoding_.front().encoded.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    const KeyframeId id = encoding_.front().id;
    Encoded encoded = encoding_.front().encoded.get();
    encoding_.pop_front();
    encode_ms_.add(encoded.ms);
    counters_.keyframes_over_budget += !budget_.open();
    publishKeyframe(id, std::move(encoded.bytes), now);
  }
}

void TrackerNode::publishKeyframe(KeyframeId id, std::vector<uint8_t> bytes, Clock::time_point now) {
  publishKeyframeBytes(bytes);
  sync_.send(id, std::move(bytes), steadyUs(now));
}

void TrackerNode::publishKeyframeBytes(const std::vector<uint8_t>& bytes) {
  link_->publish(options_.channels.keyframe, bytes.data(), static_cast<unsigned>(bytes.size()));
  budget_.spend(bytes.size());
  ++counters_.keyframe_sends;
  counters_.keyframe_bytes += static_cast<long>(bytes.size());
}

// Re-sends are never held back by the budget (link_budget.h); they count against it.
void TrackerNode::resendDue() {
  for (const std::vector<uint8_t>* bytes : sync_.resendsDue(steadyUs(Clock::now()))) publishKeyframeBytes(*bytes);
}

void TrackerNode::onMap(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  budget_.refill(steadyUs(Clock::now()));
  budget_.received(buffer->data_size);  // it crossed the link, whatever it holds
  auto msg = decodeMessage<rgbdslam::map_t>(buffer->data, buffer->data_size);
  auto update = msg ? fromLcm(*msg) : Expected<MapUpdate>(Error{msg.error()});
  if (!update) {
    ++counters_.bad_map_messages;
    std::cerr << "rgbd-tracker: ignoring a bad message on " << channel << ": " << update.error() << "\n";
    return;
  }
  ++counters_.maps_received;
  if (pending_maps_.size() >= kMaxPendingMaps) {
    collectRelocalisation(/*wait=*/true);  // the tracker is this thread's again
    applyOldestMap();
  }
  pending_maps_.push_back({std::move(*update), Clock::now()});
}

void TrackerNode::applyMap(const MapUpdate& update) {
  const auto now = Clock::now();
  const MapReceiveResult r = sync_.receive(update, steadyUs(now), [this](const MapUpdate& u) {
    const auto start = Clock::now();
    const bool known = tracker_.applyMap(u, options_.process.defer_cold_map_work);
    deferred_map_work_ = options_.process.defer_cold_map_work;  // perhaps: the next applyDeferredMap() says
    map_apply_ms_.add(msBetween(start, Clock::now()));
    return known;
  });
  for (double age_s : r.ack_latencies_s) ack_ms_.add(age_s * 1000.0);
  const int64_t holding = sync_.follower().version();
  if (r.resent_after_loss > 0) {
    std::cerr << "rgbd-tracker: the mapper lost acknowledged keyframes (map version " << update.version
              << " acknowledges fewer); sending the " << r.resent_after_loss << " it still holds again\n";
  }
  switch (r.verdict) {
    case MapVerdict::kApply:
      ++counters_.maps_applied;
      if (r.unknown_keyframes) ++counters_.maps_unknown_keyframe;
      break;
    case MapVerdict::kStale:
      ++counters_.maps_stale;
      std::cerr << "rgbd-tracker: ignoring stale map version " << update.version << " (holding " << holding
                << "; a repeat, or from the past)\n";
      return;
    case MapVerdict::kMissingDelta:
      ++counters_.maps_missing_delta;
      std::cerr << "rgbd-tracker: map version " << update.version << " is a delta after a lost one (holding "
                << holding << "); waiting for a snapshot\n";
      return;
    case MapVerdict::kForeignMap:
      ++counters_.maps_foreign;
      std::cerr << "rgbd-tracker: ignoring map version " << update.version << " of map " << update.map_id
                << " (this tracker's map is " << map_id_ << ")\n";
      return;
    case MapVerdict::kImplausible:
      ++counters_.maps_implausible;
      std::cerr << "rgbd-tracker: ignoring map version " << update.version << ": implausible (more than "
                << MapFollower::kDefaultMaxVersionStep << " versions ahead of " << holding
                << ", or acknowledging keyframes below " << update.acked_below << " of which this tracker sent fewer)\n";
      return;
  }
  for (auto it = created_.begin(); it != created_.end() && it->first < update.acked_below; it = created_.erase(it)) {
    in_map_ms_.add(msBetween(it->second, now));
  }
}

void TrackerNode::publishReceipt() {
  const rgbdslam::map_receipt_t msg = toLcm(sync_.receipt(utimeNow()));
  link_->publish(options_.channels.receipt, &msg);
  budget_.spend(static_cast<size_t>(msg.getEncodedSize()));
}

void TrackerNode::publishStatus() {
  ComponentStatus status;
  status.utime = utimeNow();
  status.component = "rgbd-tracker";
  status.state = toString(state_);
  const Counters& c = counters_;
  const MemoryUsage memory = memoryUsage();
  if (!relocalising()) readTrackerFigures();  // else the relocaliser's: the last read
  const TrackerFigures& t = tracker_figures_;
  status.counters = {{"map_id", map_id_},
                     {"map_version", sync_.follower().version()},
                     {"map_version_newest_seen", sync_.follower().newestSeen()},
                     {"keyframes", c.keyframes},
                     {"keyframes_acked", keyframesAcked()},
                     {"keyframes_unacked", static_cast<int64_t>(keyframesUnacked())},
                     {"keyframes_unacked_stored", static_cast<int64_t>(sync_.outbox().spilled())},
                     {"keyframes_unacked_lost", sync_.outbox().spillErrors()},
                     {"keyframe_sends", c.keyframe_sends},
                     {"mapper_losses", sync_.mapperLosses()},
                     {"keyframe_bytes", c.keyframe_bytes},
                     {"link_bytes", budget_.bytesSent()},
                     {"keyframes_coarser", c.keyframes_coarser},
                     {"keyframes_encoding", static_cast<int64_t>(encoding_.size())},
                     {"keyframes_over_budget", c.keyframes_over_budget},
                     {"keyframe_rung", c.last_rung},
                     {"points", t.points},
                     {"points_on_storage", t.points_on_storage},
                     {"points_lost_on_storage", t.points_lost_on_storage},
                     {"keyframes_hot", t.keyframes_hot},
                     {"keyframe_store_entries", t.store_entries},
                     {"keyframe_store_kb", t.store_kb},
                     {"keyframe_store_disk_kb", t.store_disk_kb},
                     {"keyframe_store_errors", t.store_errors},
                     {"frames", c.frames},
                     {"frames_skipped", c.frames_skipped},
                     {"frames_passed", c.frames_passed},
                     {"poses", c.poses},
                     {"lost_frames", c.lost},
                     {"frames_tracking", state_frames_[static_cast<size_t>(TrackingState::kTracking)]},
                     {"frames_dodgy", state_frames_[static_cast<size_t>(TrackingState::kDodgy)]},
                     {"frames_relocalised", state_frames_[static_cast<size_t>(TrackingState::kRelocalised)]},
                     {"frames_inconsistent", c.inconsistent},
                     {"frames_depth_aided", c.depth_aided},
                     {"new_parts", c.new_parts},
                     {"lost_episodes", loss_.episodes()},
                     {"relocalisations", loss_.relocalisations()},
                     {"relocalisations_off_frame_path", relocalisations_started_},
                     {"relocalisations_off_frame_path_recovered", relocalisations_recovered_},
                     {"bad_frames", c.bad_frames},
                     {"bad_frame_messages", c.bad_frame_messages},
                     {"bad_map_messages", c.bad_map_messages},
                     {"maps_received", c.maps_received},
                     {"maps_applied", c.maps_applied},
                     {"maps_stale", c.maps_stale},
                     {"maps_foreign", c.maps_foreign},
                     {"maps_missing_delta", c.maps_missing_delta},
                     {"maps_unknown_keyframe", c.maps_unknown_keyframe},
                     {"maps_implausible", c.maps_implausible},
                     {"rss_kb", memory.rss_kb},
                     {"peak_rss_kb", memory.peak_rss_kb},
                     {"heap_kb", memory.heap_kb},
                     {"realtime_priority", realtimePriority()}};
  status.timings_ms = {{"track_ms_median", track_ms_.quantile(0.5)},
                       {"track_ms_p99", track_ms_.quantile(0.99)},
                       {"latency_ms_median", latency_ms_.quantile(0.5)},
                       {"latency_ms_p99", latency_ms_.quantile(0.99)},
                       {"arrival_ms_median", arrival_ms_.quantile(0.5)},
                       {"frame_ms_median", frame_ms_.quantile(0.5)},
                       {"frame_ms_p99", frame_ms_.quantile(0.99)},
                       {"relocalise_ms_median", relocalise_ms_.quantile(0.5)},
                       {"relocalise_ms_p99", relocalise_ms_.quantile(0.99)},
                       {"after_pose_ms_median", after_pose_ms_.quantile(0.5)},
                       {"after_pose_ms_max", after_pose_ms_.quantile(1.0)},
                       {"map_apply_ms_median", map_apply_ms_.quantile(0.5)},
                       {"map_apply_ms_max", map_apply_ms_.quantile(1.0)},
                       {"keyframe_encode_ms_median", encode_ms_.quantile(0.5)},
                       {"keyframe_encode_ms_max", encode_ms_.quantile(1.0)},
                       {"keyframe_ack_ms_median", ack_ms_.quantile(0.5)},
                       {"keyframe_ack_ms_max", ack_ms_.quantile(1.0)},
                       {"keyframe_in_map_ms_median", in_map_ms_.quantile(0.5)},
                       {"keyframe_in_map_ms_max", in_map_ms_.quantile(1.0)}};
  const rgbdslam::status_t msg = toLcm(status);
  link_->publish(options_.channels.tracker_status, &msg);
  budget_.spend(static_cast<size_t>(msg.getEncodedSize()));
}

void TrackerNode::printSummary() const {
  const Counters& c = counters_;
  // Key-value lines on stdout (for scripts), as rgbd-slam prints its summary.
  std::printf("frames_skipped %ld\nframes_passed %ld\n", c.frames_skipped, c.frames_passed);
  std::printf("lost_episodes %ld\nrelocalisations %ld\n", loss_.episodes(), loss_.relocalisations());
  for (TrackingState state : {TrackingState::kInitialising, TrackingState::kTracking, TrackingState::kDodgy,
                              TrackingState::kLost, TrackingState::kRelocalised}) {
    std::printf("frames_%s %ld\n", toString(state), state_frames_[static_cast<size_t>(state)]);
  }
  std::printf("relocalisations_off_frame_path %ld\nrelocalisations_off_frame_path_recovered %ld\n"
              "relocalise_ms_median %.3f\nrelocalise_ms_p99 %.3f\nrelocalise_ms_max %.3f\n",
              relocalisations_started_, relocalisations_recovered_, relocalise_ms_.quantile(0.5),
              relocalise_ms_.quantile(0.99), relocalise_ms_.quantile(1.0));
  std::printf("frames_inconsistent %ld\n", c.inconsistent);
  std::printf("frames_depth_aided %ld\n", c.depth_aided);
  std::printf("lost_frames_reckoned %ld\n", tracker_.framesReckoned());  // the relocaliser has stopped
  // Frames passed while relocalising handed to the dead reckoning (Tracker::followLost; those
  // it held count in lost_frames_reckoned, with the frames relocalised it held), and the
  // time each relocalisation's job took to follow them before relocalising.
  std::printf("passed_frames_followed %ld\nfollow_ms_median %.3f\nfollow_ms_p99 %.3f\nfollow_ms_max %.3f\n",
              frames_followed_, follow_ms_.quantile(0.5), follow_ms_.quantile(0.99), follow_ms_.quantile(1.0));
  std::printf("new_parts %ld\nparts_rejoined %ld\n", c.new_parts, tracker_.rejoins());  // the relocaliser has stopped
  if (const KeyframeStore* store = tracker_.keyframeStore()) {
    std::printf("keyframe_store_mb %.1f\nkeyframe_store_errors %ld\n", store->bytes() / 1048576.0,
                static_cast<long>(store->errors()));
  }
  std::printf("points %zu\npoints_on_storage %zu\npoints_lost_on_storage %lld\n", tracker_.numPoints(),
              tracker_.pointsOnStorage(), static_cast<long long>(tracker_.pointsLostOnStorage()));
  std::printf("frames %ld\nposes %ld\nlost_frames %ld\nbad_frames %ld\nbad_messages %ld\n", c.frames,
              c.poses, c.lost, c.bad_frames, c.bad_frame_messages + c.bad_map_messages);
  std::printf("keyframes %ld\nkeyframes_acked %ld\nkeyframes_unacked %zu\nkeyframes_unacked_lost %lld\n"
              "keyframe_sends %ld\nkeyframe_bytes %ld\n",
              c.keyframes, keyframesAcked(), keyframesUnacked(), static_cast<long long>(sync_.outbox().spillErrors()),
              c.keyframe_sends, c.keyframe_bytes);
  std::printf("link_budget_kbps %.0f\nlink_bytes %lld\nlink_bytes_received %lld\nkeyframes_coarser %ld\n"
              "keyframes_over_budget %ld\n",
              options_.process.link_budget.kbps, static_cast<long long>(budget_.bytesSent()),
              static_cast<long long>(budget_.bytesReceived()), c.keyframes_coarser, c.keyframes_over_budget);
  std::printf("map_version_newest_seen %lld\nmapper_losses %ld\n", static_cast<long long>(sync_.follower().newestSeen()),
              sync_.mapperLosses());
  std::printf("map_version %lld\nmaps_received %ld\nmaps_applied %ld\nmaps_stale %ld\nmaps_missing_delta %ld\nmaps_foreign %ld\n",
              static_cast<long long>(sync_.follower().version()), c.maps_received, c.maps_applied, c.maps_stale,
              c.maps_missing_delta, c.maps_foreign);
  std::printf("arrival_ms_median %.3f\nframe_ms_median %.3f\nframe_ms_p99 %.3f\n", arrival_ms_.quantile(0.5),
              frame_ms_.quantile(0.5), frame_ms_.quantile(0.99));
  std::printf("track_ms_median %.3f\ntrack_ms_p99 %.3f\nlatency_ms_median %.3f\nlatency_ms_p99 %.3f\n",
              track_ms_.quantile(0.5), track_ms_.quantile(0.99), latency_ms_.quantile(0.5), latency_ms_.quantile(0.99));
  std::printf("after_pose_ms_median %.2f\nafter_pose_ms_p99 %.2f\nafter_pose_ms_max %.2f\n", after_pose_ms_.quantile(0.5),
              after_pose_ms_.quantile(0.99), after_pose_ms_.quantile(1.0));
  std::printf("map_apply_ms_median %.2f\nmap_apply_ms_p99 %.2f\nmap_apply_ms_max %.2f\n", map_apply_ms_.quantile(0.5),
              map_apply_ms_.quantile(0.99), map_apply_ms_.quantile(1.0));
  std::printf("map_deferred_ms_median %.2f\nmap_deferred_ms_p99 %.2f\nmap_deferred_ms_max %.2f\n",
              map_deferred_ms_.quantile(0.5), map_deferred_ms_.quantile(0.99), map_deferred_ms_.quantile(1.0));
  std::printf("keyframe_encode_ms_median %.2f\nkeyframe_encode_ms_max %.2f\n", encode_ms_.quantile(0.5),
              encode_ms_.quantile(1.0));
  std::printf("keyframe_ack_ms_median %.1f\nkeyframe_ack_ms_max %.1f\nkeyframe_in_map_ms_median %.1f\nkeyframe_in_map_ms_max %.1f\n",
              ack_ms_.quantile(0.5), ack_ms_.quantile(1.0), in_map_ms_.quantile(0.5), in_map_ms_.quantile(1.0));
  printPeakRss();
  std::fflush(stdout);
}

}  // namespace rgbdslam
