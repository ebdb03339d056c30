#include "rgbdslam/io/tum_dataset.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "rgbdslam/image/codec.h"

namespace rgbdslam {
namespace {

namespace fs = std::filesystem;

struct Stamped {
  double t;
  std::string path;
};

// The non-throwing filesystem calls: a symlink loop (ELOOP) or a permission error is a
// message, not an exception.
Status checkRegularFile(const fs::path& path) {
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (error) return Error{"cannot be reached: " + error.message()};
  if (!fs::is_regular_file(status)) return Error{fs::exists(status) ? "is not a regular file" : "does not exist"};
  return Status{};
}

// Parses "timestamp relative/path" lines; every named file must exist.
Expected<std::vector<Stamped>> readList(const std::string& dir, const std::string& name) {
  const std::string list_path = (fs::path(dir) / name).string();
  std::ifstream file(list_path);
  if (!file) return Error{list_path + ": cannot open (is " + dir + " a TUM RGB-D directory?)"};
  std::vector<Stamped> list;
  std::string line;
  for (int number = 1; std::getline(file, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream in(line);
    Stamped entry;
    std::string rest;
    const std::string where = list_path + ":" + std::to_string(number) + ": ";
    if (!(in >> entry.t >> entry.path) || !std::isfinite(entry.t)) {
      return Error{where + "expected 'timestamp path'"};
    }
    if (entry.t < 0 || entry.t > kMaxTumTimestampS) {
      return Error{where + "timestamp " + std::to_string(entry.t) + " s is outside [0, " +
                   std::to_string(kMaxTumTimestampS) + "] s"};
    }
    if (in >> rest) return Error{where + "unexpected text '" + rest + "' after the path"};
    if (Status s = checkRegularFile(fs::path(dir) / entry.path); !s) return Error{where + "names " + entry.path + ", which " + s.error()};
    if (!list.empty() && entry.t <= list.back().t) return Error{where + "timestamps must increase"};
    list.push_back(entry);
  }
  if (list.empty()) return Error{list_path + ": lists no images"};
  return list;
}

// One-to-one pairing by smallest |dt| first (as the benchmark's associate.py), in rgb order.
std::vector<TumEntry> associate(const std::vector<Stamped>& rgb, const std::vector<Stamped>& depth,
                                const TumOptions& options) {
  struct Candidate {
    double dt;
    size_t i_rgb, i_depth;
  };
  std::vector<Candidate> candidates;
  size_t start = 0;
  for (size_t i = 0; i < rgb.size(); ++i) {
    while (start < depth.size() && depth[start].t < rgb[i].t - options.max_dt_s) ++start;
    for (size_t j = start; j < depth.size() && depth[j].t <= rgb[i].t + options.max_dt_s; ++j) {
      candidates.push_back({std::abs(depth[j].t - rgb[i].t), i, j});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.dt < b.dt; });
  std::vector<long> partner(rgb.size(), -1);
  std::vector<bool> depth_used(depth.size(), false);
  for (const auto& c : candidates) {
    if (partner[c.i_rgb] >= 0 || depth_used[c.i_depth]) continue;
    partner[c.i_rgb] = static_cast<long>(c.i_depth);
    depth_used[c.i_depth] = true;
  }
  std::vector<TumEntry> entries;
  for (size_t i = 0; i < rgb.size(); ++i) {
    TumEntry e{rgb[i].t, std::numeric_limits<double>::quiet_NaN(), rgb[i].path, ""};
    if (partner[i] >= 0) {
      e.t_depth = depth[partner[i]].t;
      e.depth_path = depth[partner[i]].path;
    } else if (options.require_depth) {
      continue;
    }
    entries.push_back(e);
  }
  return entries;
}

FrameResult badFrame(const std::string& message) {
  FrameResult result;
  result.status = FrameResult::Status::kBadFrame;
  result.error = message;
  return result;
}


// An image file of the camera's size, decoded as stored. Its header is read first, so a
// file that declares a huge image is refused before the decoder allocates it.
Expected<cv::Mat> readImage(const std::string& file, const PinholeCamera& camera) {
  constexpr std::streamoff kMaxFileBytes = std::streamoff{1} << 30;  // [bytes], 4x a raw 8192^2 16-bit image
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) return Error{file + ": cannot be opened"};
  const std::streamoff bytes = in.tellg();
  if (bytes <= 0 || bytes > kMaxFileBytes) return Error{file + ": has " + std::to_string(bytes) + " bytes, not a frame image"};
  std::vector<uint8_t> data(static_cast<size_t>(bytes));
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(data.data()), bytes)) return Error{file + ": cannot be read"};
  const Expected<cv::Size> size = encodedImageSize(data.data(), data.size());
  if (!size) return Error{file + ": cannot decode (" + size.error() + ")"};
  if (size->width != camera.width || size->height != camera.height) {
    return Error{file + ": image is " + std::to_string(size->width) + "x" + std::to_string(size->height) +
                 " but the camera file says " + std::to_string(camera.width) + "x" + std::to_string(camera.height)};
  }
  Expected<cv::Mat> image = decodeImage(data.data(), data.size(), ImageRead::kAsStored, *size);
  if (!image) return Error{file + ": cannot decode (" + image.error() + ")"};
  return image;
}

}  // namespace

