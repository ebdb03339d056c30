#include "common/openni2_source.h"

#include <OpenNI.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <deque>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

namespace rgbdslam {
namespace {

enum StreamIndex { kDepth = 0, kColour = 1, kStreamCount = 2 };
constexpr const char* kStreamName[kStreamCount] = {"depth", "colour"};
constexpr double kFallbackFps = 30.0;          // when a stream reports fps 0 [Hz]
constexpr size_t kMaxPendingPerStream = 4;     // unpaired frames kept per stream
constexpr const char* kDummyVendor = "Table Tennis";  // what OpenNI2's Dummy driver reports
// The Dummy driver stamps frame_index * 33 ms but sleeps 33 ms plus its work between frames,
// so its "clock" runs 1-3 % slow against the host's (measured here): its offset estimate
// may grow this fast, or utime would fall behind the host clock by that fraction of the run.
constexpr double kDummyClockDriftPpm = 50000.0;
constexpr float kPlayerManualSpeed = -1.0f;  // OpenNI2 playback speed: wait for triggers

int64_t hostNowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

using SteadyClock = std::chrono::steady_clock;

// OpenNI::getExtendedError() as one line (it starts with a tab and ends with newlines).
std::string openniError() {
  std::string text = openni::OpenNI::getExtendedError();
  std::replace(text.begin(), text.end(), '\t', ' ');
  std::replace(text.begin(), text.end(), '\n', ' ');
  const size_t first = text.find_first_not_of(' ');
  if (first == std::string::npos) return "no details from OpenNI2";
  const size_t last = text.find_last_not_of(' ');
  return text.substr(first, last - first + 1);
}

const char* pixelFormatName(openni::PixelFormat format) {
  switch (format) {
    case openni::PIXEL_FORMAT_DEPTH_1_MM: return "DEPTH_1_MM";
    case openni::PIXEL_FORMAT_DEPTH_100_UM: return "DEPTH_100_UM";
    case openni::PIXEL_FORMAT_SHIFT_9_2: return "SHIFT_9_2";
    case openni::PIXEL_FORMAT_SHIFT_9_3: return "SHIFT_9_3";
    case openni::PIXEL_FORMAT_RGB888: return "RGB888";
    case openni::PIXEL_FORMAT_YUV422: return "YUV422";
    case openni::PIXEL_FORMAT_GRAY8: return "GRAY8";
    case openni::PIXEL_FORMAT_GRAY16: return "GRAY16";
    case openni::PIXEL_FORMAT_JPEG: return "JPEG";
    case openni::PIXEL_FORMAT_YUYV: return "YUYV";
  }
  return "unknown pixel format";
}

// Raw depth units per metre, 0 for formats this source cannot use.
double depthUnitsPerMetre(openni::PixelFormat format) {
  if (format == openni::PIXEL_FORMAT_DEPTH_1_MM) return 1000.0;
  if (format == openni::PIXEL_FORMAT_DEPTH_100_UM) return 10000.0;
  return 0.0;
}

bool formatUsable(int stream, openni::PixelFormat format) {
  return stream == kDepth ? depthUnitsPerMetre(format) > 0.0
                          : format == openni::PIXEL_FORMAT_RGB888;
}

// Preference among usable formats: lower is better.
int formatRank(int stream, openni::PixelFormat format) {
  if (stream == kDepth) return format == openni::PIXEL_FORMAT_DEPTH_1_MM ? 0 : 1;
  return 0;
}

std::string modeText(const openni::VideoMode& mode) {
  std::ostringstream out;
  out << mode.getResolutionX() << "x" << mode.getResolutionY() << "@" << mode.getFps() << " "
      << pixelFormatName(mode.getPixelFormat());
  return out.str();
}

bool sameSize(const openni::VideoMode& a, const openni::VideoMode& b) {
  return a.getResolutionX() == b.getResolutionX() && a.getResolutionY() == b.getResolutionY();
}

bool endsWithOni(const std::string& uri) {
  if (uri.size() < 4) return false;
  std::string tail = uri.substr(uri.size() - 4);
  std::transform(tail.begin(), tail.end(), tail.begin(), [](unsigned char c) { return std::tolower(c); });
  return tail == ".oni";
}

// The URIs OpenNI2 enumerates, for error messages.
std::string attachedDeviceUris() {
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  if (devices.getSize() == 0) return "OpenNI2 sees no attached device";
  std::string list;
  for (int i = 0; i < devices.getSize(); ++i) {
    list += (i ? ", " : "") + std::string(devices[i].getUri());
  }
  return "OpenNI2 devices attached: " + list;
}

std::mutex& sessionMutex() {
  static std::mutex mutex;
  return mutex;
}

// One converted frame waiting for its partner from the other stream.
struct PendingFrame {
  int64_t device_us = 0;  // device timestamp [us]
  int64_t utime = 0;      // host clock [us]
  cv::Mat image;          // BGR colour or raw depth
  double depth_scale = 0.0;
};

}  // namespace

// ---------------------------------------------------------------------------------------
// DeviceClockOffset

int64_t DeviceClockOffset::update(int64_t device_us, int64_t host_us) {
  const double measured = static_cast<double>(host_us - device_us);
  if (!initialised_) {
    offset_us_ = measured;
    initialised_ = true;
  } else {
    const double elapsed_us = static_cast<double>(std::max<int64_t>(0, host_us - last_host_us_));
    offset_us_ = std::min(offset_us_ + drift_ppm_ * 1e-6 * elapsed_us, measured);
  }
  last_host_us_ = host_us;
  return toHost(device_us);
}

int64_t DeviceClockOffset::toHost(int64_t device_us) const {
  return device_us + static_cast<int64_t>(std::llround(offset_us_));
}

// ---------------------------------------------------------------------------------------
// OpenNI2Session

Expected<std::unique_ptr<OpenNI2Session>> OpenNI2Session::acquire() {
  std::lock_guard<std::mutex> lock(sessionMutex());
  if (openni::OpenNI::initialize() != openni::STATUS_OK) {
    const std::string details = openniError();
    // OpenNI2 counts a failed initialize() too; balance it so a later attempt starts afresh.
    openni::OpenNI::shutdown();
    return Error{"OpenNI2 initialisation failed: " + details +
                 " (OpenNI2 loads its drivers from OpenNI2/Drivers next to libOpenNI2.so, "
                 "e.g. /usr/lib/x86_64-linux-gnu/OpenNI2/Drivers)"};
  }
  return std::unique_ptr<OpenNI2Session>(new OpenNI2Session());
}

OpenNI2Session::~OpenNI2Session() {
  std::lock_guard<std::mutex> lock(sessionMutex());
  openni::OpenNI::shutdown();
}

// ---------------------------------------------------------------------------------------
// OpenNI2Source::Impl: the device, its streams, the clock and the pairing buffers.

struct OpenNI2Source::Impl {
  OpenNI2Options options;
  std::string uri;  // as given after "openni2:"
  std::string name() const { return "openni2:" + uri; }

