#!/usr/bin/env bash
# Every DOF method's output on the built-in scene in nine settings (1 and 2 threads, --layers,
# --no-skip, --in-focus 3, an odd size, the artist curve, a large CoC, an all-sharp frame) and
# auto at five budgets, as float EXR with the report text and JSON (timings removed): the check
# that a refactor changed no result bit. Hashes ignore the EXR's capture date.
#   bash scripts/dof_snapshot.sh BUILD_DIR OUT_DIR     # e.g. build /tmp/dof-before
#   bash scripts/dof_snapshot.sh --compare BEFORE AFTER  # exits 1 on any difference
set -euo pipefail
if [[ "${1:-}" == "--compare" ]]; then
  before=$2 after=$3 bad=0
  diff "$before/sums.txt" "$after/sums.txt" && echo "EXR: all $(wc -l < "$before/sums.txt") identical" || bad=1
  for f in "$before"/*.txt "$before"/*.json; do
    n=$(basename "$f")
    [[ $n == sums.txt ]] && continue
    cmp -s "$f" "$after/$n" || { echo "DIFF $n"; diff "$f" "$after/$n" | head -6; bad=1; }
  done
  echo "dof_snapshot: $([[ $bad == 0 ]] && echo same || echo DIFFERENT)"
  exit $bad
fi
tridiff=$(realpath "$1")/dof/tridiff out=$2
rm -rf "$out" && mkdir -p "$out" && cd "$out"
run() {  # name, then the options
  local name=$1; shift
  OMP_WAIT_POLICY=passive "$tridiff" dof "$@" -o "$name.exr" --coc-output none \
    --report "$name.json" > "$name.txt" 2>&1 && echo "rc=0" >> "$name.txt" || echo "rc=$?" >> "$name.txt"
  sed -i '/^  time /d' "$name.txt"
  sed -i '/"seconds"/d' "$name.json" 2>/dev/null || true
}
size=(--width 200 --height 120)
for m in adi mpad ipf scatter poisson pyramid-layers sat sat-layers gems bokeh auto; do
  run "$m-t1" "${size[@]}" --method "$m" --threads 1
  run "$m-t2" "${size[@]}" --method "$m" --threads 2
  run "$m-layers" "${size[@]}" --method "$m" --threads 2 --layers
  run "$m-noskip" "${size[@]}" --method "$m" --threads 2 --no-skip
  run "$m-if3" "${size[@]}" --method "$m" --threads 1 --in-focus 3
  run "$m-odd" --width 97 --height 53 --method "$m" --threads 2
  run "$m-artist" --width 160 --height 96 --method "$m" --threads 2 --near-start 1 --near-end 3 \
    --near-radius 9 --far-start 5 --far-end 12 --far-radius 14
  run "$m-big" "${size[@]}" --method "$m" --threads 2 --sensor-width 4
  run "$m-sharp" --width 64 --height 40 --method "$m" --threads 2 --f-number 64
done
for b in 10 25 35 45 80; do run "auto-b$b" "${size[@]}" --method auto --threads 2 --psnr-budget "$b"; done
python3 - *.exr > sums.txt <<'PY'
import hashlib, re, sys
for path in sys.argv[1:]:
    data = re.sub(rb"\d{4}:\d\d:\d\d \d\d:\d\d:\d\d", b"X" * 19, open(path, "rb").read(), count=1)
    print(hashlib.sha256(data).hexdigest(), path)
PY
echo "dof_snapshot: $(wc -l < sums.txt) outputs in $out"
