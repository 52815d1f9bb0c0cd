#!/usr/bin/env bash
# Tests of the `tridiff` command line, run by CTest:
#   cli_test.sh TRIDIFF_BINARY WORK_DIR CASE
# CASE is one of: help, dof, roundtrip, errors, outputs, hostile, ipf, options, lens, views
# and formats. Every check prints what it ran
# and what it saw when it fails; the script exits non-zero if any check failed.
set -u

tridiff=$1
work=$2
case_name=$3

failures=0
fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

# run ARGS...: runs tridiff, leaving its exit status in $status and its output in $out/$err.
run() {
  out=$("$tridiff" "$@" 2>"$work/stderr.txt")
  status=$?
  err=$(cat "$work/stderr.txt")
  rm -f "$work/stderr.txt"
}

# run_file_limited KIB ARGS...: run, with files limited to KIB KiB (a write past the limit
# fails as it would on a full disk).
run_file_limited() {
  local kib=$1
  shift
  out=$( (ulimit -f "$kib" && exec "$tridiff" "$@") 2>"$work/stderr.txt")
  status=$?
  err=$(cat "$work/stderr.txt")
  rm -f "$work/stderr.txt"
}

expect_status() {  # expect_status WANT DESCRIPTION  (WANT: 0 or "nonzero")
  if [[ $1 == 0 && $status -ne 0 ]]; then
    fail "$2: exit $status, expected 0; stderr: $err"
  elif [[ $1 == nonzero && $status -eq 0 ]]; then
    fail "$2: exit 0, expected a failure; stdout: $out"
  fi
}

expect_in() {  # expect_in TEXT NEEDLE DESCRIPTION
  if [[ $1 != *"$2"* ]]; then fail "$3: '$2' not found in: $1"; fi
}

expect_file() {  # a non-empty file
  if [[ ! -s $1 ]]; then fail "$2: $1 missing or empty"; fi
}

expect_size() {  # expect_size FILE "W x H"
  if command -v oiiotool >/dev/null; then
    local info
    info=$(oiiotool --info "$1" 2>&1)
    # oiiotool pads the numbers: "160 x  90".
    if [[ $(echo "$info" | tr -s ' ') != *"$2"* ]]; then
      fail "$1: expected $2, oiiotool says: $info"
    fi
  fi
}

# The folder holds exactly the files named (nothing partial, no temporary files).
expect_only_files() {  # expect_only_files DIR FILE...
  local dir=$1
  shift
  local have want
  have=$(cd "$dir" && ls -A | sort | tr '\n' ' ')
  want=$(printf '%s\n' "$@" | sed '/^$/d' | sort | tr '\n' ' ')
  if [[ $have != "$want" ]]; then fail "$dir holds [$have], expected [$want]"; fi
}

need_oiiotool() {
  if ! command -v oiiotool >/dev/null; then
    echo "oiiotool not found: cannot make depth files" >&2
    exit 1
  fi
}

# pixel_of FILE X Y: the values of pixel (X, Y) of FILE, space separated; for an integer file
# as 0..1 (oiiotool prints those in parentheses after the integers).
pixel_of() {
  oiiotool --dumpdata "$1" 2>/dev/null | sed -n "s/^ *Pixel ($2, $3): \(.*\)/\1/p" |
    sed 's/.*(\(.*\))$/\1/; s/ *$//'
}

# expect_pixel FILE X Y "R G B" TOLERANCE DESCRIPTION: each channel within TOLERANCE.
expect_pixel() {
  local have
  have=$(pixel_of "$1" "$2" "$3")
  if ! awk -v have="$have" -v want="$4" -v tol="$5" 'BEGIN {
      n = split(have, h, " "); m = split(want, w, " ");
      if (n != m) exit 1;
      for (i = 1; i <= n; i++) if (h[i] - w[i] > tol || w[i] - h[i] > tol) exit 1 }'; then
    fail "$6: pixel ($2, $3) of $1 is [$have], expected [$4] within $5"
  fi
}

rm -rf "$work"
mkdir -p "$work"

case $case_name in
help)
  run --help
  expect_status 0 "tridiff --help"
  expect_in "$out" "--focus" "tridiff --help"
  expect_in "$out" "--method" "tridiff --help"
  run dof --help
  expect_status 0 "tridiff dof --help"
  expect_in "$out" "--focus" "tridiff dof --help"
  for option in --focus-at --focus-range --view --float focal-plane; do
    expect_in "$out" "$option" "tridiff dof --help"
  done
  run methods
  expect_status 0 "tridiff methods"
  expect_in "$out" "adi" "tridiff methods"
  expect_in "$out" "mpad" "tridiff methods"
  run bogus
  expect_status nonzero "tridiff bogus"
  expect_in "$err" "bogus" "tridiff bogus"
  ;;

dof)
  d=$work/out
  mkdir -p "$d"
  run dof --width 160 --height 90 -o "$d/out.png" --report "$d/r.json"
  expect_status 0 "dof on the built-in scene"
  expect_file "$d/out.png" "dof"
  expect_file "$d/out_coc.png" "dof"
  expect_size "$d/out.png" "160 x 90"
  expect_size "$d/out_coc.png" "160 x 90"
  expect_file "$d/r.json" "dof --report"
  json=$(cat "$d/r.json" 2>/dev/null)
  expect_in "$json" '"skipped_fraction"' "report"
  expect_in "$json" '"method": "bokeh"' "report"  # the default method
  expect_in "$json" '"layered": true' "report"      # with its layers by default
  expect_in "$out" "skipped" "stdout summary"
  l=$work/layers
  mkdir -p "$l"
  run dof --width 40 --height 30 -o "$l/nl.png" --no-layers --report "$l/nl.json"
  expect_status 0 "dof --no-layers"
  expect_in "$(cat "$l/nl.json" 2>/dev/null)" '"layered": false' "--no-layers report"
  run dof --width 40 --height 30 -o "$l/both.png" --layers --no-layers
  expect_status nonzero "--layers with --no-layers"
  expect_in "$err" "--no-layers" "--layers with --no-layers"
  [ -e "$l/both.png" ] && fail "--layers with --no-layers wrote an output"
  if command -v python3 >/dev/null; then
    python3 -c 'import json, sys
