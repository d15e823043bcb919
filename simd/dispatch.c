/* Kernel selection: the scalar reference first, then each kernel upgraded
 * to the best ISA that this CPU and the cap allow, where a version exists
 * (only where it measured faster: `vsplat-bench kernels`, docs/PERFORMANCE.md).
 * The choice lives in the caller's table (one per frame), never in a
 * global. */
#include "kernels.h"

#include <stdlib.h>
#include <string.h>


vs_isa vs_isa_from_env(void)
{
    const char *e = getenv("VSPLAT_ISA");
    vs_isa isa;
    if (!e || !*e || vs_isa_parse(e, &isa) != VS_OK) return VS_ISA_AUTO;
    return isa;
}

void vs_kernels_init(vs_kernels *k, vs_isa cap)
{
    vs_isa best = vs_isa_detect();
    if (cap == VS_ISA_AUTO || cap > best) cap = best;
    memset(k, 0, sizeof *k);
    k->isa = VS_ISA_SCALAR;
    k->splat_row1 = vs_splat_row1_scalar;
    k->splat_row4 = vs_splat_row4_scalar;
    k->composite = vs_composite_scalar;
    k->splat_block = vs_splat_block_scalar;
    k->splat_block_mix = vs_splat_block_mix_scalar;
    k->classify_cd = vs_classify_cd_scalar;
    k->classify_gs = vs_classify_gs_scalar;
    k->shade_lut = vs_shade_lut_scalar;
    k->shade_terms = vs_shade_terms_scalar;
    k->preint_alpha = vs_preint_alpha_scalar;
    k->project_brick = vs_project_brick_scalar;
    k->splat_voxel1 = vs_splat_voxel1_scalar;
    k->splat_voxel4 = vs_splat_voxel4_scalar;
    k->splat_voxel_gs = vs_splat_voxel_gs_scalar;
    k->splat_rows_mix = vs_splat_rows_mix_scalar;
    k->place_voxels = vs_place_voxels_scalar;
#if defined(__x86_64__) || defined(__i386__)
    if (cap >= VS_ISA_SSE4) {
        k->isa = VS_ISA_SSE4;
        k->splat_row4 = vs_splat_row4_sse4;
        k->splat_block = vs_splat_block_sse4;
        k->splat_block_mix = vs_splat_block_mix_sse4;
    }
    if (cap >= VS_ISA_AVX2) {
        k->isa = VS_ISA_AVX2;
        k->splat_row4 = vs_splat_row4_avx2;
        k->splat_block = vs_splat_block_avx2;
        k->splat_block_mix = vs_splat_block_mix_avx2; /* also for avx512 */
        k->classify_cd = vs_classify_cd_avx2;
        k->classify_gs = vs_classify_gs_avx2;
        k->shade_lut = vs_shade_lut_avx2;
        k->shade_terms = vs_shade_terms_avx2;
        k->preint_alpha = vs_preint_alpha_avx2;
        k->composite = vs_composite_avx2;
        k->project_brick = vs_project_brick_avx2;
        k->splat_voxel1 = vs_splat_voxel1_avx2;
        k->splat_voxel4 = vs_splat_voxel4_avx2;     /* also for avx512 */
        k->splat_voxel_gs = vs_splat_voxel_gs_avx2; /* also for avx512 */
        k->splat_rows_mix = vs_splat_rows_mix_avx2; /* also for avx512 */
        k->place_voxels = vs_place_voxels_avx2;
    }
    if (cap >= VS_ISA_AVX512) {
        k->isa = VS_ISA_AVX512;
        k->splat_row4 = vs_splat_row4_avx512;
        k->splat_block = vs_splat_block_avx512;
        k->project_brick = vs_project_brick_avx512;
        k->splat_voxel1 = vs_splat_voxel1_avx512;
        k->place_voxels = vs_place_voxels_avx512;
    }
#endif
}
