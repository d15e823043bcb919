/* The reference ray caster (raycast.c). */
#ifndef VS_RAYCAST_H
#define VS_RAYCAST_H

#include "volume.h"

vs_status vs_raycast_render(vs_context *ctx, const struct vs_volume *vol,
                            const vs_settings *s, vs_image *out, vs_stats *st);

#endif