  // Declared before the device and streams so that OpenNI2 is released after them.
  std::unique_ptr<OpenNI2Session> session;
  openni::Device device;
  openni::VideoStream streams[kStreamCount];
  bool enabled[kStreamCount] = {false, false};
  bool started[kStreamCount] = {false, false};
  openni::VideoMode modes[kStreamCount];
  bool recording = false;
  bool dummy = false;
  bool registered = false;
  bool synced = false;
  int recorded_frames[kStreamCount] = {0, 0};  // .oni: frames per stream (0 = unknown)
  int last_index[kStreamCount] = {0, 0};       // frame index last read per stream
  bool playback_wrapped = false;               // .oni: a frame index went back to the start
  int64_t frames_read = 0;                     // over both streams, since open
  int64_t frames_per_stream[kStreamCount] = {0, 0};  // since open

  DeviceClockOffset clock;
  int64_t last_utime[kStreamCount] = {INT64_MIN, INT64_MIN};
  std::deque<PendingFrame> pending[kStreamCount];
  std::optional<FrameResult> ready;  // a frame assembled but not yet returned
  int64_t seq = 0;
  std::vector<std::string> warnings;

  ~Impl();
  void parkPlayer();
  Status openDevice();
  Status createStream(int s);
  Status chooseMode(int s);
  void setUpDevice();
  Status start();
  Status awaitFirstFrames();
  FrameResult next();

