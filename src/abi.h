/* The public structs' struct_size scheme (docs/ABI.md): which sizes are
 * layouts this library knows, and the copies between a caller's struct of
 * such a size and the library's full one. */
#ifndef VS_ABI_H
#define VS_ABI_H

#include "vsplat.h"

#include <stddef.h>

/* Where field m of struct type T ends. */
#define VS_FIELD_END(T, m) (offsetof(T, m) + sizeof(((T *)0)->m))

/* 1 if size is a vs_stats layout this library knows. */
int vs_stats_layout_known(size_t size);

/* The caller's settings (s->struct_size bytes) into *full, the fields its
 * layout lacks at their defaults; full->stats_size stays the caller's.
 * VS_ERR_INVALID_ARGUMENT, with the context's message, for a struct_size
 * or stats_size this library does not know. */
vs_status vs_settings_import(vs_context *ctx, const vs_settings *s, vs_settings *full);

/* The library's full stats into the caller's struct of `size` bytes (a
 * known layout), struct_size set to it. */
void vs_stats_export(const vs_stats *full, vs_stats *out, size_t size);

/* Like vs_settings_import, but *full must hold the defaults already (the
 * loader fills it: this file depends on no other of the library's); NULL o
 * leaves them. */
vs_status vs_load_options_import(vs_context *ctx, const vs_load_options *o, vs_load_options *full);

#endif
