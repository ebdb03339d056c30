#pragma once
// Frames from OpenNI2: a live device (PrimeSense/Xtion through OpenNI2's PS1080 driver, a
// Kinect through a libfreenect OpenNI2 driver), an .oni recording, or OpenNI2's "Dummy" test
// device (320x240 depth + colour at 30 Hz, no hardware needed).
//
// Call order: openOpenNI2Source() initialises OpenNI2, opens the device, picks the video
// modes, asks for registration and frame sync, starts the streams and, for live devices,
// waits for the first frames, so that a bad URI, a missing device or a silent one is an
// error at open time. next() then blocks for at most frame_timeout_ms: no frame at all in
// that time is kFailed (device stalled or unplugged), frames that do not pair or cannot be
// converted are kBadFrame, each with a message; never a hang. A recording ends with kEnd
// once every stream's last frame was read, or when OpenNI2's player starts the file again.
// The destructor stops everything (working around two OpenNI2 2.2 races, see the .cpp) and
// releases OpenNI2.
//
// Frames: colour CV_8UC3 BGR (converted from OpenNI's RGB888), depth CV_16UC1 in the
// device's units, depth_scale in units per metre: 1000 for PIXEL_FORMAT_DEPTH_1_MM, 10000
// for DEPTH_100_UM. Colour and depth are paired by nearest device timestamp (within half a
// frame period); unpaired frames are dropped. Colour and depth of different sizes are never
// resized: such a pair is returned as kBadFrame naming both sizes (with registration on,
// the device already draws depth in the colour camera's geometry; equal sizes are then the
// user's choice of modes).
//
// Time: OpenNI2 stamps frames in microseconds of the device's clock. utime (host clock,
// microseconds since the epoch) = device timestamp + offset, where the offset is estimated
// by DeviceClockOffset (below); a frame pair takes the colour frame's time. A recording's
// stamps (which OpenNI2's Recorder starts at 0 for each stream) are mapped the same way,
// so utime is the host time of playback. utime strictly increases; seq counts delivered
// frames from 0.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

struct OpenNI2Options {
  bool colour = true;             // open the colour stream; false: depth-only frames
  bool depth = true;              // open the depth stream; false: colour-only frames
  bool registration = true;       // IMAGE_REGISTRATION_DEPTH_TO_COLOR where the device
                                  // supports it, else a warning
  bool depth_colour_sync = true;  // device frame sync where supported, else a warning
  bool mirror = false;            // mirrored images (keep false for SLAM); a warning if
                                  // true and the device cannot mirror
  int width = 640;                // requested resolution [px]; when the device does not
  int height = 480;               // offer width x height @ fps, it keeps its default mode
  int fps = 30;                   // requested frame rate [Hz]
  int frame_timeout_ms = 2000;    // longest wait for a frame, in open and in next() [ms]
  double clock_drift_ppm = 1000;  // how fast the device-to-host clock offset estimate may
                                  // grow [us per s of host time]; covers crystal drift and
                                  // NTP slewing (see DeviceClockOffset). The Dummy device,
                                  // whose stamps are frame_index * 33 ms and run 1-3 % slow,
                                  // gets at least 50000.
  std::string camera_name;        // RgbdFrame::camera_name; empty: "kinect_default", or
                                  // "openni2_dummy" for the Dummy device
  bool verbose = true;            // print the chosen modes and any warnings to stderr
};

// Maps device timestamps onto the host clock: offset = host receive time - device time is
// the frame's transport latency plus the (unknown) clock offset; its minimum over frames is
// the best estimate of the clock offset (the frame that arrived with the least latency), so
// the estimate only ever moves down to a new minimum. It may creep up by at most
// drift_ppm us per host second, so that a device clock running slower than the host's is
// followed (a pure minimum would leave utime falling behind the host clock); set
// drift_ppm = 0 for a pure minimum. The first frame's latency is taken as the first estimate.
class DeviceClockOffset {
 public:
  explicit DeviceClockOffset(double drift_ppm = 1000.0) : drift_ppm_(drift_ppm) {}
  // Refines the estimate with a frame stamped device_us [us, device clock] that arrived at
  // host_us [us, host clock]; returns the frame's host-clock time device_us + offset.
  int64_t update(int64_t device_us, int64_t host_us);
  // Host-clock time of device_us with the current estimate.
  int64_t toHost(int64_t device_us) const;
  bool initialised() const { return initialised_; }
  double offsetUs() const { return offset_us_; }  // host - device [us]

 private:
  double drift_ppm_;
  bool initialised_ = false;
  double offset_us_ = 0.0;
  int64_t last_host_us_ = 0;
};

// One reference on OpenNI2's global state: OpenNI::initialize() on acquire,
// OpenNI::shutdown() on destruction. OpenNI2 counts these itself but not thread-safely;
// this serialises them. A failed initialisation is reported with
// OpenNI::getExtendedError() (for example the drivers folder it searched).
class OpenNI2Session {
 public:
  static Expected<std::unique_ptr<OpenNI2Session>> acquire();
  ~OpenNI2Session();
  OpenNI2Session(const OpenNI2Session&) = delete;
  OpenNI2Session& operator=(const OpenNI2Session&) = delete;

 private:
  OpenNI2Session() = default;
};

class OpenNI2Source : public FrameSource {
 public:
  // As openOpenNI2Source(), keeping the concrete type (for warnings()).
  static Expected<std::unique_ptr<OpenNI2Source>> open(const std::string& uri,
                                                       const OpenNI2Options& options);
  ~OpenNI2Source() override;
  FrameResult next() override;
  // The stream's frame rate [Hz] (the colour stream's when there is one).
  double nominalRateHz() const override;
  // nullopt for devices; for .oni playback the number of frames of the shorter stream.
  std::optional<size_t> size() const override;
  // e.g. "openni2:Dummy (320x240 @ 30 Hz, depth 1 mm, unregistered, synced)".
  std::string describe() const override;
  // What could not be set up as asked (registration, sync, mode, mirroring), one per line.
  const std::vector<std::string>& warnings() const;
  bool isRecording() const;  // true for .oni playback

 private:
  struct Impl;
  explicit OpenNI2Source(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// uri is what follows "openni2:" on the command line: "Dummy" (OpenNI2's test device), a
// path to an .oni recording, a device URI (see rgbd-capture --list-devices), or "" / "any"
// for the first attached device.
Expected<std::unique_ptr<FrameSource>> openOpenNI2Source(const std::string& uri,
                                                         const OpenNI2Options& options = {});

}  // namespace rgbdslam

// rgbd-capture --list-devices uses formatDeviceList() from here.
#include "common/usb_devices.h"
