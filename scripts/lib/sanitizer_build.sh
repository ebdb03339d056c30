# Sourced by scripts/fuzz and scripts/sanitize: configures the instrumented build (clang,
# AddressSanitizer + UndefinedBehaviorSanitizer + libFuzzer coverage; -DRGBDSLAM_FUZZ=ON) in
# build-fuzz/ (or $RGBDSLAM_FUZZ_BUILD_DIR) and builds the named targets, two jobs at most.
# Sanitizer settings for what runs from it are exported here, so both scripts agree.
fuzz_build_dir=${RGBDSLAM_FUZZ_BUILD_DIR:-build-fuzz}
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0}

sanitizer_build() {  # sanitizer_build TARGET...
  mkdir -p "$fuzz_build_dir"
  CC=clang CXX=clang++ cmake -S . -B "$fuzz_build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DRGBDSLAM_FUZZ=ON -DRGBDSLAM_BUILD_BENCHMARKS=OFF > "$fuzz_build_dir/configure.log" 2>&1 \
    || { cat "$fuzz_build_dir/configure.log"; return 1; }
  cmake --build "$fuzz_build_dir" -j "$(( $(nproc) < 2 ? $(nproc) : 2 ))" --target "$@"
}
