#pragma once
// Hamming distance of two 256-bit binary descriptors (ORB's 32 bytes), inline: matching a
// frame's features against a keyframe's by brute force computes it 250 000 times, where
// cv::hal::normHamming's call (with OpenCV's trace region) cost more than the counting
// (bench_place_recognition: one verification's matching ~1.5 ms through it).
#include <cstdint>
#include <cstring>

namespace rgbdslam {

constexpr int kBinaryDescriptorBytes = 32;

// Bits set in a 64-bit word. Where the target has a population-count instruction (x86-64
// built with POPCNT, AArch64) the builtin is one instruction; on the x86-64 baseline (Debian's
// default flags) the builtin is a call into libgcc, slower than this bit-parallel count.
inline int popcount64(uint64_t x) {
#if defined(__POPCNT__) || defined(__aarch64__)
  return __builtin_popcountll(x);
#else
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
#endif
}

inline int hamming256(const uint8_t* a, const uint8_t* b) {
  int distance = 0;
  for (int word = 0; word < kBinaryDescriptorBytes / 8; ++word) {
    uint64_t x, y;
    std::memcpy(&x, a + 8 * word, 8);
    std::memcpy(&y, b + 8 * word, 8);
    distance += popcount64(x ^ y);
  }
  return distance;
}

}  // namespace rgbdslam