  enum class ReadStatus { kRead, kTimeout, kBadFrame, kFailed };
  ReadStatus readOne(SteadyClock::time_point deadline, std::string* error);
  Expected<PendingFrame> convert(int s, const openni::VideoFrameRef& frame, int64_t host_us);
  void pair(int s);
  FrameResult assemble(PendingFrame* depth, PendingFrame* colour);
  FrameResult timedOut(int64_t frames_this_call) const;
  bool playbackFinished() const;
  std::optional<size_t> recordedFrames() const;  // the shorter stream's; nullopt for devices
  int streamCount() const { return int(enabled[kDepth]) + int(enabled[kColour]); }
  int mainStream() const { return enabled[kColour] ? kColour : kDepth; }
  double fps() const;  // the main stream's, kFallbackFps when it reports none [Hz]
  void warn(const std::string& text) { warnings.push_back(text); }
  std::string describe() const;
};

OpenNI2Source::Impl::~Impl() {
  if (recording) parkPlayer();
  bool any_started = false;
  for (int s = 0; s < kStreamCount; ++s) {
    if (started[s]) {
      streams[s].stop();
      any_started = true;
    }
  }
  // OpenNI2's Dummy driver only clears a flag in stop(): its frame threads run on until they
  // next look at it (up to one frame period later) and would then touch a destroyed stream,
  // or an unloaded driver after OpenNI::shutdown() (a crash seen in about half the runs).
  // Real drivers stop synchronously; waiting a few frame periods costs little at close.
  if (any_started && !recording) {
    std::this_thread::sleep_for(std::chrono::microseconds(int64_t(3e6 / fps())) +
                                std::chrono::milliseconds(50));
  }
  for (auto& stream : streams) stream.destroy();
  device.close();
}

// OpenNI2's .oni player thread walks its list of streams without a lock between frames (and
// without pause once a non-repeating file has ended), so destroying a stream can crash it
// (seen in about one run in fifteen). In manual-trigger mode (speed -1) it waits up to 2 s
// for a trigger at its next frame, off the list: destroy the streams within that time.
// (Closing the device before destroying the streams instead makes OpenNI2 read freed memory.)
void OpenNI2Source::Impl::parkPlayer() {
  openni::PlaybackControl* playback = device.getPlaybackControl();
  if (playback == nullptr || !(started[kDepth] || started[kColour])) return;
  playback->setSpeed(kPlayerManualSpeed);
  std::this_thread::sleep_for(std::chrono::microseconds(int64_t(2e6 / fps())) +
                              std::chrono::milliseconds(30));
}

double OpenNI2Source::Impl::fps() const {
  const int s = mainStream();
  const int fps = enabled[s] ? modes[s].getFps() : 0;
  return fps > 0 ? fps : kFallbackFps;
}

Status OpenNI2Source::Impl::openDevice() {
  const bool any = uri.empty() || uri == "any";
  std::error_code ignored;
  const bool is_file = !any && std::filesystem::is_regular_file(uri, ignored);
  recording = endsWithOni(uri) || is_file;
  if (recording && !is_file) {
    return Error{name() + ": no such .oni recording"};
  }
  const char* device_uri = any ? openni::ANY_DEVICE : uri.c_str();
  if (device.open(device_uri) != openni::STATUS_OK) {
    const std::string details = openniError();
    if (recording) return Error{name() + ": OpenNI2 cannot play this recording (" + details + ")"};
    return Error{name() + ": cannot open " + (any ? "any OpenNI2 device" : "device '" + uri + "'") +
                 " (" + details + "; " + attachedDeviceUris() +
                 "; see rgbd-capture --list-devices; openni2:Dummy is OpenNI2's test device)"};
  }
  recording = device.isFile();
  dummy = std::string(device.getDeviceInfo().getVendor()) == kDummyVendor;
  return {};
}

// The offered mode that 'accept' takes, in a usable pixel format (the preferred one first);
// null if there is none.
template <typename Accept>
const openni::VideoMode* bestOffered(int s, const openni::Array<openni::VideoMode>& offered, Accept accept) {
  const openni::VideoMode* best = nullptr;
  for (int i = 0; i < offered.getSize(); ++i) {
    const openni::VideoMode& mode = offered[i];
    if (!formatUsable(s, mode.getPixelFormat()) || !accept(mode)) continue;
    if (best == nullptr || formatRank(s, mode.getPixelFormat()) < formatRank(s, best->getPixelFormat())) {
      best = &mode;
    }
  }
  return best;
}

// Prefers width x height @ fps; else keeps the device's default mode if this source can read
// its pixel format; else takes a readable mode of the default's size, or any readable mode.
Status OpenNI2Source::Impl::chooseMode(int s) {
  openni::VideoStream& stream = streams[s];
  const openni::VideoMode current = stream.getVideoMode();
  const openni::Array<openni::VideoMode>& offered = stream.getSensorInfo().getSupportedVideoModes();
  const openni::VideoMode* wanted = bestOffered(s, offered, [&](const openni::VideoMode& mode) {
    return mode.getResolutionX() == options.width && mode.getResolutionY() == options.height &&
           mode.getFps() == options.fps;
  });
  const bool current_usable = formatUsable(s, current.getPixelFormat());
  if (wanted == nullptr && !current_usable) {
    wanted = bestOffered(s, offered, [&](const openni::VideoMode& mode) { return sameSize(mode, current); });
    if (wanted == nullptr) wanted = bestOffered(s, offered, [](const openni::VideoMode&) { return true; });
    if (wanted == nullptr) {
      std::string list;
      for (int i = 0; i < offered.getSize(); ++i) list += (i ? ", " : "") + modeText(offered[i]);
      return Error{name() + ": the " + kStreamName[s] + " stream offers no mode this source can read (" +
                   list + "; depth needs DEPTH_1_MM or DEPTH_100_UM, colour RGB888)"};
    }
  }
  const std::string stream_name = kStreamName[s];
  if (wanted == nullptr) {
    warn(stream_name + ": " + std::to_string(options.width) + "x" + std::to_string(options.height) + "@" +
         std::to_string(options.fps) + " not offered; keeping the device's mode " + modeText(current));
  } else if (stream.setVideoMode(*wanted) != openni::STATUS_OK) {
    const std::string details = openniError();
    if (!current_usable) {
      return Error{name() + ": cannot set the " + stream_name + " mode " + modeText(*wanted) + " (" + details + ")"};
    }
    warn(stream_name + ": setting " + modeText(*wanted) + " failed (" + details + "); keeping " + modeText(current));
  }
  modes[s] = stream.getVideoMode();
  return {};
}

Status OpenNI2Source::Impl::createStream(int s) {
  const openni::SensorType type = s == kDepth ? openni::SENSOR_DEPTH : openni::SENSOR_COLOR;
  if (!device.hasSensor(type)) {
    warn(std::string("the device has no ") + kStreamName[s] + " sensor");
    return {};
  }
  if (streams[s].create(device, type) != openni::STATUS_OK) {
    return Error{name() + ": cannot create the " + kStreamName[s] + " stream (" + openniError() + ")"};
  }
  enabled[s] = true;
  if (recording) {
    // A recording plays its streams as recorded; only check that they can be converted.
    modes[s] = streams[s].getVideoMode();
    if (!formatUsable(s, modes[s].getPixelFormat())) {
      return Error{name() + ": the recording's " + kStreamName[s] + " stream is " +
                   modeText(modes[s]) + ", which this source cannot read"};
    }
    return {};
  }
  if (Status chosen = chooseMode(s); !chosen) return chosen;
  if (streams[s].isPropertySupported(openni::STREAM_PROPERTY_MIRRORING)) {
    if (streams[s].setMirroringEnabled(options.mirror) != openni::STATUS_OK) {
      warn(std::string(kStreamName[s]) + ": cannot set mirroring (" + openniError() + ")");
    }
  } else if (options.mirror) {
    warn(std::string(kStreamName[s]) + ": the device cannot mirror; images are not mirrored");
  }
  return {};
}

// A recording: its frame counts. A live device with both streams: registration, frame sync,
// and a warning when the two sizes differ.
void OpenNI2Source::Impl::setUpDevice() {
  if (recording) {
    // Repeat stays on (OpenNI2's default): with it off, the player thread spins on a core
    // once the file has ended. The end is found from the frame indices instead.
    openni::PlaybackControl* playback = device.getPlaybackControl();
    if (playback != nullptr) {
      for (int s = 0; s < kStreamCount; ++s) {
        if (enabled[s]) recorded_frames[s] = std::max(0, playback->getNumberOfFrames(streams[s]));
      }
    }
    return;
  }
  if (streamCount() < 2) return;
  if (options.registration) {
    if (!device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
      warn("the device cannot register depth to colour; depth stays in the depth camera's geometry");
    } else if (device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) !=
               openni::STATUS_OK) {
      warn("registering depth to colour failed (" + openniError() + ")");
    } else {
      registered = true;
    }
  }
  if (options.depth_colour_sync) {
    if (device.setDepthColorSyncEnabled(true) != openni::STATUS_OK) {
      warn("depth/colour frame sync not available (" + openniError() +
           "); frames are paired by timestamp only");
    } else {
      synced = true;
    }
  }
  if (!sameSize(modes[kDepth], modes[kColour])) {
    warn("colour " + modeText(modes[kColour]) + " and depth " + modeText(modes[kDepth]) +
         " differ in size; frames will be reported as bad (no resizing is done): choose equal "
         "modes");
  }
}

