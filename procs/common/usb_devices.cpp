#include "common/usb_devices.h"

#include <OpenNI.h>
#include <libusb.h>

#include <cstdio>
#include <memory>
#include <sstream>

#include "common/openni2_source.h"

namespace rgbdslam {
namespace {

constexpr uint16_t kVendorPrimeSense = 0x1d27;
constexpr uint16_t kVendorMicrosoft = 0x045e;

struct KnownProduct {
  uint16_t vendor_id;
  uint16_t product_id;
  const char* name;
  const char* note;
};

// The Microsoft products are Kinect v1 parts (those in Debian's udev rules for OpenNI2,
// 60-libopenni2-0.rules, plus the Kinect for Windows audio firmware variants) and Kinect v2,
// listed so that it is recognised and reported as unsupported. Any other Microsoft device is
// ignored. Every PrimeSense device is listed; these are the ones named.
constexpr KnownProduct kKnownProducts[] = {
    {kVendorMicrosoft, 0x02ae, "Xbox NUI Camera", "Kinect for Xbox 360: depth/colour camera"},
    {kVendorMicrosoft, 0x02ad, "Xbox NUI Audio", "Kinect for Xbox 360: microphones (not used)"},
    {kVendorMicrosoft, 0x02b0, "Xbox NUI Motor", "Kinect for Xbox 360: tilt motor, LED (not used)"},
    {kVendorMicrosoft, 0x02bf, "Kinect for Windows NUI Camera", "Kinect for Windows: depth/colour camera"},
    {kVendorMicrosoft, 0x02be, "Kinect for Windows NUI Audio", "Kinect for Windows: microphones (not used)"},
    {kVendorMicrosoft, 0x02c3, "Kinect for Windows NUI Audio", "Kinect for Windows: microphones (not used)"},
    {kVendorMicrosoft, 0x02bb, "Kinect for Windows NUI Audio", "Kinect for Windows: microphones (not used)"},
    {kVendorMicrosoft, 0x02c2, "Kinect for Windows NUI Motor", "Kinect for Windows: tilt motor (not used)"},
    {kVendorMicrosoft, 0x02c4, "Xbox NUI Sensor (Kinect v2)", "Kinect v2: not supported by OpenNI2 (libfreenect2)"},
    {kVendorMicrosoft, 0x02d9, "Xbox NUI Sensor (Kinect v2)", "Kinect v2: not supported by OpenNI2 (libfreenect2)"},
    {kVendorPrimeSense, 0x0600, "PrimeSense PS1080 (e.g. ASUS Xtion PRO)", "OpenNI2 PS1080 driver"},
    {kVendorPrimeSense, 0x0601, "PrimeSense PS1080 (e.g. ASUS Xtion PRO LIVE, Carmine 1.08)",
     "OpenNI2 PS1080 driver"},
    {kVendorPrimeSense, 0x0609, "PrimeSense PS1080 (Carmine 1.09)", "OpenNI2 PS1080 driver"},
};

const KnownProduct* findProduct(uint16_t vendor_id, uint16_t product_id) {
  for (const auto& product : kKnownProducts) {
    if (product.vendor_id == vendor_id && product.product_id == product_id) return &product;
  }
  return nullptr;
}

bool isKinectCamera(const UsbCameraInfo& info) {
  return info.vendor_id == kVendorMicrosoft && (info.product_id == 0x02ae || info.product_id == 0x02bf);
}

std::string hex4(uint16_t value) {
  char text[8];
  std::snprintf(text, sizeof(text), "%04x", value);
  return text;
}

// The product string descriptor; empty when the device cannot be opened (permissions) or
// has none.
std::string readProductString(libusb_device* device, uint8_t string_index) {
  if (string_index == 0) return {};
  libusb_device_handle* handle = nullptr;
  if (libusb_open(device, &handle) != LIBUSB_SUCCESS || handle == nullptr) return {};
  unsigned char text[256] = {};
  const int length = libusb_get_string_descriptor_ascii(handle, string_index, text, sizeof(text) - 1);
  libusb_close(handle);
  return length > 0 ? std::string(reinterpret_cast<const char*>(text), static_cast<size_t>(length)) : std::string();
}

struct UsbContextDeleter {
  void operator()(libusb_context* context) const { libusb_exit(context); }
};

void setError(std::string* error, const std::string& text) {
  if (error != nullptr) *error = text;
}

}  // namespace

std::vector<UsbCameraInfo> listUsbCameras(std::string* error) {
  setError(error, "");
  std::vector<UsbCameraInfo> cameras;
  libusb_context* raw_context = nullptr;
  const int initialised = libusb_init(&raw_context);
  if (initialised != LIBUSB_SUCCESS) {
    setError(error, std::string("libusb_init failed: ") + libusb_strerror(initialised) +
                        " (no USB access here? e.g. a container without /dev/bus/usb)");
    return cameras;
  }
  std::unique_ptr<libusb_context, UsbContextDeleter> context(raw_context);
  libusb_device** devices = nullptr;
  const ssize_t count = libusb_get_device_list(context.get(), &devices);
  if (count < 0) {
    setError(error, std::string("libusb_get_device_list failed: ") + libusb_strerror(static_cast<int>(count)));
    return cameras;
  }
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(devices[i], &descriptor) != LIBUSB_SUCCESS) continue;
    const KnownProduct* known = findProduct(descriptor.idVendor, descriptor.idProduct);
    if (descriptor.idVendor != kVendorPrimeSense && known == nullptr) continue;
    UsbCameraInfo info;
    info.bus = libusb_get_bus_number(devices[i]);
    info.address = libusb_get_device_address(devices[i]);
    info.vendor_id = descriptor.idVendor;
    info.product_id = descriptor.idProduct;
    info.product_name = readProductString(devices[i], descriptor.iProduct);
    if (info.product_name.empty()) info.product_name = known ? known->name : "PrimeSense device";
    info.note = known ? known->note : "PrimeSense sensor (OpenNI2 PS1080 or PSLink driver)";
    cameras.push_back(std::move(info));
  }
  libusb_free_device_list(devices, 1);
  return cameras;
}

