# Helpers shared by the CLI tests (tests/cli_*.sh), sourced after
# `set -euo pipefail`: pass/fail counting, a temporary folder, and running
# vsplat with its output kept.  A script whose runs need more (a timeout,
# a memory limit) defines its own run after sourcing this.
passed=0
failed=0
ok() { passed=$((passed + 1)); }
bad() { failed=$((failed + 1)); echo "FAIL: $*" >&2; }

# tu_setup PATH_TO_VSPLAT: VSPLAT as an absolute path, T a fresh folder
# removed on exit
tu_setup() {
    VSPLAT=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
    T=$(mktemp -d)
    trap 'rm -rf "$T"' EXIT
}

# run ARGS...: runs vsplat; sets rc, stdout in $T/out, stderr in $T/err
run() {
    set +e
    "$VSPLAT" "$@" >"$T/out" 2>"$T/err"
    rc=$?
    set -e
}
# expect_ok DESC ARGS...: vsplat ARGS exits 0
expect_ok() {
    local desc=$1
    shift
    run "$@"
    if [[ $rc -eq 0 ]]; then ok; else bad "$desc: exit $rc; stderr: $(head -c 400 "$T/err")"; fi
}
expect_file() { if [[ -s $1 ]]; then ok; else bad "$2: $1 was not written"; fi; }
# expect_out / expect_err REGEX DESC: the last run's stdout / stderr matches
expect_out() { if grep -Eq -- "$1" "$T/out"; then ok; else bad "$2: stdout lacks /$1/: $(head -c 400 "$T/out")"; fi; }
expect_err() { if grep -Eq -- "$1" "$T/err"; then ok; else bad "$2: stderr lacks /$1/: $(head -c 400 "$T/err")"; fi; }

# tu_done: the summary line; the exit status says whether every check passed
tu_done() {
    echo "$passed passed, $failed failed"
    [[ $failed -eq 0 ]]
}