Status OpenNI2Source::Impl::start() {
  for (int s = 0; s < kStreamCount; ++s) {
    if (!enabled[s]) continue;
    if (streams[s].start() != openni::STATUS_OK) {
      return Error{name() + ": cannot start the " + kStreamName[s] + " stream (" + openniError() + ")"};
    }
    started[s] = true;
  }
  return {};
}

// A live device must deliver a frame on every stream within the timeout, so that a silent
// device fails at open rather than at the first next(). Frames read here are kept. (It also
// guarantees that the Dummy driver's frame threads are running before any stop(): they set
// their running flag themselves, so a stop() before that would be lost.)
Status OpenNI2Source::Impl::awaitFirstFrames() {
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(options.frame_timeout_ms);
  for (int s = 0; s < kStreamCount; ++s) {
    while (enabled[s] && frames_per_stream[s] == 0) {
      std::string error;
      const ReadStatus status = readOne(deadline, &error);
      if (status == ReadStatus::kTimeout) {
        return Error{name() + ": the " + kStreamName[s] + " stream sent no frame within " +
                     std::to_string(options.frame_timeout_ms) + " ms of starting"};
      }
      if (status == ReadStatus::kFailed) return Error{error};
    }
  }
  return {};
}

// Waits for a frame on any stream until the deadline, converts it and files it for pairing.
OpenNI2Source::Impl::ReadStatus OpenNI2Source::Impl::readOne(SteadyClock::time_point deadline,
                                                            std::string* error) {
  openni::VideoStream* waiting[kStreamCount];
  int index_of[kStreamCount];
  int count = 0;
  for (int s = 0; s < kStreamCount; ++s) {
    if (!enabled[s]) continue;
    index_of[count] = s;
    waiting[count++] = &streams[s];
  }
  const auto remaining = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - SteadyClock::now());
  if (remaining.count() <= 0) return ReadStatus::kTimeout;
  int ready_index = -1;
  const openni::Status waited =
      openni::OpenNI::waitForAnyStream(waiting, count, &ready_index, static_cast<int>(remaining.count()));
  if (waited == openni::STATUS_TIME_OUT) return ReadStatus::kTimeout;
  const int64_t host_us = hostNowUs();
  if (waited != openni::STATUS_OK || ready_index < 0 || ready_index >= count) {
    *error = name() + ": waiting for frames failed (" + openniError() + ")";
    return ReadStatus::kFailed;
  }
  const int s = index_of[ready_index];
  openni::VideoFrameRef frame;
  if (streams[s].readFrame(&frame) != openni::STATUS_OK || !frame.isValid()) {
    *error = name() + ": reading a " + kStreamName[s] + " frame failed (" + openniError() + ")";
    return ReadStatus::kBadFrame;
  }
  if (recording && frame.getFrameIndex() < last_index[s]) {
    playback_wrapped = true;  // the player started the file again: it has ended
    return ReadStatus::kRead;
  }
  ++frames_read;
  ++frames_per_stream[s];
  last_index[s] = frame.getFrameIndex();
  auto converted = convert(s, frame, host_us);
  if (!converted) {
    *error = converted.error();
    return ReadStatus::kBadFrame;
  }
  pending[s].push_back(std::move(*converted));
  if (pending[s].size() > kMaxPendingPerStream) pending[s].pop_front();
  pair(s);
  return ReadStatus::kRead;
}

