#!/usr/bin/env bash
# Checks CI makes on the source text (no build needed). Today: every OpenMP parallel region
# passes num_threads, so a caller's `threads` is obeyed everywhere (tridiff/threads.hpp).
# Prints each offending pragma as file:line and exits 1 if there is one.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 - <<'PY'
import pathlib, re, sys
folders = ["solvers", "image", "diffusion", "blur", "dof", "bench", "tools", "tests", "fuzz",
           "distributed", "python"]
bad = []
for folder in folders:
    for path in sorted(pathlib.Path(folder).rglob("*")):
        if path.suffix not in {".cpp", ".hpp", ".h", ".cc"}:
            continue
        lines = path.read_text().splitlines()
        i = 0
        while i < len(lines):
            start, text = i, lines[i]
            while text.rstrip().endswith("\\") and i + 1 < len(lines):  # continued pragma
                i += 1
                text = text.rstrip()[:-1] + " " + lines[i]
            if re.match(r"\s*#\s*pragma\s+omp\s+parallel\b", text) and "num_threads" not in text:
                bad.append(f"{path}:{start + 1}: {text.strip()}")
            i += 1
for line in bad:
    print(line)
if bad:
    print(f"lint: {len(bad)} OpenMP parallel region(s) without num_threads(resolve_threads(...))",
          file=sys.stderr)
    sys.exit(1)
PY