std::vector<std::string> listOpenNI2Devices(std::string* error) {
  setError(error, "");
  std::vector<std::string> lines;
  auto session = OpenNI2Session::acquire();
  if (!session) {
    setError(error, session.error());
    return lines;
  }
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  for (int i = 0; i < devices.getSize(); ++i) {
    const openni::DeviceInfo& device = devices[i];
    lines.push_back(std::string(device.getUri()) + "  name '" + device.getName() + "', vendor '" +
                    device.getVendor() + "', usb " + hex4(device.getUsbVendorId()) + ":" +
                    hex4(device.getUsbProductId()));
  }
  return lines;
}

DeviceListing listDevices() {
  DeviceListing listing;
  listing.usb = listUsbCameras(&listing.usb_error);
  listing.openni2 = listOpenNI2Devices(&listing.openni2_error);
  return listing;
}

std::string formatDeviceList(const DeviceListing& listing) {
  std::ostringstream out;
  out << "USB RGB-D cameras (PrimeSense 1d27:*, Microsoft Kinect 045e:*):\n";
  if (!listing.usb_error.empty()) out << "  (could not list: " << listing.usb_error << ")\n";
  if (listing.usb.empty()) out << "  none found\n";
  bool kinect_camera = false, primesense = false;
  for (const auto& camera : listing.usb) {
    out << "  bus " << camera.bus << " address " << camera.address << "  " << hex4(camera.vendor_id) << ":"
        << hex4(camera.product_id) << "  " << camera.product_name << "  [" << camera.note << "]\n";
    kinect_camera = kinect_camera || isKinectCamera(camera);
    primesense = primesense || camera.vendor_id == kVendorPrimeSense;
  }
  out << "OpenNI2 devices (use as --source openni2:URI):\n";
  if (!listing.openni2_error.empty()) out << "  (could not list: " << listing.openni2_error << ")\n";
  if (listing.openni2.empty()) out << "  none found\n";
  for (const auto& device : listing.openni2) out << "  " << device << "\n";
  out << "  (openni2:Dummy is OpenNI2's built-in test device; openni2:FILE.oni plays a recording)\n";
  if (kinect_camera && listing.openni2.empty()) {
    out << "Hint: a Kinect camera is on the USB bus but OpenNI2 lists no device. OpenNI2's own "
           "drivers (PS1080, PSLink) do not drive Microsoft's Kinect; it needs libfreenect's "
           "OpenNI2 driver (libFreenectDriver.so) in OpenNI2's Drivers folder.\n";
  } else if (primesense && listing.openni2.empty()) {
    out << "Hint: a PrimeSense camera is on the USB bus but OpenNI2 lists no device: check the device "
           "permissions (udev rules 60-libopenni2-0.rules, group video) and re-plug it.\n";
  }
  return out.str();
}

std::string formatDeviceList() { return formatDeviceList(listDevices()); }

}  // namespace rgbdslam
