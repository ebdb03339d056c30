#pragma once
// Small valid messages of every subscribed type, made by the project's own encoders (toLcm),
// for the conversion tests and the fuzzers' seed corpora (fuzz/make_seeds.cpp). Images are
// 64x48 so a fuzzer's inputs stay small.
#include <cstdint>
#include <string>
#include <vector>

#include "common/lcm_conversions.h"

namespace rgbdslam::test {

RgbdFrame sampleFrame(int width = 64, int height = 48);  // random colour, depth 0..4 m
KeyframeData sampleKeyframe();    // keyframe 3 of map 1234: grey, depth, a measurement, a point
MapUpdate sampleMapUpdate();      // a snapshot: acknowledgements, a keyframe, points, removals
ComponentStatus sampleStatus();   // two counters, one timing
PoseEstimate samplePose();        // tracking, a pose away from the origin, its map pose another, part 42
MapReceipt sampleReceipt();       // map 1234: version 8 applied, 9 seen, keyframes 2..5 sendable

// Appends one event in the LCM log format (common/lcm_log_reader.h) to 'log'; a
// claimed_length >= 0 is written instead of the data's true length.
void appendLogEvent(std::vector<uint8_t>& log, int64_t number, const std::string& channel,
                    const std::vector<uint8_t>& data, int32_t claimed_length = -1);

template <typename T>
std::vector<uint8_t> encode(const T& msg) {
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace rgbdslam::test