Expected<PendingFrame> OpenNI2Source::Impl::convert(int s, const openni::VideoFrameRef& frame,
                                                    int64_t host_us) {
  const openni::PixelFormat format = frame.getVideoMode().getPixelFormat();
  const int width = frame.getWidth(), height = frame.getHeight(), stride = frame.getStrideInBytes();
  const int bytes_per_pixel = s == kDepth ? 2 : 3;
  const std::string which = std::string(kStreamName[s]) + " frame " + std::to_string(frame.getFrameIndex());
  if (!formatUsable(s, format)) {
    return Error{name() + ": " + which + " is " + pixelFormatName(format) + ", which this source cannot read"};
  }
  if (frame.getData() == nullptr || width <= 0 || height <= 0 || stride < width * bytes_per_pixel ||
      frame.getDataSize() < stride * (height - 1) + width * bytes_per_pixel) {
    return Error{name() + ": " + which + " is truncated (" + std::to_string(frame.getDataSize()) +
                 " bytes for " + std::to_string(width) + "x" + std::to_string(height) + ")"};
  }
  PendingFrame out;
  void* data = const_cast<void*>(frame.getData());
  if (s == kDepth) {
    out.image = cv::Mat(height, width, CV_16UC1, data, static_cast<size_t>(stride)).clone();
    out.depth_scale = depthUnitsPerMetre(format);
  } else {
    cv::cvtColor(cv::Mat(height, width, CV_8UC3, data, static_cast<size_t>(stride)), out.image,
                 cv::COLOR_RGB2BGR);
  }
  out.device_us = static_cast<int64_t>(frame.getTimestamp());
  out.utime = clock.update(out.device_us, host_us);
  if (out.utime <= last_utime[s]) out.utime = last_utime[s] + 1;  // strictly increasing
  last_utime[s] = out.utime;
  return out;
}

