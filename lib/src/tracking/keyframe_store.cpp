#include "rgbdslam/tracking/keyframe_store.h"

#include <fcntl.h>
#include <linux/magic.h>
#include <sys/stat.h>
#include <sys/vfs.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace rgbdslam {
namespace {

uint32_t crcOf(const uint8_t* data, size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes at most 4 GB a call; an entry is a keyframe's image or extras (kilobytes).
  while (size > 0) {
    const uInt chunk = static_cast<uInt>(std::min<size_t>(size, 1u << 30));
    crc = crc32(crc, data, chunk);
    data += chunk;
    size -= chunk;
  }
  return static_cast<uint32_t>(crc);
}

}  // namespace

Expected<std::unique_ptr<KeyframeStore>> KeyframeStore::open(const std::string& directory) {
  if (directory.empty()) return Error{"keyframe store: no directory given"};
  int fd = ::open(directory.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
    // A file system without O_TMPFILE: a named file, unlinked at once.
    std::string path = directory + "/rgbd-keyframes.XXXXXX";
    fd = ::mkostemp(path.data(), O_CLOEXEC);
    if (fd >= 0) ::unlink(path.c_str());
  }
  if (fd < 0) {
    return Error{"keyframe store: cannot make a file in '" + directory + "': " + std::strerror(errno)};
  }
  auto store = std::unique_ptr<KeyframeStore>(new KeyframeStore(fd));
  struct stat st {};
  if (::fstat(fd, &st) == 0 && st.st_blksize > 0) store->block_ = st.st_blksize;
  struct statfs fs {};
  store->in_memory_ = ::fstatfs(fd, &fs) == 0 && (fs.f_type == TMPFS_MAGIC || fs.f_type == RAMFS_MAGIC);
  return store;
}

KeyframeStore::~KeyframeStore() {
  if (fd_ >= 0) ::close(fd_);
}

bool KeyframeStore::put(KeyframeId id, Kind kind, const std::vector<uint8_t>& bytes, bool release_later) {
  if (full_) return false;
  // Each entry starts on a block of its own, so that removing it gives all its blocks back.
  const int64_t start = (end_ + block_ - 1) / block_ * block_;
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::pwrite(fd_, bytes.data() + written, bytes.size() - written,
                               static_cast<off_t>(start + static_cast<int64_t>(written)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {  // storage full or failing: what was written of it is given back, the old entry stays
      release(Entry{start, static_cast<int64_t>(written), 0});
      ++errors_;
      full_ = true;
      return false;
    }
    written += static_cast<size_t>(n);
  }
  if (const auto old = index_.find(key(id, kind)); old != index_.end()) {  // replaced
    if (release_later) {
      queued_.push_back(old->second);
    } else {
      release(old->second);
    }
    live_bytes_ -= old->second.size;
    --kind_entries_[static_cast<size_t>(kind)];
    index_.erase(old);
  }
  const Entry entry{start, static_cast<int64_t>(bytes.size()), crcOf(bytes.data(), bytes.size())};
  index_[key(id, kind)] = entry;
  ++kind_entries_[static_cast<size_t>(kind)];
  end_ = start + entry.size;
  live_bytes_ += entry.size;
  return true;
}

Expected<std::vector<uint8_t>> KeyframeStore::get(KeyframeId id, Kind kind) {
  const auto it = index_.find(key(id, kind));
  static const char* const kNames[kKinds] = {" image", " extras", " message", " points"};
  const std::string what = "keyframe store: keyframe " + std::to_string(id) + kNames[static_cast<size_t>(kind)];
  if (it == index_.end()) return Error{what + ": not stored"};
  const Entry entry = it->second;
  std::vector<uint8_t> bytes(static_cast<size_t>(entry.size));
  size_t read = 0;
  std::string failure;
  while (read < bytes.size()) {
    const ssize_t n = ::pread(fd_, bytes.data() + read, bytes.size() - read,
                              static_cast<off_t>(entry.offset + static_cast<int64_t>(read)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      failure = "read failed (" + (n < 0 ? std::string(std::strerror(errno)) : std::string("short file")) + ")";
      break;
    }
    read += static_cast<size_t>(n);
  }
  if (failure.empty() && crcOf(bytes.data(), bytes.size()) != entry.crc) {
    failure = "the storage returned other bytes (CRC mismatch)";
  }
  if (failure.empty()) return bytes;
  // Counted once: the entry goes, and its keyframe goes on without it.
  ++errors_;
  remove(id, kind);
  return Error{what + ": " + failure};
}

void KeyframeStore::remove(KeyframeId id) {
  for (size_t kind = 0; kind < kKinds; ++kind) remove(id, static_cast<Kind>(kind));
}

void KeyframeStore::removeLater(KeyframeId id) {
  for (size_t kind = 0; kind < kKinds; ++kind) removeLater(id, static_cast<Kind>(kind));
}

void KeyframeStore::removeLater(KeyframeId id, Kind kind) {
  const auto it = index_.find(key(id, kind));
  if (it == index_.end()) return;
  queued_.push_back(it->second);
  live_bytes_ -= it->second.size;
  --kind_entries_[static_cast<size_t>(kind)];
  index_.erase(it);
  full_ = false;
}

uint32_t KeyframeStore::checksum(const std::vector<uint8_t>& bytes) { return crcOf(bytes.data(), bytes.size()); }

size_t KeyframeStore::releaseQueued(size_t max) {
  for (size_t done = 0; done < max && !queued_.empty(); ++done) {
    release(queued_.back());
    queued_.pop_back();
  }
  return queued_.size();
}

void KeyframeStore::remove(KeyframeId id, Kind kind) {
  const auto it = index_.find(key(id, kind));
  if (it == index_.end()) return;
  release(it->second);
  live_bytes_ -= it->second.size;
  --kind_entries_[static_cast<size_t>(kind)];
  index_.erase(it);
  full_ = false;  // room again, perhaps
}

void KeyframeStore::clear() {
  index_.clear();
  queued_.clear();  // the file is cut below: those bytes go with it
  kind_entries_ = {};
  live_bytes_ = 0;
  full_ = false;
  if (end_ > 0 && ::ftruncate(fd_, 0) == 0) end_ = 0;
}

int64_t KeyframeStore::diskBytes() const {
  struct stat st {};
  return ::fstat(fd_, &st) == 0 ? static_cast<int64_t>(st.st_blocks) * 512 : -1;
}

void KeyframeStore::release(const Entry& entry) {
  if (entry.size <= 0) return;
  // A file system that cannot punch holes (FAT) keeps the bytes until the process ends:
  // diskBytes() shows it.
  ::fallocate(fd_, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, static_cast<off_t>(entry.offset),
              static_cast<off_t>(entry.size));
}

}  // namespace rgbdslam
