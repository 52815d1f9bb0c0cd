#!/usr/bin/env bash
# The libFuzzer targets of fuzz/ (see fuzz/README.md): builds them with clang in build-fuzz,
# makes their seed corpora, replays every saved case of fuzz/regressions/<target>/, then fuzzes
# each target for SECONDS. A crash, sanitizer report, leak, timeout or out-of-memory is saved
# in fuzz/regressions/<target>/ (commit it) and makes the script fail, after the other targets
# have run.
#
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET]     # default 60
#
# TRIDIFF_FUZZ_TARGETS="fuzz_solver_args ..." runs only those targets. The corpora grown by
# the runs stay in build-fuzz/fuzz-corpus/ for the next run; logs are in build-fuzz/fuzz-logs/.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds="${1:-60}"
case "$seconds" in
  ''|*[!0-9]*) echo "scripts/fuzz.sh: SECONDS_PER_TARGET must be a whole number, got '$seconds'" >&2
               exit 2 ;;
esac
build=build-fuzz
root="$PWD"
start=$SECONDS

bash scripts/deps.sh fuzz
# -O1 with line tables, as libFuzzer's documentation advises: a faster build than -O2 -g, and
# every report still names file and line.
CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTRIDIFF_FUZZ=ON \
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
      -DTRIDIFF_BUILD_TESTS=OFF -DTRIDIFF_BUILD_BENCH=OFF >/dev/null
# Only the fuzz targets and what they link, not the whole project; each on its own, so that
# a target that does not compile fails the script at the end, after the others have run.
read -r -a targets <<<"${TRIDIFF_FUZZ_TARGETS:-$(cat "$build/fuzz/targets.txt")}"
failed=()
built=()
for target in "${targets[@]}"; do
  if cmake --build "$build" -j"$(nproc)" --target "$target"; then
    built+=("$target")
  else
    echo "fuzz: $target: BUILD FAILED" >&2
    failed+=("$target (build)")
  fi
done
echo "fuzz: built ${built[*]} in $((SECONDS - start)) s"

# ---------------------------------------------------------------------------------------------
# Seed corpora, made afresh each run (nothing binary is committed).

# fuzz_image_read's input: byte 0 picks the extension (this order, fuzz_image_read.cpp) and
# the colour encoding, byte 1 the depth options, then the file.
extensions=(png jpg tif exr hdr bmp tga ppm)

# image_seed FILE OPTIONS_BYTE: FILE prefixed as fuzz_image_read expects.
image_seed() {
  local file=$1 options=$2 index
  for index in "${!extensions[@]}"; do [ "${extensions[index]}" = "${file##*.}" ] && break; done
  if [ "${extensions[index]}" != "${file##*.}" ]; then
    echo "fuzz: no extension byte for $file" >&2
    exit 1
  fi
  { printf "\\$(printf %03o "$index")\\$(printf %03o "$options")"; cat "$file"; } \
    > "$seeds/fuzz_image_read/$(basename "$file")-$options"
}