Expected<std::vector<TumEntry>> readTumIndex(const std::string& dir, const TumOptions& options) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) return Error{dir + ": no such directory" + (error ? " (" + error.message() + ")" : "")};
  auto rgb = readList(dir, "rgb.txt");
  if (!rgb) return Error{rgb.error()};
  auto depth = readList(dir, "depth.txt");
  if (!depth) return Error{depth.error()};
  auto entries = associate(*rgb, *depth, options);
  if (entries.empty()) return Error{dir + ": no colour image has a depth image within " + std::to_string(options.max_dt_s) + " s"};
  return entries;
}

TumSource::TumSource(std::string dir, std::vector<TumEntry> entries, PinholeCamera camera)
    : dir_(std::move(dir)), entries_(std::move(entries)), camera_(std::move(camera)) {}

FrameResult TumSource::next() {
  if (next_ >= entries_.size()) return FrameResult{};
  return read(next_++);
}

FrameResult TumSource::read(size_t i) const {
  const TumEntry& e = entries_.at(i);
  const std::string rgb_file = (fs::path(dir_) / e.rgb_path).string();
  FrameResult result;
  RgbdFrame& frame = result.frame;
  Expected<cv::Mat> colour = readImage(rgb_file, camera_);
  if (!colour) return badFrame(colour.error());
  frame.colour = *colour;
  if (frame.colour.depth() != CV_8U) return badFrame(rgb_file + ": colour image is not 8-bit");
  if (frame.colour.channels() == 4) cv::cvtColor(frame.colour, frame.colour, cv::COLOR_BGRA2BGR);
  if (frame.colour.channels() == 1) cv::cvtColor(frame.colour, frame.colour, cv::COLOR_GRAY2BGR);
  if (!e.depth_path.empty()) {
    const std::string depth_file = (fs::path(dir_) / e.depth_path).string();
    Expected<cv::Mat> depth = readImage(depth_file, camera_);
    if (!depth) return badFrame(depth.error());
    frame.depth = *depth;
    if (frame.depth.type() != CV_16UC1) {
      return badFrame(depth_file + ": depth must be a 16-bit single-channel image, this one is " +
                      std::to_string(frame.depth.elemSize1() * 8) + "-bit with " +
                      std::to_string(frame.depth.channels()) + " channel(s)");
    }
  }
  frame.utime = static_cast<int64_t>(std::llround(e.t_rgb * 1e6));
  frame.seq = static_cast<int64_t>(i);
  frame.depth_scale = camera_.depth_factor;
  frame.camera_name = camera_.name;
  result.status = FrameResult::Status::kFrame;
  return result;
}

double TumSource::nominalRateHz() const {
  if (entries_.size() < 2) return 30.0;
  const double span = entries_.back().t_rgb - entries_.front().t_rgb;
  return span > 0 ? (entries_.size() - 1) / span : 30.0;
}

std::string TumSource::describe() const {
  char rate[32];
  std::snprintf(rate, sizeof(rate), "%.1f", nominalRateHz());
  return "tum:" + dir_ + " (" + std::to_string(entries_.size()) + " frames, " + rate + " Hz)";
}

Expected<std::unique_ptr<TumSource>> openTumDataset(const std::string& dir,
                                                    const PinholeCamera& camera,
                                                    const TumOptions& options) {
  auto entries = readTumIndex(dir, options);
  if (!entries) return Error{entries.error()};
  return std::make_unique<TumSource>(dir, std::move(*entries), camera);
}

}  // namespace rgbdslam