// Files a finished frame in 'ready' when stream s's newest frame completes one: alone for a
// single-stream source, else with the other stream's frame nearest in time, if that is within
// half a frame period. Frames older than a pair can no longer pair and are dropped.
void OpenNI2Source::Impl::pair(int s) {
  if (ready) return;  // the previous frame has not been taken yet; keep this one pending
  if (streamCount() == 1) {
    PendingFrame frame = std::move(pending[s].front());
    pending[s].pop_front();
    ready = s == kDepth ? assemble(&frame, nullptr) : assemble(nullptr, &frame);
    return;
  }
  const int o = 1 - s;
  const PendingFrame& newest = pending[s].back();
  const int64_t half_period_us = static_cast<int64_t>(0.5e6 / fps());
  int best = -1;
  int64_t best_dt = 0;
  for (size_t i = 0; i < pending[o].size(); ++i) {
    const int64_t dt = std::llabs(pending[o][i].device_us - newest.device_us);
    if (dt <= half_period_us && (best < 0 || dt < best_dt)) {
      best = static_cast<int>(i);
      best_dt = dt;
    }
  }
  if (best < 0) return;
  PendingFrame mine = std::move(pending[s].back());
  PendingFrame theirs = std::move(pending[o][best]);
  pending[s].clear();
  pending[o].erase(pending[o].begin(), pending[o].begin() + best + 1);
  ready = s == kDepth ? assemble(&mine, &theirs) : assemble(&theirs, &mine);
}

