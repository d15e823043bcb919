#!/usr/bin/env bash
# The library's structure, checked: no import circle between its files
# (object A uses a symbol object B defines, and B, through any chain, one
# of A's), and no source file in src/ over 800 lines.
#   tests/layers.sh SOURCE_DIR OBJECT...
set -euo pipefail
src=$1
shift
fail=0
edges=$(mktemp)
trap 'rm -f "$edges"' EXIT
# symbol -> object that defines it; then an edge per use of another's
for o in "$@"; do
    nm "$o" | awk -v o="$(basename "$o" .o)" '$2 ~ /^[TDBR]$/ { print "D", $3, o } $1 == "U" { print "U", $2, o }'
done | awk '$1 == "D" { def[$2] = $3; next } { use[NR] = $2 " " $3 }
    END { for (i in use) { split(use[i], p, " "); if ((p[1] in def) && def[p[1]] != p[2]) print p[2], def[p[1]] } }' |
    sort -u >"$edges"
n=$(wc -l <"$edges")
if [ "$n" -lt 20 ]; then
    echo "FAIL: only $n dependencies between ${#@} objects: nm found nothing to check"
    fail=1
fi
if ! loops=$(tsort "$edges" 2>&1 >/dev/null) || [ -n "$loops" ]; then
    echo "FAIL: import circle between library files:"
    echo "$loops" | sed 's/^/  /'
    fail=1
else
    echo "no import circle among $# objects ($n dependencies)"
fi
while read -r lines file; do
    [ "$file" = total ] && continue
    if [ "$lines" -gt 800 ]; then
        echo "FAIL: $file has $lines lines (at most 800)"
        fail=1
    fi
done < <(find "$src/src" -name '*.[ch]' -o -name '*.cpp' | xargs wc -l)
echo "largest file in src/: $(find "$src/src" -name '*.[ch]' -o -name '*.cpp' | xargs wc -l | sort -n | tail -2 | head -1)"
exit $fail
