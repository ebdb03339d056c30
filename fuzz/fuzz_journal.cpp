// libFuzzer target: the mapper's journal as a restarted mapper reads it: MapJournal::open,
// then every journaled keyframe through the wire check and the conversion.
#include "common/lcm_conversions.h"
#include "common/map_journal.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string dir = rgbdslam::fuzz::scratchPath("state");
  static const std::string path = [] {
    rgbdslam::MapJournal::Contents unused;
    (void)rgbdslam::MapJournal::open(dir, &unused);  // makes the folder
    return dir + "/map.journal";
  }();
  rgbdslam::fuzz::writeFile(path, data, size);
  rgbdslam::MapJournal::Contents contents;
  auto journal = rgbdslam::MapJournal::open(dir, &contents);
  if (!journal) return 0;
  for (const auto& bytes : contents.keyframes) {
    auto msg = rgbdslam::decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size());
    if (msg) (void)rgbdslam::fromLcm(*msg);
  }
  return 0;
}