FrameResult OpenNI2Source::Impl::assemble(PendingFrame* depth, PendingFrame* colour) {
  FrameResult result;
  if (depth != nullptr && colour != nullptr && depth->image.size() != colour->image.size()) {
    result.status = FrameResult::Status::kBadFrame;
    result.error = name() + ": colour " + std::to_string(colour->image.cols) + "x" +
                   std::to_string(colour->image.rows) + " and depth " + std::to_string(depth->image.cols) +
                   "x" + std::to_string(depth->image.rows) +
                   " differ in size; not resizing (choose equal modes, or registration)";
    return result;
  }
  result.status = FrameResult::Status::kFrame;
  RgbdFrame& frame = result.frame;
  frame.utime = colour != nullptr ? colour->utime : depth->utime;
  frame.seq = seq++;
  if (colour != nullptr) frame.colour = std::move(colour->image);
  if (depth != nullptr) {
    frame.depth = std::move(depth->image);
    frame.depth_scale = depth->depth_scale;
  }
  frame.camera_name = !options.camera_name.empty() ? options.camera_name
                      : dummy                       ? "openni2_dummy"
                                                    : "kinect_default";
  return result;
}

std::optional<size_t> OpenNI2Source::Impl::recordedFrames() const {
  if (!recording) return std::nullopt;
  int frames = INT_MAX;
  for (int s = 0; s < kStreamCount; ++s) {
    if (enabled[s]) frames = std::min(frames, recorded_frames[s]);
  }
  if (frames <= 0 || frames == INT_MAX) return std::nullopt;
  return static_cast<size_t>(frames);
}

bool OpenNI2Source::Impl::playbackFinished() const {
  if (!recording) return false;
  if (playback_wrapped) return true;
  for (int s = 0; s < kStreamCount; ++s) {
    if (enabled[s] && (recorded_frames[s] <= 0 || last_index[s] < recorded_frames[s])) return false;
  }
  return true;
}

FrameResult OpenNI2Source::Impl::timedOut(int64_t frames_this_call) const {
  FrameResult result;
  const std::string waited = std::to_string(options.frame_timeout_ms) + " ms";
  if (recording) {
    if (frames_read > 0) return result;  // kEnd: the player stops at the end of the file
    result.status = FrameResult::Status::kFailed;
    result.error = name() + ": the recording delivered no frame within " + waited +
                   " (OpenNI2 2.2's player silently drops the frames of recordings made without "
                   "the cropping property, e.g. recordings of the Dummy device)";
    return result;
  }
  if (frames_this_call == 0) {
    result.status = FrameResult::Status::kFailed;
    result.error = name() + ": no frame within " + waited + " (device stalled or unplugged)";
    return result;
  }
  result.status = FrameResult::Status::kBadFrame;
  std::ostringstream out;
  out << name() << ": " << frames_this_call << " frames in " << waited
      << " but no colour/depth pair within half a frame period";
  for (int s = 0; s < kStreamCount; ++s) {
    if (!pending[s].empty()) out << "; last " << kStreamName[s] << " at " << pending[s].back().device_us << " us";
  }
  result.error = out.str();
  return result;
}

FrameResult OpenNI2Source::Impl::next() {
  const auto deadline = SteadyClock::now() + std::chrono::milliseconds(options.frame_timeout_ms);
  int64_t frames_this_call = 0;
  while (true) {
    if (ready) {
      FrameResult result = std::move(*ready);
      ready.reset();
      // Frames read while this one waited may already complete the next one.
      for (int s = 0; s < kStreamCount && !ready; ++s) {
        if (!pending[s].empty()) pair(s);
      }
      return result;
    }
    if (playbackFinished()) return FrameResult{};  // kEnd
    std::string error;
    switch (readOne(deadline, &error)) {
      case ReadStatus::kRead: ++frames_this_call; break;
      case ReadStatus::kTimeout: return timedOut(frames_this_call);
      case ReadStatus::kBadFrame: return FrameResult{FrameResult::Status::kBadFrame, {}, error};
      case ReadStatus::kFailed: return FrameResult{FrameResult::Status::kFailed, {}, error};
    }
  }
}

