/* Error reporting: the context's last-error message and status names.
 * Every file that reports an error depends on this one alone, not on the
 * context's lifetime (context.c), which frees the caches those files keep. */
#include "context.h"

#include <stdarg.h>
#include <stdio.h>

const char *vs_last_error(const vs_context *ctx)
{
    if (!ctx) return "no context";
    return ctx->error;
}

vs_status vs_set_error(vs_context *ctx, vs_status st, const char *fmt, ...)
{
    if (ctx) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(ctx->error, sizeof ctx->error, fmt, ap);
        va_end(ap);
    }
    return st;
}

const char *vs_status_string(vs_status s)
{
    switch (s) {
    case VS_OK: return "ok";
    case VS_ERR_INVALID_ARGUMENT: return "invalid argument";
    case VS_ERR_IO: return "i/o error";
    case VS_ERR_FORMAT: return "malformed input";
    case VS_ERR_OUT_OF_MEMORY: return "out of memory";
    case VS_ERR_TOO_LARGE: return "too large";
    case VS_ERR_UNSUPPORTED: return "unsupported";
    case VS_ERR_CANCELLED: return "cancelled";
    case VS_ERR_INTERNAL: return "internal error";
    case VS_ERR_BUSY: return "context busy: another thread is using it (one context per thread)";
    }
    return "unknown status";
}
