#!/usr/bin/env bash
# Build the whole test suite with sanitizers and run it:
#   build-asan/  gcc, -DVSPLAT_SANITIZE=address,undefined  (ASan + UBSan + LeakSanitizer)
#   build-tsan/  clang, -DVSPLAT_SANITIZE=thread            (ThreadSanitizer)
# Usage: tools/sanitize.sh [asan|tsan]...   (default: both)
# Tests honour VSPLAT_TEST_QUICK=1 (smaller images and volumes, shorter soak).
# Every sanitizer halts on the first report, so a finding fails its test.
# Suppressions only for third-party libraries, each with its reason:
# tools/sanitize.supp (LeakSanitizer), tools/sanitize-tsan.supp (TSan).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$ROOT/tools/install-deps.sh"
JOBS=${VSPLAT_JOBS:-2}
export VSPLAT_TEST_QUICK=${VSPLAT_TEST_QUICK:-1}
export VSPLAT_SANITIZED=1 # tests/cli_hostile.sh: no ulimit -v (sanitizers reserve terabytes of shadow)
SUPP="$ROOT/tools/sanitize.supp"

kinds=("$@")
[[ ${#kinds[@]} -eq 0 ]] && kinds=(asan tsan)
status=0
t_all=$(date +%s)
for kind in "${kinds[@]}"; do
    t0=$(date +%s)
    case $kind in
    asan)
        B="$ROOT/build-asan"
        cmake -S "$ROOT" -B "$B" -DVSPLAT_SANITIZE=address,undefined -DVSPLAT_WERROR=ON \
            -DCMAKE_C_COMPILER=gcc -DCMAKE_CXX_COMPILER=g++ >/dev/null
        # intercept_tls_get_addr=0: on some machines (a 2-core EPYC VM whose
        # CPUID hides RDTSCP) ASan's record of dynamic TLS goes wrong once
        # the OpenImageIO module is loaded ("DTLS 15 at 0x1d09-0x800002e0b"),
        # and LeakSanitizer's tracer dies on it at exit (SIGSEGV, exit 134)
        # after every image written; without the interception LSan still
        # scans static TLS and the heap
        env_vars=(
            "ASAN_OPTIONS=halt_on_error=1:abort_on_error=1:detect_leaks=1:fast_unwind_on_malloc=0:detect_stack_use_after_return=1:strict_string_checks=1:check_initialization_order=1:intercept_tls_get_addr=0"
            "UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1"
            "LSAN_OPTIONS=suppressions=$SUPP:print_suppressions=0"
        )
        ;;
    tsan)
        B="$ROOT/build-tsan"
        # gcc's TSan works too, but clang's is the reference implementation
        cmake -S "$ROOT" -B "$B" -DVSPLAT_SANITIZE=thread -DVSPLAT_WERROR=ON \
            -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ >/dev/null
        # its own file: TSan cannot parse the LSan entries of sanitize.supp
        env_vars=("TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$ROOT/tools/sanitize-tsan.supp"
            "VSPLAT_TEST_NOFORK=1") # test_stiff: TSan forbids threads after a multi-threaded fork
        ;;
    *)
        echo "sanitize.sh: unknown kind '$kind' (asan, tsan)" >&2
        exit 1
        ;;
    esac
    echo "== $kind: building in $B" >&2
    cmake --build "$B" -j"$JOBS" >/dev/null
    t1=$(date +%s)
    echo "== $kind: built in $((t1 - t0)) s; running ctest" >&2
    if ! env "${env_vars[@]}" ctest --test-dir "$B" --output-on-failure -j"$JOBS" --timeout 1500; then
        status=1
        echo "== $kind: FAILED" >&2
    fi
    t2=$(date +%s)
    echo "== $kind: build $((t1 - t0)) s, tests $((t2 - t1)) s" >&2
done
echo "== sanitize.sh: total $(( $(date +%s) - t_all )) s, $([[ $status -eq 0 ]] && echo passed || echo FAILED)" >&2
exit $status
