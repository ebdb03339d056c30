#pragma once
// The processes' memory allocator. Every process of the suite (procs/) runs on jemalloc
// (Debian's libjemalloc2, linked into procs/common; not in the sanitizer and fuzzing builds,
// whose runtimes bring their own malloc), configured here at start, before main.
//
// Why not glibc's malloc: over a long flight the onboard tracker allocates and frees frames,
// images and pyramids on several threads. glibc gives each thread an arena of its own and
// keeps what it frees resident there, so the tracker's resident memory rose after the first
// minute with its threads' high-water marks, not its data (80.8 -> 96.8 MiB over the
// ten-minute flight, docs/open_work.md, session 42), and glibc's remedies each cost latency
// or gave little back (docs/design.md, "The allocator"). jemalloc gives pages freed for a while
// (dirty_decay_ms, 10 s by default) back to the system on a background thread of its own
// (background_thread:true, set here), off the frame path. Measured: docs/open_work.md,
// session 43.
#include <cstdint>
#include <string>

namespace rgbdslam {

// The allocator built in: "jemalloc", or "glibc" / "sanitizer" in the builds without it.
std::string allocatorName();

// What the program holds from malloc now [kB]: jemalloc's stats.allocated (glibc's
// mallinfo2, blocks in use plus mapped ones, in builds without jemalloc). Resident memory
// well above it is memory the allocator keeps for reuse, not the program's data. -1 where
// the allocator does not say (the sanitizers').
int64_t heapInUseKb();

}  // namespace rgbdslam
