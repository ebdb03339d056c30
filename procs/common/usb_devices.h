#pragma once
// Which RGB-D cameras are attached, for rgbd-capture --list-devices: the USB devices of
// PrimeSense (vendor 0x1d27: PS1080 sensors such as ASUS Xtion and Carmine) and of
// Microsoft's Kinect (vendor 0x045e, the products listed in usb_devices.cpp), found with
// libusb-1.0, and the devices OpenNI2's drivers can open.
// Failures (no USB access in a container, OpenNI2 without drivers) come back as an error
// string next to an empty list, never as a crash. Nothing here opens a stream.
#include <cstdint>
#include <string>
#include <vector>

namespace rgbdslam {

struct UsbCameraInfo {
  int bus = 0;              // USB bus number
  int address = 0;          // device address on that bus
  uint16_t vendor_id = 0;   // 0x1d27 PrimeSense, 0x045e Microsoft
  uint16_t product_id = 0;
  std::string product_name;  // the device's own product string when it can be read, else
                             // the name from the built-in table
  std::string note;          // what it means here, e.g. "the Kinect's depth/colour camera"
};

// PrimeSense and Kinect devices on the USB buses. On failure returns what it found so far
// (usually nothing) and sets *error (if error is not null); on success clears *error.
std::vector<UsbCameraInfo> listUsbCameras(std::string* error);

// Devices OpenNI2 enumerates, one line each: "URI  name 'NAME', vendor 'VENDOR', usb
// VVVV:PPPP". OpenNI2's Dummy test device is never enumerated (open it as openni2:Dummy).
std::vector<std::string> listOpenNI2Devices(std::string* error);

struct DeviceListing {
  std::vector<UsbCameraInfo> usb;
  std::string usb_error;  // empty when the USB enumeration worked
  std::vector<std::string> openni2;
  std::string openni2_error;  // empty when OpenNI2 enumeration worked
};

// Runs both enumerations.
DeviceListing listDevices();

// The text rgbd-capture --list-devices prints: a header per list, one line per device,
// "none found" for an empty list, the error where a list could not be made, and a hint
// when a camera is on the USB bus but OpenNI2 cannot open it.
std::string formatDeviceList(const DeviceListing& listing);
// formatDeviceList(listDevices()).
std::string formatDeviceList();

}  // namespace rgbdslam
