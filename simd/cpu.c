/* CPU feature probe: cpuid for the instruction sets plus xgetbv for the
 * operating system's register-state support (AVX needs YMM state saved,
 * AVX-512 also opmask and ZMM state). */
#include "vsplat.h"

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>

static unsigned long long read_xcr0(void)
{
    unsigned int lo, hi;
    __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    return ((unsigned long long)hi << 32) | lo;
}

vs_isa vs_isa_detect(void)
{
    unsigned int a, b, c, d;
    if (!__get_cpuid(1, &a, &b, &c, &d)) return VS_ISA_SCALAR;
    int sse41 = (c >> 19) & 1, osxsave = (c >> 27) & 1, avx = (c >> 28) & 1, fma = (c >> 12) & 1;
    if (!sse41) return VS_ISA_SCALAR;
    if (!osxsave || !avx) return VS_ISA_SSE4;
    unsigned long long xcr0 = read_xcr0();
    if ((xcr0 & 0x6) != 0x6) return VS_ISA_SSE4; /* XMM and YMM state */
    if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return VS_ISA_SSE4;
    int avx2 = (b >> 5) & 1;
    int avx512f = (b >> 16) & 1, avx512dq = (b >> 17) & 1, avx512bw = (b >> 30) & 1, avx512vl = (b >> 31) & 1;
    if (!avx2 || !fma) return VS_ISA_SSE4;
    if (avx512f && avx512dq && avx512bw && avx512vl && (xcr0 & 0xe6) == 0xe6) return VS_ISA_AVX512;
    return VS_ISA_AVX2;
}
#else
vs_isa vs_isa_detect(void) { return VS_ISA_SCALAR; }
#endif