r = json.load(open(sys.argv[1]))
assert 0 <= r["skipped_fraction"] <= 1' "$d/r.json" ||
      fail "r.json is not valid JSON with skipped_fraction in [0, 1]"
  fi
  expect_only_files "$d" out.png out_coc.png r.json

  run dof --width 160 --height 90 --method mpad --max-coc 8 -o "$d/mpad.png" --report "$d/mpad.json"
  expect_status 0 "dof --method mpad --max-coc 8"
  expect_file "$d/mpad.png" "mpad"
  expect_file "$d/mpad_coc.png" "mpad"
  json=$(cat "$d/mpad.json" 2>/dev/null)
  expect_in "$json" '"method": "mpad"' "mpad report"
  # |CoC| <= 8 -> beta <= 64/32 = 2 -> at most 8 explicit steps of 0.25 (at 160 px wide the
  # scene's largest |CoC| is about 5.4 px: 4 steps).
  steps=$(echo "$json" | sed -n 's/.*"explicit_steps": \([0-9]*\).*/\1/p')
  if [[ -z $steps || $steps -lt 1 || $steps -gt 8 ]]; then
    fail "mpad --max-coc 8: explicit_steps '$steps' not in [1, 8]"
  fi
  run dof --width 160 --height 90 --method mpad --max-coc 8 --f-number 0.5 -o "$d/mpad8.png" \
    --report "$d/mpad8.json"
  expect_status 0 "dof --method mpad --max-coc 8 --f-number 0.5"
  # f/0.5 puts the twig at ~19 px, clamped to 8: exactly 8 steps.
  expect_in "$(cat "$d/mpad8.json" 2>/dev/null)" '"explicit_steps": 8' "mpad report at the clamp"

  run dof --width 160 --height 90 --layers -o "$d/layers.png" --report "$d/layers.json"
  expect_status 0 "dof --layers"
  expect_file "$d/layers.png" "layers"
  # The scene has a twig in the near field: layering happens.
  expect_in "$(cat "$d/layers.json" 2>/dev/null)" '"layered": true' "layers report"

  run dof --width 160 --height 90 -o "$d/out.exr" --coc-output "$d/coc.exr"
  expect_status 0 "dof with EXR output"
  expect_file "$d/out.exr" "EXR output"
  expect_file "$d/coc.exr" "EXR CoC output"
  if command -v oiiotool >/dev/null; then
    info=$(oiiotool --info "$d/out.exr" 2>&1)
    expect_in "$info" "openexr" "out.exr format"
  fi
  ;;

roundtrip)
  need_oiiotool
  d=$work
  run dof --width 160 --height 90 --input-output "$d/in.exr" -o "$d/o1.png"
  expect_status 0 "dof writing the input"
  expect_file "$d/in.exr" "--input-output"
  expect_size "$d/in.exr" "160 x 90"
  oiiotool --pattern constant:color=2.0 160x90 1 -d float -o "$d/depth.exr" || fail "oiiotool depth"
  run dof --color "$d/in.exr" --depth "$d/depth.exr" -o "$d/o2.png" --focus 2 --report "$d/r2.json"
  expect_status 0 "dof from files"
  expect_file "$d/o2.png" "dof from files"
  expect_file "$d/o2_coc.png" "dof from files"
  expect_size "$d/o2.png" "160 x 90"
  # All at the focus distance: nothing to blur, every pixel skipped.
  expect_in "$(cat "$d/r2.json" 2>/dev/null)" '"skipped_fraction": 1' "in-focus depth"
  run dof --color "$d/in.exr" --depth "$d/depth.exr" -o "$d/o3.png" --focus 1 --method mpad --layers
  expect_status 0 "dof from files, mpad with layers"
  expect_file "$d/o3.png" "dof from files, mpad"
  ;;

errors)
  need_oiiotool
  d=$work/e
  mkdir -p "$d"
  make=(oiiotool --pattern)
  "${make[@]}" constant:color=2.0 160x90 1 -d float -o "$work/depth.exr" || fail "oiiotool"
  "${make[@]}" constant:color=2.0 80x45 1 -d float -o "$work/small_depth.exr" || fail "oiiotool"
  oiiotool --pattern constant:color=2.0 160x90 1 --fill:color=-1 1x1+5+7 -d float \
    -o "$work/negative_depth.exr" || fail "oiiotool"
  "${make[@]}" constant:color=0.3,0.5,0.7 160x90 3 -d half -o "$work/color.exr" || fail "oiiotool"

  run dof --color "$d/missing.exr" --depth "$work/depth.exr" -o "$d/x.png"
  expect_status nonzero "missing --color file"
  expect_in "$err" "missing.exr" "missing --color file"
  expect_only_files "$d"  # no x.png, no x_coc.png, no temporary file

  run dof --color "$work/color.exr" --depth "$d/nodepth.exr" -o "$d/x.png"
  expect_status nonzero "missing --depth file"
  expect_in "$err" "nodepth.exr" "missing --depth file"
  expect_only_files "$d"

  run dof --width 32 --height 18 --method nope -o "$d/x.png"
  expect_status nonzero "--method nope"
  expect_in "$err" "nope" "--method nope"
  expect_in "$err" "adi" "--method nope"
  expect_in "$err" "mpad" "--method nope"
  expect_only_files "$d"

  run dof --width 32 --height 18 --focus abc -o "$d/x.png"
  expect_status nonzero "--focus abc"
  expect_in "$err" "--focus" "--focus abc"
  expect_in "$err" "abc" "--focus abc"
  expect_only_files "$d"

  run dof --width 32 --height 18 --focus 0.01 -o "$d/x.png"
  expect_status nonzero "--focus inside the focal length"
  expect_in "$err" "focus" "--focus 0.01"
  expect_only_files "$d"

  run dof --color "$work/color.exr" --depth "$work/small_depth.exr" -o "$d/x.png"
  expect_status nonzero "colour and depth of different sizes"
  expect_in "$err" "160 x 90" "different sizes"
  expect_in "$err" "80 x 45" "different sizes"
  expect_only_files "$d"

  run dof --color "$work/color.exr" --depth "$work/negative_depth.exr" -o "$d/x.png"
  expect_status nonzero "negative depth"
  expect_in "$err" "negative_depth.exr" "negative depth"
  expect_in "$err" "5, 7" "negative depth (pixel 5, 7)"
  expect_only_files "$d"

  # NaN colour: refused on reading (the default method, in place, would skip it unread).
  oiiotool --pattern constant:color=0.3,0.5,0.7 160x90 3 --fill:color=nan,nan,nan 1x1+5+7 \
    -d float -o "$work/nan_color.exr" || fail "oiiotool"
  run dof --color "$work/nan_color.exr" --depth "$work/depth.exr" -o "$d/x.png"
  expect_status nonzero "NaN colour"
  expect_in "$err" "nan_color.exr: pixel (5, 7) of channel 'R' is NaN" "NaN colour"
  expect_only_files "$d"

  # A colour image as depth, no channel named: which channel is depth cannot be guessed.
  run dof --color "$work/color.exr" --depth "$work/color.exr" -o "$d/x.png"
  expect_status nonzero "depth from an RGB file without --depth-channel"
  expect_in "$err" "--depth-channel" "depth from an RGB file without --depth-channel"
  expect_in "$err" "R, G, B" "depth from an RGB file without --depth-channel"
  expect_only_files "$d"

  run dof --width 32 --height 18 --bogus 1 -o "$d/x.png"
  expect_status nonzero "unknown option"
  expect_in "$err" "--bogus" "unknown option"

  run dof --width 32 --height 18 --threads 1e12 -o "$d/x.png"
  expect_status nonzero "--threads beyond int"
  expect_in "$err" "--threads" "--threads beyond int"
  expect_in "$err" "out of range" "--threads beyond int"
  expect_only_files "$d"

  run dof --width 32 --height 18 --f-number -1 -o "$d/x.png"
  expect_status nonzero "--f-number -1"
  expect_in "$err" "--f-number" "--f-number -1 (named as the option)"
  expect_only_files "$d"

  run dof --width 32 --height 18 --threads
  expect_status nonzero "option without its value"
  expect_in "$err" "--threads" "option without its value"

  # The sanity check of this case: the same inputs, fixed, do work.
  run dof --color "$work/color.exr" --depth "$work/depth.exr" -o "$d/ok.png"
  expect_status 0 "valid files"
  expect_file "$d/ok.png" "valid files"
  ;;