make_image_seeds() {
  local images="$build/fuzz-seeds/images"
  rm -rf "$images" && mkdir -p "$images" "$seeds/fuzz_image_read"
  # Tiny valid images of each format, channel layout and sample type the readers handle.
  local rgb="--pattern fill:topleft=0,0.2,1:topright=1,0.5,0:bottomleft=0.1,1,0.3"
  rgb+=":bottomright=1,1,1 3x2 3"
  local rgba="--pattern fill:top=0.2,0.4,0.6,1:bottom=0.9,0.1,0.5,0.25 3x2 4"
  local grey="--pattern fill:left=0.25:right=0.75 3x2 1"
  oiiotool --pattern constant:color=0.5,0.25,0.75 1x1 3 -d uint8 -o "$images/1x1.png"
  oiiotool $rgb -d uint8 -o "$images/rgb.png"
  oiiotool $rgba -d uint8 -o "$images/rgba.png"
  oiiotool $grey -d uint16 -o "$images/grey16.png"
  oiiotool $rgb -d uint8 -o "$images/rgb.jpg"
  oiiotool $grey -d uint8 -o "$images/grey.jpg"
  oiiotool $rgb -d uint16 -o "$images/rgb16.tif"
  oiiotool $rgba -d float -o "$images/rgba-float.tif"
  oiiotool $grey -d float -o "$images/grey-float.tif"
  oiiotool $rgb -d half -o "$images/rgb-half.exr"
  oiiotool $grey --chnames Z -d float -o "$images/z.exr"
  oiiotool $rgba --ch R,G,B,A,Z=1.5 -d half -o "$images/rgbaz.exr"
  oiiotool $rgb -o "$images/rgb.hdr"
  oiiotool $rgb -d uint8 -o "$images/rgb.bmp"
  oiiotool $rgba -d uint8 -o "$images/rgba.tga"
  oiiotool $rgb -d uint8 -o "$images/rgb.ppm"
  oiiotool $grey -d uint8 -o "$images/grey.ppm"  # a PGM (P5) under the .ppm extension
  for image in "$images"/*; do
    # Depth options 0 (linear, channel found by name) and 72 (normalized, planes 1 to 10).
    image_seed "$image" 0
    image_seed "$image" 72
  done
}

# fuzz_cli_args's input: argv[1..], one argument a line.
make_cli_seeds() {
  local dir="$seeds/fuzz_cli_args" n=0
  mkdir -p "$dir"
  while IFS= read -r line; do
    n=$((n + 1))
    tr ' ' '\n' <<<"$line" > "$dir/argv-$n"
  done <<'EOF'
--help
methods
dof --help
dof --focus 3 --f-number 2 -o out.png
dof --method adi --width 64 --height 48 --threads 1 -o out.exr --coc-output coc.exr
dof --method auto --psnr-budget 30 --layers --in-focus 1 --report report.json
dof --method mpad --no-skip --input-output input.png --max-coc 16 --focal-length 35
dof --color in.png --depth depth.exr --depth-channel Z --color-encoding srgb --max-pixels 1000
dof --color in.exr --depth in.exr --depth-convention normalized --near 1 --far 10
dof --depth-convention inverse --sensor-width 24 --focus 2.5
dof --near-start 1 --near-end 2 --near-radius 4 --far-start 5 --far-end 8 --far-radius 6
ipf --help
ipf --mask 5
ipf --program laplacian --parts 2 --check --threads 2 -o ipf.png
ipf --rule printed --in-focus 2 --area-weight-bits 8 --color-weight-bits 12 --register-size 64
ipf --clock-mhz 310 --bandwidth-gbs 20 --pixels-per-clock 2 --cycles-per-pixel 5
EOF
}

seeds="$build/fuzz-seeds"
rm -rf "$seeds" && mkdir -p "$seeds"
make_image_seeds
make_cli_seeds

# ---------------------------------------------------------------------------------------------
# Replay, then fuzz.

# Worker threads sleep instead of spinning (the tests may run beside the fuzzer on 2 cores),
# and OpenMP teams are capped at 4 threads: the solvers still see and check any `threads`
# argument, but a team of a thousand on two cores would make the fuzzer crawl.
export OMP_WAIT_POLICY=passive OMP_THREAD_LIMIT=4
# OpenImageIO allocates a 64 MiB buffer for every read that converts to float, whatever the
# image size; AddressSanitizer writes 8 MiB of shadow for it three times. Huge pages for the
# shadow halve the image target's time (measured: 300 runs in 31 s -> 13 s), finding the same.
asan_options=detect_leaks=1:no_huge_pages_for_shadow=0
export LSAN_OPTIONS="suppressions=$root/fuzz/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# fuzz_image_read's scratch folders (one per process) go here, not to /tmp: a crashing process
# cannot remove its own.
export TMPDIR="$root/$build/fuzz-tmp"
rm -rf "$TMPDIR" && mkdir -p "$TMPDIR"
limits=(-rss_limit_mb=2048 -timeout=10)

# fuzz_image_read differs in two ways, both for the libraries under OpenImageIO:
# - No leak check: OpenImageIO's PNG reader leaks a std::string per truncated PNG (libpng's
#   longjmp skips its destructor). Measured with a program of OpenImageIO calls alone
#   (ImageInput::open, read_image, geterror): 31 bytes per read.
# - A malloc() of more than 256 MiB returns null, as on a machine without that memory: libpng
#   allocates what a chunk header declares (1.4 GB, 11 s in plain oiiotool, for a 300-byte
#   PNG) and handles the null as an error. A C++ `new` that large, in tridiff or OpenEXR, is
#   still reported at once (with 2^16 pixels tridiff needs a few MiB; OpenImageIO 64 MiB).
image_asan_options="${asan_options/detect_leaks=1/detect_leaks=0}"
image_asan_options+=:allocator_may_return_null=1:max_allocation_size_mb=256
asan_options_for() {
  if [ "$1" = fuzz_image_read ]; then echo "$image_asan_options"; else echo "$asan_options"; fi
}

mkdir -p "$build/fuzz-logs"

# fuzz TARGET ARGS...: the target with its environment, run in the scratch folder so that a
# stray relative write (`-o out.png` in a command line) cannot land in the repository.
# $extra_asan_options is appended to the target's ASAN_OPTIONS.
fuzz() {
  local target=$1
  shift
  (cd "$TMPDIR" && ASAN_OPTIONS=$(asan_options_for "$target")${extra_asan_options:-} \
     "$root/$build/fuzz/$target" "${limits[@]}" "$@")
}

# replay TARGET: every saved case, one process each so that all of them are reported.
replay() {
  local target=$1 case_file status=0 log="$build/fuzz-logs/$1-replay.log"
  for case_file in fuzz/regressions/"$target"/*; do
    [ -f "$case_file" ] && [ "$(basename "$case_file")" != README.md ] || continue
    # Full stacks for allocations (too slow while fuzzing): an allocation made in a library
    # without frame pointers is then traced to its caller.
    if ! extra_asan_options=:fast_unwind_on_malloc=0 fuzz "$target" "$root/$case_file" \
         > "$log" 2>&1; then
      echo "fuzz: $target: regression case $case_file FAILS:"
      grep -v '^INFO:' "$log" | tail -n 40
      status=1
    fi
  done
  return $status
}

# run TARGET: fuzz for $seconds, new findings into fuzz/regressions/TARGET/.
run() {
  local target=$1 log="$build/fuzz-logs/$1.log" corpus="$root/$build/fuzz-corpus/$1"
  mkdir -p "$corpus" "fuzz/regressions/$target" "$seeds/$target"
  local status=0 saved
  saved=$(ls "fuzz/regressions/$target" | tr '\n' ' ')  # the cases from before this run
  # New corpus entries go to the first folder; the seeds are read only.
  fuzz "$target" -max_total_time="$seconds" -print_final_stats=1 \
    -artifact_prefix="$root/fuzz/regressions/$target/" "$corpus" "$root/$seeds/$target" \
    > "$log" 2>&1 || status=$?
  local runs speed
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
  if ((status)) && [ "$target" = fuzz_image_read ] && grep -q "out-of-memory" "$log"; then
    # An allocation the size a damaged header declares, made inside OpenEXR or another codec
    # before tridiff sees a pixel (tridiff's own checks cover what they can: the pixel limit,
    # OpenEXR attribute sizes). Reported and kept apart in fuzz/upstream-oom/, not replayed:
    # the bytes are there for the next guard, and CI does not fail on another library's
    # allocator. Crashes, sanitizer reports and timeouts still fail.
    mkdir -p "fuzz/upstream-oom/$target"
    local found
    for found in "fuzz/regressions/$target"/*; do
      [[ " $saved " == *" $(basename "$found") "* ]] || mv "$found" "fuzz/upstream-oom/$target/"
    done
    echo "fuzz: $target: WARNING: out of memory inside a codec after ${runs:-?} runs; input" \
         "kept in fuzz/upstream-oom/$target/ (see fuzz/README.md):"
    grep -E "out-of-memory|in Imf_|in OpenImageIO|readValueFrom|png_" "$log" | head -n 12
    return 0
  fi
  if ((status)); then
    echo "fuzz: $target: FAILED (exit $status) after ${runs:-?} runs; the end of $log:"
    grep -v -e '^#[0-9]' -e '^INFO:' "$log" | tail -n 60
    return 1
  fi
  echo "fuzz: $target: ${runs:-?} runs in ${seconds} s (${speed:-?}/s)," \
       "corpus $(ls "$corpus" | wc -l) inputs"
}

for target in ${built[@]+"${built[@]}"}; do
  replay "$target" || { failed+=("$target (regressions)"); continue; }
  run "$target" || failed+=("$target")
done

echo "fuzz: done in $((SECONDS - start)) s"
if ((${#failed[@]})); then
  echo "fuzz: FAILED: ${failed[*]}" >&2
  echo "fuzz: a new failing input is in fuzz/regressions/<target>/: commit it" >&2
  exit 1
fi
