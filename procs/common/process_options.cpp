#include "common/process_options.h"

#include "common/cli.h"

namespace rgbdslam {

void ChannelOptions::bind(OptionRegistry* r) {
  r->bindName("channels", "frame", &frame, "RGB-D frames from rgbd-capture (local bus)");
  r->bindName("channels", "pose", &pose, "poses from the tracker (local bus)");
  r->bindName("channels", "keyframe", &keyframe, "keyframes from the tracker to the mapper (link)");
  r->bindName("channels", "map", &map, "map versions from the mapper to the tracker (link)");
  r->bindName("channels", "receipt", &receipt, "the tracker's map receipts: the map version it holds (link)");
  r->bindName("channels", "tracker_status", &tracker_status, "the tracker's health reports (link)");
  r->bindName("channels", "mapper_status", &mapper_status, "the mapper's health reports");
}

void TrackerProcessOptions::bind(OptionRegistry* r) {
  const std::string s = "tracker_node";
  r->bind(s, "status_period_s", &status_period_s, 1e-3, kMaxPeriodS, "s", "health reports this often");
  // Each waiting frame is a decoded 640x480 frame (1.5 MB); 1000 would be 1.5 GB.
  r->bind(s, "max_backlog_frames", &max_backlog_frames, 1, 1000, "frames",
          "frames waiting to be tracked at most; a newer frame pushes out the oldest");
  r->bind(s, "exit_after_idle_s", &exit_after_idle_s, 0.0, kMaxPeriodS, "s",
          "finish when no frame came for this long (0: run until stopped)");
  r->bind(s, "ack_wait_s", &ack_wait_s, 0.0, kMaxPeriodS, "s",
          "when finishing, wait this long for keyframe acknowledgements");
  r->bind(s, "realtime_priority", &realtime_priority, 0, 99, "SCHED_FIFO priority",
          "run the tracking thread under SCHED_FIFO at this priority, so that a frame does not wait "
          "for a core while the mapper, the capture or other software runs (needs root, CAP_SYS_NICE "
          "or RLIMIT_RTPRIO; refused: a warning, normal priority); LCM's receive threads, which carry "
          "its frames, too; the encoder and keyframe worker at the normal priority (0: normal priority)");
  r->bind(s, "relocalise_off_frame_path", &relocalise_off_frame_path,
          "while lost, relocalise on a second thread: the frame being relocalised and those after it "
          "until it is done are answered lost at once, and the first frame after a relocalisation that "
          "worked is tracked from its pose (false: relocalise on the tracking thread, each relocalised "
          "frame's pose as late as its relocalisation; the first pose of a run, in a loaded map too, is "
          "always found in line)");
  r->bind(s, "follow_passed_frames", &follow_passed_frames, 0, 30, "frames",
          "while relocalising off the frame path, keep the depth of at most this many of the frames passed "
          "meanwhile (evenly spaced) for the tracker's dead reckoning (tracker.relocalise_dead_reckoning) to "
          "follow before the next relocalisation; each holds a depth image, 0.6 MB at 640x480 (0: the dead "
          "reckoning follows the frames relocalised only; off by default, process_options.h says why)");
  r->bind(s, "defer_cold_map_work", &defer_cold_map_work,
          "apply a map version's work on cold keyframes' points (and the keyframe store's holes for "
          "culled keyframes) in steps of 200 entries between frames, not in one block");
  r->bind(s, "keyframe_grey", &keyframe_encoding.jpeg_grey, {{"jpeg", true}, {"png", false}},
          "keyframe image on the link (png is lossless)");
  r->bind(s, "keyframe_jpeg_quality", &keyframe_encoding.jpeg_quality, 1, 100, "",
          "JPEG quality of keyframe images");
  r->bind(s, "keyframe_depth", &keyframe_encoding.depth_step, {{"full", 1}, {"half", 2}, {"quarter", 4}, {"eighth", 8}},
          "keyframe depth on the link: every pixel, or every 2nd, 4th or 8th pixel and row (the centre of each block)");
  r->bind(s, "keyframe_depth_near_corners", &keyframe_encoding.depth_near_corners,
          "keyframe depth on the link only near the image's FAST corners, where the mapper reads it, even with "
          "the link budget to spare (the budget's second rung does this anyway)");
  r->bind(s, "keyframe_depth_step_sigma", &keyframe_depth_step_sigma, 0.0, 2.0, "sigma",
          "keyframe depth on the link as inverse depth in steps of this fraction of the noise "
          "model's depth sigma (rounding adds 0.29 times it in sigma; 0: lossless zlib)");
  noise.bind(r);
  link_budget.bind(r, s);
}

void MapperProcessOptions::bind(OptionRegistry* r) {
  r->bind("mapper_node", "status_period_s", &status_period_s, 1e-3, kMaxPeriodS, "s",
          "health reports this often");
}

void ProcessOptions::bind(OptionRegistry* r) {
  channels.bind(r);
  tracker_node.bind(r);
  mapper_node.bind(r);
}

}  // namespace rgbdslam