outputs)
  # The files of one run are written whole or not at all, as a set: every path is checked
  # before the work, and nothing is renamed into place until every file is written.
  d=$work/o
  mkdir -p "$d"
  run dof --width 32 --height 18 -o "$d/x.png" --coc-output "$work/no/such/folder/c.png"
  expect_status nonzero "--coc-output in a missing folder"
  expect_in "$err" "--coc-output" "--coc-output in a missing folder"
  expect_only_files "$d"
  run dof --width 32 --height 18 -o "$d/x.png" --report "$work/no/such/folder/r.json"
  expect_status nonzero "--report in a missing folder"
  expect_in "$err" "--report" "--report in a missing folder"
  expect_only_files "$d"
  mkdir "$d/r.json"
  run dof --width 32 --height 18 -o "$d/x.png" --report "$d/r.json"
  expect_status nonzero "--report naming a folder"
  expect_in "$err" "is a folder" "--report naming a folder"
  expect_only_files "$d" r.json
  rmdir "$d/r.json"
  run dof --width 32 --height 18 -o "$d/x.png" --coc-output "$d/./x.png"
  expect_status nonzero "--coc-output the same file as --output"
  expect_in "$err" "--output" "--coc-output the same file as --output"
  expect_only_files "$d"
  run dof --width 32 --height 18 -o "$d/x.unknownformat"
  expect_status nonzero "an output format OpenImageIO cannot write"
  expect_in "$err" "$d/x.unknownformat" "an output format OpenImageIO cannot write"
  expect_only_files "$d"
  # A huge blur for explicit diffusion is refused before any output exists.
  run dof --width 32 --height 18 --method mpad --far-start 1 --far-end 1.5 --far-radius 1e6 \
    -o "$d/x.png"
  expect_status nonzero "mpad asked for 5e11 explicit steps"
  expect_in "$err" "explicit steps" "mpad asked for 5e11 explicit steps"
  expect_only_files "$d"

  # Names with quotes still make valid JSON; the EXR CoC map holds the signed diameters.
  run dof --width 160 --height 90 -o "$d/q\"x.png" --coc-output "$d/coc.exr" --report "$d/r\"q.json"
  expect_status 0 "outputs named with quotes"
  expect_only_files "$d" 'q"x.png' coc.exr 'r"q.json'
  if command -v python3 >/dev/null; then
    python3 -c 'import json, sys; json.load(open(sys.argv[1]))' "$d/r\"q.json" ||
      fail "the report of outputs named with quotes is not valid JSON"
  fi
  if command -v oiiotool >/dev/null; then
    stats=$(oiiotool --stats "$d/coc.exr" 2>&1 | tr -s ' ')
    expect_in "$stats" "1 channel" "CoC EXR"
    # The built-in scene has a near twig (negative CoC) and a far background (positive).
    min=$(echo "$stats" | sed -n 's/.*Stats Min: \([-0-9.e]*\).*/\1/p')
    max=$(echo "$stats" | sed -n 's/.*Stats Max: \([-0-9.e]*\).*/\1/p')
    if ! awk -v lo="$min" -v hi="$max" 'BEGIN { exit !(lo < -1 && hi > 1) }'; then
      fail "CoC EXR: signed range [$min, $max] expected to reach below -1 and above 1 px"
    fi
  fi

  # The outputs are encoded side by side: each file holds its own picture (as a run with that
  # output alone writes it), and no byte depends on the thread count.
  t=$work/threads
  mkdir -p "$t"
  for n in 1 2; do
    run dof --width 96 --height 54 --threads $n -o "$t/$n.png" --coc-output "$t/${n}_coc.png" \
      --input-output "$t/${n}_in.png"
    expect_status 0 "three outputs on $n thread(s)"
  done
  run dof --width 96 --height 54 -o "$t/alone.png" --coc-output none
  expect_status 0 "the output alone"
  run dof --width 96 --height 54 -o "$t/beside.png" --coc-output "$t/alone_coc.png"
  expect_status 0 "the CoC output beside it"
  for name in "" _coc _in; do
    cmp -s "$t/1$name.png" "$t/2$name.png" || fail "1$name.png and 2$name.png differ"
  done
  cmp -s "$t/2.png" "$t/alone.png" || fail "--output differs from the run that writes it alone"
  cmp -s "$t/2_coc.png" "$t/alone_coc.png" || fail "--coc-output differs from a run without --input-output"
  cmp -s "$t/2.png" "$t/2_in.png" && fail "--output holds the input"
  ;;