std::string OpenNI2Source::Impl::describe() const {
  std::ostringstream out;
  out << name() << " (";
  const openni::VideoMode& main = modes[mainStream()];
  if (streamCount() == 2 && !sameSize(modes[kDepth], modes[kColour])) {
    out << "colour " << modes[kColour].getResolutionX() << "x" << modes[kColour].getResolutionY()
        << ", depth " << modes[kDepth].getResolutionX() << "x" << modes[kDepth].getResolutionY();
  } else {
    out << main.getResolutionX() << "x" << main.getResolutionY();
    if (streamCount() == 1) out << (enabled[kDepth] ? " depth only" : " colour only");
  }
  out << " @ " << main.getFps() << " Hz";
  if (enabled[kDepth]) {
    out << ", depth " << (modes[kDepth].getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM ? "1 mm" : "100 um");
  }
  if (recording) {
    const std::optional<size_t> frames = recordedFrames();
    out << ", recording" << (frames ? " of " + std::to_string(*frames) + " frames" : std::string());
  } else if (streamCount() == 2) {
    out << (registered ? ", registered" : ", unregistered") << (synced ? ", synced" : ", unsynced");
  }
  out << ")";
  return out.str();
}

// ---------------------------------------------------------------------------------------
// OpenNI2Source

Expected<std::unique_ptr<OpenNI2Source>> OpenNI2Source::open(const std::string& uri,
                                                             const OpenNI2Options& options) {
  const std::string name = "openni2:" + uri;
  if (!options.colour && !options.depth) return Error{name + ": neither colour nor depth requested"};
  if (options.frame_timeout_ms <= 0) return Error{name + ": frame_timeout_ms must be positive"};
  if (options.width <= 0 || options.height <= 0 || options.fps <= 0) {
    return Error{name + ": the requested mode needs a positive width, height and fps"};
  }
  if (options.clock_drift_ppm < 0) return Error{name + ": clock_drift_ppm must not be negative"};

  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->uri = uri;
  impl->clock = DeviceClockOffset(options.clock_drift_ppm);
  auto session = OpenNI2Session::acquire();
  if (!session) return Error{name + ": " + session.error()};
  impl->session = std::move(*session);

  if (Status opened = impl->openDevice(); !opened) return Error{opened.error()};
  if (impl->dummy) impl->clock = DeviceClockOffset(std::max(options.clock_drift_ppm, kDummyClockDriftPpm));
  if (options.depth) {
    if (Status created = impl->createStream(kDepth); !created) return Error{created.error()};
  }
  if (options.colour) {
    if (Status created = impl->createStream(kColour); !created) return Error{created.error()};
  }
  if (impl->streamCount() == 0) return Error{name + ": the device has none of the requested streams"};
  impl->setUpDevice();
  if (Status started = impl->start(); !started) return Error{started.error()};
  // A recording is not waited for here: a player that delivers nothing shows in next().
  if (!impl->recording) {
    if (Status first = impl->awaitFirstFrames(); !first) return Error{first.error()};
  }
  if (options.verbose) {
    std::cerr << impl->describe();
    for (int s = 0; s < kStreamCount; ++s) {
      if (impl->enabled[s]) std::cerr << "; " << kStreamName[s] << " " << modeText(impl->modes[s]);
    }
    std::cerr << "\n";
    for (const auto& warning : impl->warnings) std::cerr << name << ": warning: " << warning << "\n";
  }
  return std::unique_ptr<OpenNI2Source>(new OpenNI2Source(std::move(impl)));
}

OpenNI2Source::OpenNI2Source(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OpenNI2Source::~OpenNI2Source() = default;

FrameResult OpenNI2Source::next() { return impl_->next(); }

double OpenNI2Source::nominalRateHz() const { return impl_->modes[impl_->mainStream()].getFps(); }

std::optional<size_t> OpenNI2Source::size() const { return impl_->recordedFrames(); }

std::string OpenNI2Source::describe() const { return impl_->describe(); }
const std::vector<std::string>& OpenNI2Source::warnings() const { return impl_->warnings; }
bool OpenNI2Source::isRecording() const { return impl_->recording; }

Expected<std::unique_ptr<FrameSource>> openOpenNI2Source(const std::string& uri,
                                                         const OpenNI2Options& options) {
  auto source = OpenNI2Source::open(uri, options);
  if (!source) return Error{source.error()};
  return std::unique_ptr<FrameSource>(std::move(*source));
}

}  // namespace rgbdslam
