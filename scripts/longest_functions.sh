#!/usr/bin/env bash
# Lists the longest functions of the project's C++ sources (lines from the
# signature to the closing brace), as universal-ctags sees them.
#   bash scripts/longest_functions.sh [N] [DIR...]   (default: 10, the source folders)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-10}
shift || true
dirs=("$@")
[ ${#dirs[@]} -eq 0 ] && dirs=(geometry renderer harness)
command -v ctags >/dev/null || { echo "longest_functions: needs universal-ctags (apt-get install universal-ctags)" >&2; exit 1; }
ctags -R -x --languages=C++ --kinds-C++=f --fields=+ne --_xformat='%{end} %n %F %{scope} %N' "${dirs[@]}" |
  awk '$1 ~ /^[0-9]+$/ { len = $1 - $2 + 1; scope = ($4 == "-" ? "" : $4 "::"); printf "%5d  %s:%d  %s%s\n", len, $3, $2, scope, $5 }' |
  sed -E "s/__anon[0-9a-f]+:://g; s/curvlab:://" | sort -rn | head -n "$n"
