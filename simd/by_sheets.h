/* The voxel kernels' usual sheet counts as constants: BY_SHEETS(CALL)
 * calls CALL(2) .. CALL(5) for those counts of ns and CALL(ns) for the
 * others, so that an always_inline body is compiled once per count and
 * keeps the sheets' weights and destinations in registers over the whole
 * footprint (with ns a variable they are reloaded for every vector:
 * splat_voxel4 and splat_voxel_gs measured 1.2-1.3x faster constant). */
#ifndef VS_BY_SHEETS_H
#define VS_BY_SHEETS_H

#define BY_SHEETS(CALL)                                                                                                \
    switch (ns) {                                                                                                      \
    case 2: CALL(2); break;                                                                                            \
    case 3: CALL(3); break;                                                                                            \
    case 4: CALL(4); break;                                                                                            \
    case 5: CALL(5); break;                                                                                            \
    default: CALL(ns); break;                                                                                          \
    }

#endif
