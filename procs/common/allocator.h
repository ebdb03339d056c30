#pragma once
// The processes' memory allocator. Every program that links procs/common (the processes,
// the test tools, the benchmarks) runs on jemalloc (Debian's libjemalloc2), with its purging
// on background threads of its own, turned on as the program starts (allocator.cpp). The
// sanitizer and fuzzing builds link no jemalloc: their runtimes bring their own malloc.
//
// Why not glibc's malloc: over a long flight the onboard tracker allocates and frees frames,
// images and pyramids on several threads. glibc gives each thread an arena of its own and
// keeps what it frees resident there, so the tracker's resident memory rose after the first
// minute with its threads' high-water marks, not its data (80.8 -> 96.8 MiB over the
// ten-minute flight, docs/open_work.md, session 42), and glibc's remedies each cost latency
// or gave little back (docs/design.md, "The allocator"). jemalloc gives pages freed for a
// while (dirty_decay_ms, 10 s by default) back to the system from its background threads,
// off the frame path (blocks of 8 MiB and more excepted: jemalloc 5.3 purges those at once,
// on the freeing thread; the frame path's largest is LCM's 1.5 MB frame buffer). Measured:
// docs/open_work.md, session 43.
#include <cstdint>

namespace rgbdslam {

// Whether jemalloc's background threads purge freed pages (false in the instrumented builds,
// or if they could not start: allocator.cpp warns on stderr then).
bool allocatorPurgesInBackground();

// What the program holds from malloc now [kB]: jemalloc's stats.allocated. Resident memory
// well above it is memory the allocator keeps for reuse, not the program's data. -1 where
// the allocator does not say (the sanitizers').
int64_t heapInUseKb();

}  // namespace rgbdslam
