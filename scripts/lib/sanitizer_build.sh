# Sourced by scripts/fuzz and scripts/sanitize: configures and builds an instrumented build,
# two jobs at most, and exports the sanitizer settings both scripts run with. The compiler
# flags (-O1, line tables only, unity builds) are in cmake/instrumented_build.cmake.
#   fuzz_build TARGET...  clang, ASan + UBSan + libFuzzer coverage (-DRGBDSLAM_FUZZ=ON), in
#                         build-fuzz/ ($RGBDSLAM_FUZZ_BUILD_DIR)
#   asan_build TARGET...  the project's compiler (gcc), ASan + UBSan (-DRGBDSLAM_SANITIZE=ON),
#                         in build-asan/ ($RGBDSLAM_ASAN_BUILD_DIR). The unit tests run here,
#                         not under clang: their accuracy thresholds were measured with gcc,
#                         and clang's code moved two mapper figures past them.
fuzz_build_dir=${RGBDSLAM_FUZZ_BUILD_DIR:-build-fuzz}
asan_build_dir=${RGBDSLAM_ASAN_BUILD_DIR:-build-asan}
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

instrumented_build() {  # instrumented_build DIR "CMAKE ARGS" TARGET...
  local dir=$1 args=$2 start=$SECONDS
  shift 2
  mkdir -p "$dir"
  # shellcheck disable=SC2086
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRGBDSLAM_BUILD_BENCHMARKS=OFF $args \
      > "$dir/configure.log" 2>&1 || { cat "$dir/configure.log"; return 1; }
  cmake --build "$dir" -j "$(( $(nproc) < 2 ? $(nproc) : 2 ))" --target "$@"
  echo "== $dir: $* configured and built in $((SECONDS - start)) s"
}
fuzz_build() { CC=clang CXX=clang++ instrumented_build "$fuzz_build_dir" -DRGBDSLAM_FUZZ=ON "$@"; }
asan_build() { instrumented_build "$asan_build_dir" -DRGBDSLAM_SANITIZE=ON "$@"; }