hostile)
  # Outputs never replace a special file, an input or a redirected standard stream; a full
  # disk is an error naming the file; huge or damaged inputs are refused before the work;
  # nothing is left behind, no temporary file either.
  need_oiiotool
  d=$work/h
  mkdir -p "$d"
  small=(--width 32 --height 18)

  run dof "${small[@]}" -o "$d/x.png" --report /dev/null
  expect_status nonzero "--report /dev/null"
  expect_in "$err" "--report '/dev/null': is a character device" "--report /dev/null"
  [[ -c /dev/null ]] || fail "/dev/null is no longer a character device"
  expect_only_files "$d"

  mkfifo "$d/fifo.png"
  out=$(timeout 60 "$tridiff" dof "${small[@]}" -o "$d/fifo.png" 2>"$work/stderr.txt")
  status=$?
  err=$(cat "$work/stderr.txt")
  expect_status nonzero "-o naming a FIFO (no reader: must not hang)"
  expect_in "$err" "FIFO" "-o naming a FIFO"
  [[ -p $d/fifo.png ]] || fail "the FIFO was replaced"
  rm -f "$d/fifo.png"

  # `--report /dev/stdout > file`: renaming over that file would cut the redirection off.
  "$tridiff" dof "${small[@]}" -o "$d/x.png" --report /dev/stdout >"$work/redirected.txt" \
    2>"$work/stderr.txt"
  status=$?
  err=$(cat "$work/stderr.txt")
  expect_status nonzero "--report /dev/stdout redirected to a file"
  expect_in "$err" "standard output" "--report /dev/stdout redirected to a file"
  expect_only_files "$d"

  # An output may not replace an input, under any spelling.
  oiiotool --pattern constant:color=0.3,0.5,0.7 32x18 3 -d half -o "$d/color.exr" || fail "oiiotool"
  oiiotool --pattern constant:color=2.0 32x18 1 -d float -o "$d/depth.exr" || fail "oiiotool"
  ln "$d/depth.exr" "$d/depth_link.exr"
  cp "$d/color.exr" "$work/color_before.exr"
  run dof --color "$d/color.exr" --depth "$d/depth.exr" -o "$d/color.exr"
  expect_status nonzero "-o equal to --color"
  expect_in "$err" "is the --color file" "-o equal to --color"
  run dof --color "$d/color.exr" --depth "$d/depth.exr" -o "$d/x.png" --coc-output "$d/depth_link.exr"
  expect_status nonzero "--coc-output a hard link of --depth"
  expect_in "$err" "is the --depth file" "--coc-output a hard link of --depth"
  run ipf --color "$d/color.exr" --depth "$d/depth.exr" --mask 3 -o "$d/./color.exr"
  expect_status nonzero "ipf -o equal to --color"
  expect_in "$err" "is the --color file" "ipf -o equal to --color"
  cmp -s "$d/color.exr" "$work/color_before.exr" || fail "the --color file was changed"
  expect_only_files "$d" color.exr depth.exr depth_link.exr
  rm -f "$d"/*

  # A failed write, as a full disk fails it: here the file-size limit (no privileges needed).
  for command in dof:big.png dof:big.jpg dof:big.exr dof:big.tif ipf:ipf.png; do
    output=${command#*:}
    run_file_limited 4 "${command%%:*}" --width 160 --height 90 -o "$d/$output"
    expect_status nonzero "$command past the file-size limit"
    expect_in "$err" "--output '$d/$output': cannot write (File too large)" "$command past the limit"
    expect_only_files "$d"
  done
  # A disk really full, where this runs as root and may mount a small tmpfs.
  mkdir -p "$work/full"
  if [[ $(id -u) == 0 ]] && mount -t tmpfs -o size=12k tmpfs "$work/full" 2>/dev/null; then
    for output in full.png full.jpg; do
      run dof --width 160 --height 90 -o "$work/full/$output" --coc-output "$work/full/c.png"
      expect_status nonzero "$output on a full disk"
      expect_in "$err" "cannot write (No space left on device)" "$output on a full disk"
      expect_only_files "$work/full"
    done
    umount "$work/full"
  else
    echo "note: cannot mount a tmpfs here; a full disk is tested through the file-size limit"
  fi

  # The longest legal name works; one byte more is refused before the work.
  long=$(printf 'n%.0s' {1..251})
  run dof "${small[@]}" -o "$d/$long.png" --coc-output "$d/c.png"
  expect_status 0 "an output name of 255 bytes"
  expect_only_files "$d" "$long.png" c.png
  run dof "${small[@]}" -o "$d/x.png" --coc-output none
  expect_status 0 "--coc-output none"
  expect_only_files "$d" "$long.png" c.png x.png
  run dof "${small[@]}" -o "$d/n$long.png"
  expect_status nonzero "an output name of 256 bytes"
  expect_in "$err" "the name is too long" "an output name of 256 bytes"
  rm -f "$d"/*

  # A 20000 x 20000 PNG in a few dozen bytes: refused from its header, at once.
  if command -v python3 >/dev/null; then
    python3 - "$d/huge.png" <<'PY'
import struct, sys, zlib
def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
header = struct.pack(">IIBBBBB", 20000, 20000, 8, 2, 0, 0, 0)
open(sys.argv[1], "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
                              chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b""))
PY
    run dof --color "$d/huge.png" --depth "$d/huge.png" -o "$d/x.png"
    expect_status nonzero "a PNG declaring 20000 x 20000"
    expect_in "$err" "huge.png: is 20000 x 20000 = 400000000 pixels, more than the limit" \
      "a PNG declaring 20000 x 20000"
    expect_in "$err" "--max-pixels" "a PNG declaring 20000 x 20000"
  fi
  oiiotool --pattern constant:color=0.3,0.5,0.7 32x18 3 -d half -o "$d/color.exr" || fail "oiiotool"
  oiiotool --pattern constant:color=2.0 32x18 1 -d float -o "$d/depth.exr" || fail "oiiotool"
  run dof --color "$d/color.exr" --depth "$d/depth.exr" --max-pixels 575 -o "$d/x.png"
  expect_status nonzero "--max-pixels below the image"
  expect_in "$err" "is 32 x 18 = 576 pixels, more than the limit of 575" "--max-pixels 575"
  run dof --color "$d/color.exr" --depth "$d/depth.exr" --max-pixels 0 -o "$d/x.png"
  expect_status nonzero "--max-pixels 0"
  expect_in "$err" "--max-pixels" "--max-pixels 0"

  # A truncated TIFF: its reader says success with strips missing; tridiff refuses it.
  oiiotool --pattern noise 160x90 3 -d uint8 -o "$d/whole.tif" || fail "oiiotool"
  head -c "$(($(stat -c %s "$d/whole.tif") / 2))" "$d/whole.tif" >"$d/cut.tif"
  run dof --color "$d/cut.tif" --depth "$d/depth.exr" -o "$d/x.png"
  expect_status nonzero "a truncated TIFF"
  expect_in "$err" "cut.tif: cannot read the pixels" "a truncated TIFF"
  # A truncated PNG: one message of tridiff's, without libpng's own line before it.
  oiiotool --pattern noise 160x90 3 -d uint8 -o "$d/whole.png" || fail "oiiotool"
  head -c "$(($(stat -c %s "$d/whole.png") / 2))" "$d/whole.png" >"$d/cut.png"
  run dof --color "$d/cut.png" --depth "$d/depth.exr" -o "$d/x.png"
  expect_status nonzero "a truncated PNG"
  expect_in "$err" "cut.png: cannot read the pixels" "a truncated PNG"
  [[ $err != *"libpng error"* ]] || fail "libpng's own message reached stderr: $err"
  expect_only_files "$d" huge.png color.exr depth.exr whole.tif cut.tif whole.png cut.png

  # Nothing after `methods` or `--help`; a bare `tridiff` is an error: usage on stderr only.
  for words in "methods extra" "--help extra"; do
    # shellcheck disable=SC2086
    run $words
    expect_status nonzero "tridiff $words"
    expect_in "$err" "extra" "tridiff $words"
  done
  run
  expect_status nonzero "a bare tridiff"
  expect_in "$err" "usage" "a bare tridiff"
  [[ -z $out ]] || fail "a bare tridiff printed on stdout: $out"
  ;;

ipf)
  # The Inverse Post Filter model on the built-in scene at 160 x 90, mask 17, four parts:
  # lines of 160/4 + 16 = 56 stages; each part (90 + 16) x 56 + 16 = 5952 clocks, 23 808 in all;
  # reads 14 400 pixels + 3 boundaries x 16 halo columns x 90 lines = 18 720, writes 14 400:
  # 18 720 x 8 + 14 400 x 4 = 207 360 bytes.
  d=$work/out
  mkdir -p "$d"
  run ipf --width 160 --height 90 --mask 17 --parts 4 --clock-mhz 310 --bandwidth-gbs 20 --check \
    -o "$d/ipf.png"
  expect_status 0 "ipf on the built-in scene"
  expect_file "$d/ipf.png" "ipf"
  expect_size "$d/ipf.png" "160 x 90"
  expect_in "$out" "16 pipes" "ipf pipes"
  expect_in "$out" "line 56 stages" "ipf line length"
  expect_in "$out" "23808 pipe steps per frame for 14400 pixels" "ipf clocks"
  expect_in "$out" "23808 clocks run (= the estimate)" "ipf model clocks"
  expect_in "$out" "18720 pixels read, 14400 written, 0.20736 MB" "ipf memory"
  expect_in "$out" "1 pixel(s)/clock at 310 MHz" "ipf pixels per clock"
  expect_in "$out" "software ipf method: identical" "ipf --check"
  expect_only_files "$d" ipf.png

  run ipf --program laplacian --width 160 --height 90 --mask 3 --parts 2 --check -o "$d/lap.png"
  expect_status 0 "ipf --program laplacian"
  expect_file "$d/lap.png" "laplacian"
  expect_in "$out" "direct convolution: identical" "laplacian --check"

  run ipf --help
  expect_status 0 "ipf --help"
  expect_in "$out" "--pixels-per-clock" "ipf --help"
  expect_in "$out" "--focus" "ipf --help"
  run methods
  expect_in "$out" "ipf" "tridiff methods lists ipf"

  for bad in "--mask 4" "--mask 1" "--parts 0" "--clock-mhz 0" "--bandwidth-gbs -1" \
    "--pixels-per-clock 0" "--program blur" "--color-weight-bits 4"; do
    # shellcheck disable=SC2086
    run ipf --width 32 --height 18 $bad -o "$d/bad.png"
    expect_status nonzero "ipf $bad"
    expect_in "$err" "${bad%% *}" "ipf $bad names the option"
  done
  expect_only_files "$d" ipf.png lap.png
  ;;

options)
  # Hostile and contradictory options (issue 21): each is refused before any work, with a
  # message naming the option(s), and nothing is written in the working folder (where the
  # default outputs tridiff_dof.png and tridiff_ipf.png would go).
  d=$work/opt
  mkdir -p "$d"
  tridiff=$(realpath "$tridiff")
  work=$(realpath "$work")
  cd "$d" || exit 1
  small=(--width 64 --height 48)
  # refused DESCRIPTION NEEDLE... -- ARGS...: a non-zero exit, every NEEDLE on stderr, no file.
  refused() {
    local description=$1 needle
    local needles=()
    shift
    while [[ $1 != -- ]]; do
      needles+=("$1")
      shift
    done
    shift
    run "$@"
    expect_status nonzero "$description"
    for needle in "${needles[@]}"; do expect_in "$err" "$needle" "$description"; done
    expect_only_files "$d"
  }

  # The thread count: beyond the library's bound (1024) the OpenMP runtime crashed.
  refused "dof --threads 100000" "--threads" "at most 1024" -- dof "${small[@]}" --threads 100000
  refused "ipf --threads 1025" "--threads" "at most 1024" -- ipf "${small[@]}" --threads 1025
  refused "dof --threads -1" "--threads" -- dof "${small[@]}" --threads -1

  # The ipf model's bounds, before the frame is rendered.
  refused "ipf --mask 1000001" "--mask" "511" -- ipf "${small[@]}" --mask 1000001
  refused "ipf --mask 513" "--mask" "511" -- ipf "${small[@]}" --mask 513
  refused "ipf 1920 x 1080 at mask 255" "--mask" "4e+10" -- ipf --mask 255
  refused "ipf --parts 2000" "--parts" "1024" -- ipf "${small[@]}" --parts 2000
  refused "ipf --register-size 100000" "--register-size" "65536" -- \
    ipf "${small[@]}" --register-size 100000
  refused "ipf --pixels-per-clock 1e6" "--pixels-per-clock" "1024" -- \
    ipf "${small[@]}" --pixels-per-clock 1e6
  refused "ipf --cycles-per-pixel 2000" "--cycles-per-pixel" "1024" -- \
    ipf "${small[@]}" --cycles-per-pixel 2000
  refused "ipf --clock-mhz 1e9" "--clock-mhz" -- ipf "${small[@]}" --clock-mhz 1e9
  refused "ipf --bandwidth-gbs 1e9" "--bandwidth-gbs" -- ipf "${small[@]}" --bandwidth-gbs 1e9
  refused "ipf laplacian --rule" "--rule" "--program dof" -- \
    ipf "${small[@]}" --program laplacian --rule printed
  # The plan's own refusal, named as the option.
  refused "ipf --parts 100 on 64 px" "--parts" -- ipf "${small[@]}" --parts 100

  # An option given twice (the last used to win), a flag too, -o and --output alike.
  refused "--width twice" "--width" "twice" -- dof "${small[@]}" --width 32
  refused "--layers twice" "--layers" "twice" -- dof "${small[@]}" --layers --layers
  refused "-o and --output" "--output" "twice" -- dof "${small[@]}" -o a.png --output b.png
  refused "ipf --mask twice" "--mask" "twice" -- ipf "${small[@]}" --mask 3 --mask 5

  # Lens character (issue 26): ranges checked before any work, a kernel image read and checked
  # before the frame, the option named; a method that cannot honour it refuses it by name.
  refused "--aperture-blades 2" "--aperture-blades" "at least 3" -- \
    dof "${small[@]}" --method scatter --aperture-blades 2
  refused "--aperture-blades -4" "--aperture-blades" -- \
    dof "${small[@]}" --method bokeh --aperture-blades -4
  refused "--aperture-roundness 1.5" "--aperture-roundness" "[0, 1]" -- \
    dof "${small[@]}" --method bokeh --aperture-roundness 1.5
  refused "--highlight-threshold 0" "--highlight-threshold" "> 0" -- \
    dof "${small[@]}" --method bokeh --highlight-threshold 0
  refused "--highlight-gain -1" "--highlight-gain" ">= 0" -- \
    dof "${small[@]}" --method scatter --highlight-gain -1
  refused "adi --aperture-blades 6" "--aperture-blades" "bokeh" -- \
    dof "${small[@]}" --method adi --aperture-blades 6
  refused "sat --highlight-threshold 2" "--highlight-threshold" "scatter" -- \
    dof "${small[@]}" --method sat --highlight-threshold 2
  if command -v oiiotool >/dev/null; then
    oiiotool --create 8x8 1 -d float -o "$work/dark_kernel.exr" &&
      oiiotool --pattern constant:color=-1 8x8 1 -d float -o "$work/negative_kernel.exr" &&
      oiiotool --pattern constant:color=1 8x8 1 -d float -o "$work/square_kernel.exr" ||
      fail "oiiotool"
    refused "an all-zero --aperture-image" "--aperture-image" "zero everywhere" -- \
      dof "${small[@]}" --method bokeh --aperture-image "$work/dark_kernel.exr"
    refused "a negative --aperture-image" "--aperture-image" ">= 0" -- \
      dof "${small[@]}" --method scatter --aperture-image "$work/negative_kernel.exr"
    refused "a missing --aperture-image" "nothing.exr" -- \
      dof "${small[@]}" --method scatter --aperture-image "$work/nothing.exr"
    refused "--aperture-image as the output" "--aperture-image" -- \
      dof "${small[@]}" --method bokeh --aperture-image "$work/square_kernel.exr" \
      -o "$work/square_kernel.exr"
    run dof "${small[@]}" --method bokeh --aperture-image "$work/square_kernel.exr" \
      --highlight-gain 2 -o "$work/kernel_bokeh.exr" --coc-output none
    expect_status 0 "bokeh with a kernel image"
    expect_file "$work/kernel_bokeh.exr" "bokeh with a kernel image"
  fi

  # The built-in scene's size with files: the files have their own.
  if command -v oiiotool >/dev/null; then
    oiiotool --pattern constant:color=0.3,0.5,0.7 64x48 3 -d half -o "$work/color.exr" &&
      oiiotool --pattern constant:color=2.0 64x48 1 -d float -o "$work/depth.exr" ||
      fail "oiiotool"
    refused "--width with --color" "--width" "--color" -- \
      dof --color "$work/color.exr" --depth "$work/depth.exr" --width 64
    refused "--height with --color" "--height" "--color" -- \
      ipf --color "$work/color.exr" --depth "$work/depth.exr" --height 48
  fi

  # Lens options with the artist curve, which replaces the lens: both named.
  for lens in "--focus 3" "--f-number 2" "--focal-length 35" "--sensor-width 24" "--max-coc 8"; do
    # shellcheck disable=SC2086
    refused "$lens with the artist curve" "${lens%% *}" "--near-start" -- \
      dof "${small[@]}" --near-start 0.5 --near-end 2 --near-radius 4 $lens
  done

  # An empty or reversed range with a radius used to turn that blur off silently.
  refused "reversed near range" "--near-end" "--near-start" -- \
    dof "${small[@]}" --near-start 2 --near-end 1 --near-radius 4
  refused "near radius without a range" "--near-end" "--near-radius" -- \
    dof "${small[@]}" --near-radius 4
  refused "empty far range" "--far-end" "--far-start" -- \
    dof "${small[@]}" --far-start 5 --far-end 5 --far-radius 3
  refused "reversed far range" "--far-end" "--far-start" -- \
    dof "${small[@]}" --far-start 8 --far-end 5 --far-radius 3
  refused "overlapping ranges" "--far-start" "--near-end" -- \
    dof "${small[@]}" --near-start 1 --near-end 3 --near-radius 4 --far-start 2 --far-end 6 \
    --far-radius 3

  # A CoC map too large for the method is named as the options that made it, not 'coc'.
  refused "mpad at --max-coc 1e7" "--max-coc" "explicit steps" -- \
    dof "${small[@]}" --method mpad --max-coc 1e7 --f-number 0.001
  refused "mpad at --far-radius 1e6" "--far-radius" "explicit steps" -- \
    dof "${small[@]}" --method mpad --far-start 1 --far-end 1.5 --far-radius 1e6
  [[ $err != *"'coc'"* ]] || fail "the CoC map's error still names 'coc': $err"
  # Splats that would take days are refused at once (the largest CoC named), not run.
  refused "scatter at --max-coc 16000" "--max-coc" "weights" -- \
    dof "${small[@]}" --method scatter --max-coc 16000 --f-number 0.01 --focal-length 600

  # The sanity check of this case: the bound itself, and both blur regions, do work.
  run dof "${small[@]}" --threads 1024 --near-start 0.5 --near-end 2 --near-radius 3 \
    --far-start 5 --far-end 9 --far-radius 4 -o ok.png
  expect_status 0 "dof --threads 1024 with both artist-curve regions"
  expect_only_files "$d" ok.png ok_coc.png
  ;;

lens)
  # Where the lens focuses (issue 26): at a pixel's depth, over a range; and the lens in use,
  # with the values that are tridiff's defaults, said when the image is the user's.
  need_oiiotool
  d=$work/l
  mkdir -p "$d"
  # 128 x 48: 1 m for x < 16, 20 m for 40 <= x < 48, 3.2 m (the default focus) elsewhere.
  oiiotool --pattern constant:color=3.2 128x48 1 --fill:color=1 16x48+0+0 \
    --fill:color=20 8x48+40+0 -d float -o "$work/depth.exr" &&
    oiiotool --pattern constant:color=0.5,0.5,0.5 128x48 3 -d half -o "$work/color.exr" ||
    fail "oiiotool"
  files=(--color "$work/color.exr" --depth "$work/depth.exr")

  run dof "${files[@]}" -o "$d/a.png" --report "$d/a.json"
  expect_status 0 "dof on files with the default lens"
  expect_in "$out" "lens     50 mm f/2.8 focused at 3.2 m, sensor 36 mm (defaults: focus, focal-length, f-number, sensor-width; give them for your camera)" "the default lens said"
  expect_in "$(cat "$d/a.json" 2>/dev/null)" '"lens_defaults": ["focus", "focal-length", "f-number", "sensor-width"]' "the default lens in the report"
  run dof "${files[@]}" -o "$d/b.png" --focus 2 --f-number 4 --focal-length 35 --sensor-width 24
  expect_status 0 "dof on files with the whole lens given"
  expect_in "$out" "lens     35 mm f/4 focused at 2 m, sensor 24 mm" "the lens given"
  [[ $out != *defaults* ]] || fail "the lens given is not a default: $out"
  run dof --width 64 --height 36 -o "$d/c.png"
  expect_status 0 "dof on the built-in scene"
  [[ $out != *"lens     "* ]] || fail "the built-in scene's lens is its own, no lens line: $out"

  # The 5 x 5 median: column 15 has three columns at 1 m in its window, column 16 three at 3.2.
  run dof "${files[@]}" -o "$d/e.png" --focus-at 15,20
  expect_status 0 "--focus-at 15,20"
  expect_in "$out" "focused at 1 m (the depth at pixel (15, 20)" "--focus-at on the near side"
  run dof "${files[@]}" -o "$d/f.png" --focus-at 16,20
  expect_status 0 "--focus-at 16,20"
  expect_in "$out" "focused at 3.2 m (the depth at pixel (16, 20)" "--focus-at on the far side"
  run dof --width 64 --height 36 -o "$d/g.png" --focus-at 63,35
  expect_status 0 "--focus-at on the built-in scene's corner"

  # --focus-range 2,5 at f/2: 3.2 m sharp; 1 m as focused at 2 m: A f (d - 2)/(d (2 - f)) on
  # the sensor = 0.025 * 0.05 * -1 / 1.95 m, * 1000 / 36 * 128 px = -2.2792 px; 20 m as focused
  # at 5 m: 0.025 * 0.05 * 15 / (20 * 4.95) * 1000 / 36 * 128 = 0.67340 px.
  run dof "${files[@]}" -o "$d/h.png" --focus-range 2,5 --f-number 2 --coc-output "$d/h.exr" --float
  expect_status 0 "--focus-range 2,5"
  expect_in "$out" "in focus from 2 to 5 m" "--focus-range in the lens line"
  expect_pixel "$d/h.exr" 5 10 "-2.2792" 2e-4 "CoC in front of the range"
  expect_pixel "$d/h.exr" 30 10 "0" 0 "CoC inside the range"
  expect_pixel "$d/h.exr" 44 10 "0.67340" 2e-4 "CoC behind the range"
  expect_only_files "$d" a.png a_coc.png a.json b.png b_coc.png c.png c_coc.png e.png e_coc.png \
    f.png f_coc.png g.png g_coc.png h.png h.exr

  # Refusals, before any output is written.
  e=$work/refused
  mkdir -p "$e"
  for bad in "--focus-at 128,0|outside the 128 x 48" "--focus-at 0,-1|outside" \
    "--focus-at 1.5,2|X,Y" "--focus-at 3|X,Y" "--focus-at 1,2,3|X,Y" \
    "--focus-at 3,3 --focus 2|--focus" "--focus-range 1,2 --focus 2|--focus" \
    "--focus-range 1,2 --focus-at 1,1|--focus-at" "--focus-range 3,1|nearer than its near end" \
    "--focus-range 0.01,1|focal length" "--focus-range 0,1|> 0" "--focus-range 1|NEAR,FAR" \
    "--focus-range 1,x|NEAR,FAR" "--focus-range 1,2 --near-start 1 --near-end 2 --near-radius 3|--near-start"; do
    option=${bad%%|*}
    needle=${bad#*|}
    # shellcheck disable=SC2086
    run dof "${files[@]}" -o "$e/x.png" $option
    expect_status nonzero "$option"
    expect_in "$err" "${option%% *}" "$option (names the option)"
    expect_in "$err" "$needle" "$option"
    expect_only_files "$e"
  done
  ;;

views)
  # --view: a picture of what the method sees, at known pixels of a synthetic frame (the depth
  # of the lens case at f/1.4: 1 m is CoC -4.4 px, near; 20 m +1.7 px, far; 3.2 m sharp).
  need_oiiotool
  d=$work/v
  mkdir -p "$d"
  oiiotool --pattern constant:color=3.2 128x48 1 --fill:color=1 16x48+0+0 \
    --fill:color=20 8x48+40+0 -d float -o "$work/depth.exr" &&
    oiiotool --pattern constant:color=0.5,0.5,0.5 128x48 3 -d half -o "$work/color.exr" ||
    fail "oiiotool"
  files=(--color "$work/color.exr" --depth "$work/depth.exr" --f-number 1.4 --coc-output none)
  for view in coc focal-plane layers tiles; do
    run dof "${files[@]}" --view "$view" -o "$d/$view.png" --report "$d/$view.json"
    expect_status 0 "--view $view"
    expect_in "$out" "view     $view" "--view $view summary"
    expect_in "$(cat "$d/$view.json" 2>/dev/null)" "\"view\": \"$view\"" "--view $view report"
    expect_size "$d/$view.png" "128 x 48"
  done
  # PNG is sRGB: linear 0.25 is 137/255, 0.5 is 188/255, 0.125 is 99/255.
  expect_pixel "$d/coc.png" 5 20 "0 0.5373 1" 0.005 "coc view, near"
  expect_pixel "$d/coc.png" 30 20 "0 0 0" 0 "coc view, sharp"
  expect_pixel "$d/focal-plane.png" 5 20 "0 0 1" 0 "focal-plane view, near"
  expect_pixel "$d/focal-plane.png" 30 20 "0 1 0" 0 "focal-plane view, in focus"
  expect_pixel "$d/focal-plane.png" 44 20 "1 0 0" 0 "focal-plane view, far"
  expect_pixel "$d/layers.png" 5 20 "1 1 1" 0 "layers view, near layer"
  expect_pixel "$d/layers.png" 44 20 "0 0 0" 0 "layers view, far background"
  # Tiles of 32: x < 64 is reached by the near and far discs; x >= 64 is skipped, darkened.
  expect_pixel "$d/tiles.png" 20 20 "0.7373 0.7373 0.7373" 0.005 "tiles view, worked tile"
  expect_pixel "$d/tiles.png" 100 20 "0.3882 0.3882 0.3882" 0.005 "tiles view, skipped tile"
  run dof "${files[@]}" --view tiles --no-skip -o "$d/all.png"
  expect_pixel "$d/all.png" 100 20 "0.7373 0.7373 0.7373" 0.005 "tiles view with --no-skip"
  # A wider --in-focus takes the far 1.7 px in.
  run dof "${files[@]}" --view focal-plane --in-focus 2 -o "$d/wide.png"
  expect_pixel "$d/wide.png" 44 20 "0 1 0" 0 "focal-plane view, --in-focus 2"

  e=$work/refused
  mkdir -p "$e"
  run dof "${files[@]}" --view depth -o "$e/x.png"
  expect_status nonzero "--view depth"
  expect_in "$err" "--view" "--view depth"
  expect_in "$err" "coc, focal-plane, layers or tiles" "--view depth"
  expect_only_files "$e"
  ;;

formats)
  # Output formats (issue 26): 32-bit OpenEXR with --float, .hdr from any colour image, .pfm
  # refused before the work.
  need_oiiotool
  d=$work/f
  mkdir -p "$d"
  # 1 + 2^-20 is between two halves; 1e6 is beyond half; all at the focus: nothing blurs.
  oiiotool --pattern constant:color=1.00000095367431640625,0.5,1000000 8x4 3 -d float \
    -o "$work/color.exr" &&
    oiiotool --pattern constant:color=1.00000095367431640625,0.5,2 8x4 3 -d float \
      -o "$work/small.exr" &&
    oiiotool --pattern constant:color=0.3,0.5,0.7,1 8x4 4 -d half -o "$work/rgba.exr" &&
    oiiotool --pattern constant:color=3.2 8x4 1 -d float -o "$work/depth.exr" || fail "oiiotool"
  for input in color small; do
    run dof --color "$work/$input.exr" --depth "$work/depth.exr" --float -o "$d/$input.exr" \
      --input-output "$d/${input}_in.exr" --coc-output none
    expect_status 0 "--float from $input.exr"
    for written in "$input.exr" "${input}_in.exr"; do
      expect_in "$(oiiotool --info "$d/$written" 2>&1)" "float openexr" "--float: $written"
      oiiotool --fail 0 --warn 0 "$work/$input.exr" "$d/$written" --diff >/dev/null ||
        fail "--float: $d/$written differs from $work/$input.exr"
    done
  done
  # Without --float a frame within half's range is half: 1 + 2^-20 is lost.
  run dof --color "$work/small.exr" --depth "$work/depth.exr" -o "$d/half.exr" --coc-output none
  expect_in "$(oiiotool --info "$d/half.exr" 2>&1)" "half openexr" "half by default"
  expect_pixel "$d/half.exr" 0 0 "1 0.5 2" 0 "half rounds 1 + 2^-20 to 1"

  # .hdr from an RGBA image: it used to fail after the render ("HDR can only support
  # 3-channel images"); alpha is left out. RGBE keeps 2^-7 of the largest channel.
  run dof --color "$work/rgba.exr" --depth "$work/depth.exr" -o "$d/rgba.hdr" --coc-output none
  expect_status 0 ".hdr from RGBA"
  expect_in "$(oiiotool --info "$d/rgba.hdr" 2>&1)" "3 channel" ".hdr from RGBA"
  expect_pixel "$d/rgba.hdr" 3 2 "0.3 0.5 0.7" 0.0055 ".hdr from RGBA"

  e=$work/refused
  mkdir -p "$e"
  for option in --output --coc-output --input-output; do
    output=()
    [[ $option != --output ]] && output=(-o "$e/x.png")
    run dof --color "$work/rgba.exr" --depth "$work/depth.exr" "${output[@]}" $option "$e/y.pfm"
    expect_status nonzero "$option .pfm"
    expect_in "$err" "$option: $e/y.pfm: unknown image format '.pfm'" "$option .pfm"
    expect_only_files "$e"
  done
  run dof --color "$work/rgba.exr" --depth "$work/depth.exr" -o "$e/x.png" --float
  expect_status nonzero "--float without an OpenEXR output"
  expect_in "$err" "--float" "--float without an OpenEXR output"
  expect_only_files "$e"
  ;;

*)
  echo "unknown case '$case_name'" >&2
  exit 2
  ;;
esac

if ((failures)); then
  echo "$case_name: $failures check(s) failed" >&2
  exit 1
fi
echo "$case_name: all checks passed"
