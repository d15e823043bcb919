#!/usr/bin/env bash
# Fuzz the volume loaders, the transfer-function parser and the renderer
# with libFuzzer:
#   tools/fuzz.sh [seconds-per-target] [target...]     (default 20 s, every target)
# Builds with clang into build-fuzz/ (ASan + UBSan, coverage on the library),
# runs each harness over its corpus (build-fuzz/corpus/<target>/, which
# grows run by run, plus the committed tests/fuzz/seeds/<target>/ and the
# reproducers in tests/fuzz/regressions/<target>/), then fuzzes it for the
# given time and prints its execution count.  -rss_limit_mb and
# -malloc_limit_mb 2048: an absurd allocation is a finding too; -timeout
# 25 s: the first input of fuzz_stack/fuzz_tar loads OpenImageIO's plugins,
# which took 12 s under ASan on a loaded machine.  A crash, leak, hang or
# OOM leaves its input in build-fuzz/crashes/<target>/ and is copied to
# tests/fuzz/regressions/<target>/, which tests/test_fuzz_regressions.c
# (tests/test_render_fuzz.c for render) replays in the normal test suite:
# commit it with the fix.
#
# VSPLAT_FUZZ_SEED fixes libFuzzer's seed and starts every target from the
# committed seeds and reproducers only (the grown corpus is cleared), so
# that a run can be repeated: CI runs `VSPLAT_FUZZ_SEED=1 tools/fuzz.sh 15`
# (10 targets, about 3 minutes after the build).  Unset: random seeds.
#
# Before a release, fuzz 10 minutes a target with random seeds, two at a
# time on two cores, and record the executions and findings (the summary
# lines) in docs/RELIABILITY.md:
#   tools/fuzz.sh 1                 # builds every harness (1 s each) first:
#                                   # a relink of the image module under a
#                                   # running harness crashes it (SIGBUS/SEGV)
#   tools/fuzz.sh 600 nifti nrrd den raw metaimage & tools/fuzz.sh 600 stack tar tf render dicom; wait
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
SECS=${1:-20}
shift || true
B=${VSPLAT_FUZZ_BUILD_DIR:-$ROOT/build-fuzz}
JOBS=${VSPLAT_JOBS:-2}
if ! [[ $SECS =~ ^[0-9]+$ ]] || [[ $SECS -lt 1 ]]; then
    echo "fuzz.sh: seconds per target must be a positive integer, got '$SECS'" >&2
    exit 1
fi
"$ROOT/tools/install-deps.sh"
command -v clang >/dev/null || { echo "fuzz.sh: clang is missing (tools/install-deps.sh installs it)" >&2; exit 1; }

cmake -S "$ROOT" -B "$B" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DVSPLAT_FUZZ=ON \
    -DVSPLAT_SANITIZE=address,undefined,fuzzer-no-link -DVSPLAT_WERROR=ON >/dev/null
targets=("$@")
if [[ ${#targets[@]} -eq 0 ]]; then
    targets=(nifti nrrd den raw stack tar metaimage)
    [[ -f /usr/include/gdcm-3.0/gdcmReader.h ]] && targets+=(dicom)
    [[ -f $ROOT/src/io/tf_file.c ]] && targets+=(tf)
    targets+=(render)
fi
cmake --build "$B" -j"$JOBS" --target "${targets[@]/#/fuzz_}" >/dev/null

# intercept_tls_get_addr=0: as in tools/sanitize.sh (LeakSanitizer's tracer
# dies on ASan's record of dynamic TLS on some machines once OIIO is loaded)
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:fast_unwind_on_malloc=0:allocator_may_return_null=1:intercept_tls_get_addr=0
export LSAN_OPTIONS=suppressions=$ROOT/tools/sanitize.supp:print_suppressions=0
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
found=0
summary=()
for t in "${targets[@]}"; do
    corpus="$B/corpus/$t"
    crashes="$B/crashes/$t"
    rm -rf "$crashes" # earlier findings were copied to tests/fuzz/regressions already
    if [[ -n ${VSPLAT_FUZZ_SEED:-} ]]; then rm -rf "$corpus"; fi # repeatable: the committed inputs only
    mkdir -p "$corpus" "$crashes"
    # new inputs go to the first folder; the committed ones are only read
    dirs=("$corpus")
    for d in "$ROOT/tests/fuzz/seeds/$t" "$ROOT/tests/fuzz/regressions/$t"; do if [[ -d $d ]]; then dirs+=("$d"); fi; done
    log="$B/fuzz_$t.log"
    echo "== fuzz_$t: $SECS s" >&2
    set +e
    (cd "$B" && "$B/tests/fuzz/fuzz_$t" "${dirs[@]}" ${VSPLAT_FUZZ_SEED:+-seed="$VSPLAT_FUZZ_SEED"} -max_total_time="$SECS" -timeout=25 -rss_limit_mb=2048 \
        -malloc_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$crashes/" >"$log" 2>&1)
    rc=$?
    set -e
    execs=$(grep -m1 'stat::number_of_executed_units' "$log" | awk '{print $2}')
    cov=$(grep -E '^#[0-9]+.*(DONE|pulse|NEW|REDUCE)' "$log" | tail -1 | grep -oE 'cov: [0-9]+' || true)
    n_corpus=$(find "$corpus" -type f | wc -l)
    arts=$(find "$crashes" -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) | wc -l)
    line="fuzz_$t: ${execs:-?} executions in $SECS s, ${cov:-cov: ?}, corpus $n_corpus, findings $arts (exit $rc)"
    summary+=("$line")
    echo "$line" >&2
    if [[ $arts -gt 0 || $rc -ne 0 ]]; then
        found=1
        mkdir -p "$ROOT/tests/fuzz/regressions/$t"
        find "$crashes" -type f -exec cp -n {} "$ROOT/tests/fuzz/regressions/$t/" \;
        grep -m1 -A12 -E 'ERROR|WARNING|runtime error|deadly signal' "$log" >&2 || tail -20 "$log" >&2
    fi
done
printf '%s\n' "${summary[@]}"
if [[ $found -ne 0 ]]; then
    echo "fuzz.sh: findings copied to tests/fuzz/regressions/ (logs in $B/fuzz_*.log)" >&2
    exit 1
fi
