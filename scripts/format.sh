#!/usr/bin/env bash
# C++ formatting with clang-format 14 and the repository's .clang-format (STYLE.md's layout:
# Google-like, 100 columns, 2-space indent).
#   bash scripts/format.sh              # rewrites every C++ file that differs from the format
#   bash scripts/format.sh --check      # changes nothing; lists the files that differ and how
#                                       # many lines, exits 1 if any does (for CI)
#   bash scripts/format.sh [--check] FILE...   # only these files
# The files: *.cpp, *.hpp and *.h tracked by git in the code folders below. Installs
# clang-format when it is missing (bash scripts/deps.sh format). Another major version of
# clang-format formats differently: the script refuses one.
set -euo pipefail
cd "$(dirname "$0")/.."

check=0
files=()
for arg in "$@"; do
  case "$arg" in
    --check) check=1 ;;
    -h|--help) sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "scripts/format.sh: unknown option '$arg' (see --help)" >&2; exit 2 ;;
    *) files+=("$arg") ;;
  esac
done

folders=(solvers image diffusion blur dof bench tests testing tools fuzz
         examples python distributed)  # the last three when they exist
if ((${#files[@]} == 0)); then
  mapfile -t files < <(git ls-files -- "${folders[@]/%//*.cpp}" "${folders[@]/%//*.hpp}" \
                                       "${folders[@]/%//*.h}")
fi

clang_format="${CLANG_FORMAT:-}"
if [ -z "$clang_format" ]; then
  command -v clang-format-14 >/dev/null || command -v clang-format >/dev/null ||
    bash scripts/deps.sh format
  clang_format="$(command -v clang-format-14 || command -v clang-format)"
fi
version="$("$clang_format" --version)"
if [[ ! "$version" =~ version\ 14\. ]]; then
  echo "scripts/format.sh: $clang_format is not clang-format 14 ($version); set CLANG_FORMAT" >&2
  exit 2
fi

if ((check == 0)); then
  printf '%s\0' "${files[@]}" |
    xargs -0 -r -n 16 -P "$(nproc)" "$clang_format" -i --style="file:$PWD/.clang-format"
  exit 0
fi

# Each file that differs, with the number of its lines the format would change.
report="$(printf '%s\0' "${files[@]}" | xargs -0 -r -P "$(nproc)" -I{} sh -c '
  "$1" --style="file:$3" "$2" | cmp -s - "$2" && exit 0
  changed=$("$1" --style="file:$3" "$2" | diff "$2" - | grep -c "^<") || true
  echo "$2: $changed lines"' sh "$clang_format" {} "$PWD/.clang-format")"
if [ -n "$report" ]; then
  sort <<<"$report"
  echo "scripts/format.sh: $(wc -l <<<"$report") of ${#files[@]} files differ from" \
       ".clang-format; bash scripts/format.sh rewrites them" >&2
  exit 1
fi
echo "scripts/format.sh: ${#files[@]} files formatted"
