#!/usr/bin/env bash
# The library's structure in figures, for before/after comparisons of a redesign (issue notes,
# docs/development.md "Layering"): lines per room of host/, the files over 500 lines, the longest
# functions, the mean function length, and the lower layers' upward includes.
#
#   bash scripts/structure_figures.sh [CHECKOUT]      (CHECKOUT defaults to this one)
#
# Counts physical lines of host/ (C++ sources and headers; tests, tools and kernels left out).
# Function extents come from Universal Ctags (Debian package universal-ctags): a function is
# its definition's first to last line, its braces included.
set -euo pipefail

root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$root"
command -v ctags >/dev/null && ctags --version 2>/dev/null | grep -q Universal ||
  { echo "structure_figures: needs Universal Ctags (apt install universal-ctags)" >&2; exit 1; }

echo "== lines per room of host/ (files, lines)"
for room in host/*/ host; do
  if [[ "$room" == host ]]; then
    files=$(find host -maxdepth 1 -name '*.[ch]pp')
    name="host/ (top level)"
  else
    files=$(find "$room" -name '*.[ch]pp')
    name=$room
  fi
  [[ -n "$files" ]] || continue
  # shellcheck disable=SC2086
  printf '%-28s %4d %7d\n' "$name" "$(echo "$files" | wc -l)" "$(cat $files | wc -l)"
done

echo "== files over 500 lines"
find host -name '*.[ch]pp' -print0 | xargs -0 wc -l | awk '$2 != "total" && $1 > 500 {print "  " $1, $2}' | sort -rn

echo "== longest functions (lines, name, file:line)"
# One line per function: its length, name and place (awk reads to the end: no pipe is cut short).
lengths=$(ctags -R --languages=C++ --kinds-C++=f --fields=+ne -o - host | awk -F'\t' '{
    line = 0; end = 0
    for (i = 4; i <= NF; ++i) {
      if ($i ~ /^line:/) line = substr($i, 6)
      if ($i ~ /^end:/) end = substr($i, 5)
    }
    if (end > 0) print end - line + 1, $1, $2 ":" line
  }' | sort -rn)
echo "$lengths" | awk 'NR <= 10 {print "  " $0}'
echo "$lengths" | awk '{n += 1; sum += $1} END {printf "== functions: %d, mean length %.1f lines\n", n, sum / n}'

echo "== upward includes (a lower layer including the facade or the stepping rooms)"
lower=(host/elements host/scene host/solver host/contact host/cpu host/opencl host/opencl_disabled)
existing=()
for d in "${lower[@]}"; do [[ -e "$d" ]] && existing+=("$d"); done
count=$(grep -rnE '#include *[<"](stabint/(simulator|batch|events|stabint)\.hpp|(integrator|state|scripting)/)' \
  "${existing[@]}" | wc -l || true)
echo "  $count"
