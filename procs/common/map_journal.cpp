#include "common/map_journal.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>

namespace rgbdslam {
namespace {

constexpr uint8_t kMagic[3] = {'M', 'J', '1'};
constexpr uint8_t kKeyframeRecord = 1;
constexpr uint8_t kVersionRecord = 2;
constexpr uint8_t kCulledRecord = 3;
constexpr size_t kHeaderSize = 12;                   // magic 3 + type 1 + length 4 + crc 4
constexpr uint32_t kMaxRecordBytes = 256u << 20;     // larger claimed lengths are corrupt

void putU32(uint8_t* out, uint32_t value) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(value >> (8 * i));
}

uint32_t getU32(const uint8_t* in) {
  uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value |= static_cast<uint32_t>(in[i]) << (8 * i);
  return value;
}

uint32_t crcOf(const uint8_t* data, size_t size) {
  return static_cast<uint32_t>(crc32(0L, data, static_cast<uInt>(size)));
}

std::string errnoText(const std::string& what, const std::string& path) {
  return what + " " + path + ": " + std::strerror(errno);
}

// The whole journal; none yet is empty. Anything but a regular file (a directory, a FIFO, a
// device) is an error: reading a directory through a stream throws.
Expected<std::vector<uint8_t>> readJournal(const std::string& path) {
  std::vector<uint8_t> bytes;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    if (errno == ENOENT) return bytes;
    return Error{errnoText("cannot open", path)};
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    return Error{path + ": is not a regular file (a directory or a device?); move it aside or use --fresh"};
  }
  uint8_t chunk[1 << 16];
  for (ssize_t n; (n = ::read(fd, chunk, sizeof chunk)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string error = errnoText("cannot read", path);
      ::close(fd);
      return Error{error};
    }
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  ::close(fd);
  return bytes;
}

}  // namespace

Expected<MapJournal> MapJournal::open(const std::string& dir, Contents* contents) {
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) return Error{errnoText("cannot create", dir)};
  const std::string path = dir + "/map.journal";
  *contents = Contents{};
  auto read = readJournal(path);
  if (!read) return Error{read.error()};
  const std::vector<uint8_t>& bytes = *read;
  size_t offset = 0;
  while (offset < bytes.size()) {
    const uint8_t* record = bytes.data() + offset;
    const size_t left = bytes.size() - offset;
    if (left < kHeaderSize || std::memcmp(record, kMagic, 3) != 0) break;
    const uint32_t length = getU32(record + 4);
    if (length > kMaxRecordBytes || left - kHeaderSize < length) break;
    const uint8_t* payload = record + kHeaderSize;
    if (crcOf(payload, length) != getU32(record + 8)) break;
    if (record[3] == kKeyframeRecord) {
      contents->keyframes.emplace_back(payload, payload + length);
    } else if (record[3] == kVersionRecord && length == 8) {
      int64_t version = 0;
      std::memcpy(&version, payload, 8);
      contents->last_version = version;
    } else if (record[3] == kCulledRecord && length % 8 == 0) {
      for (size_t i = 0; i < length; i += 8) {
        int64_t id = 0;
        std::memcpy(&id, payload + i, 8);
        contents->culled.push_back(id);
      }
    } else {
      break;
    }
    offset += kHeaderSize + length;
  }
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return Error{errnoText("cannot open", path)};
  if (offset < bytes.size()) {
    contents->warning = path + ": dropped " + std::to_string(bytes.size() - offset) +
                        " bytes of a torn or corrupt record at offset " + std::to_string(offset);
    if (::ftruncate(fd, static_cast<off_t>(offset)) != 0) {
      const std::string error = errnoText("cannot truncate", path);
      ::close(fd);
      return Error{error};
    }
  }
  if (::lseek(fd, static_cast<off_t>(offset), SEEK_SET) < 0) {
    const std::string error = errnoText("cannot seek", path);
    ::close(fd);
    return Error{error};
  }
  return MapJournal(fd, path);
}

MapJournal::MapJournal(MapJournal&& other) noexcept : fd_(other.fd_), path_(std::move(other.path_)) {
  other.fd_ = -1;
}

MapJournal& MapJournal::operator=(MapJournal&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_, path_ = std::move(other.path_);
    other.fd_ = -1;
  }
  return *this;
}

MapJournal::~MapJournal() {
  if (fd_ >= 0) ::close(fd_);
}

Status MapJournal::appendKeyframe(const IncomingKeyframe& keyframe) {
  if (keyframe.encoded.empty()) return Error{path_ + ": a keyframe without its message cannot be journaled"};
  return appendKeyframe(keyframe.encoded.data(), keyframe.encoded.size());
}

Status MapJournal::appendKeyframe(const void* data, size_t size) {
  return append(kKeyframeRecord, data, size);
}

Status MapJournal::appendVersion(int64_t version) {
  return append(kVersionRecord, &version, sizeof version);
}

Status MapJournal::appendCulled(const std::vector<KeyframeId>& ids) {
  static_assert(sizeof(KeyframeId) == 8, "journal records hold 64-bit ids");
  return append(kCulledRecord, ids.data(), ids.size() * sizeof(KeyframeId));
}

Status MapJournal::append(uint8_t type, const void* data, size_t size) {
  if (size > kMaxRecordBytes) return Error{"journal record of " + std::to_string(size) + " bytes is too large"};
  std::vector<uint8_t> record(kHeaderSize + size);
  std::memcpy(record.data(), kMagic, 3);
  record[3] = type;
  putU32(record.data() + 4, static_cast<uint32_t>(size));
  if (size > 0) std::memcpy(record.data() + kHeaderSize, data, size);
  putU32(record.data() + 8, crcOf(record.data() + kHeaderSize, size));
  const off_t start = ::lseek(fd_, 0, SEEK_CUR);
  const ssize_t written = ::write(fd_, record.data(), record.size());
  if (written != static_cast<ssize_t>(record.size())) {
    const std::string error = errnoText("cannot write", path_);
    if (start >= 0 && ::ftruncate(fd_, start) == 0) ::lseek(fd_, start, SEEK_SET);  // no torn record
    return Error{error};
  }
  if (::fdatasync(fd_) != 0) return Error{errnoText("cannot sync", path_)};
  return Status{};
}

}  // namespace rgbdslam
