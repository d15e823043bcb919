/* Loading the OpenImageIO adapter module (src/io/oiio_adapter.h says why it is
 * a module).  The handle lives in the context, like every other cache; the
 * module is opened RTLD_NODELETE because OpenImageIO keeps threads and
 * static objects that must outlive any dlclose. */
#include "context.h"
#include "oiio_adapter.h"

#include <dlfcn.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VS_LSAN_EARLY 1
#endif
#elif defined(__SANITIZE_ADDRESS__)
#define VS_LSAN_EARLY 1
#endif
#ifdef VS_LSAN_EARLY
#include <pthread.h>
#include <sanitizer/lsan_interface.h>

/* Sanitizer builds only.  OpenImageIO loads OpenVDB, whose log4cplus starts
 * threads when loaded and stops them from a destructor at exit, registered
 * after LeakSanitizer's exit-time check and so run before it: that check can
 * then meet threads half way through exiting, and its tracer crashes
 * ("Tracer caught signal 11").  An atexit handler registered after the
 * module is loaded runs before that destructor, while those threads are
 * idle; the check made there is the process's only one. */
static void lsan_check_now(void) { __lsan_do_leak_check(); }
static void lsan_register(void) { atexit(lsan_check_now); }
static pthread_once_t lsan_once = PTHREAD_ONCE_INIT;
#endif

#ifndef VS_INSTALL_LIBDIR
#define VS_INSTALL_LIBDIR "lib"
#endif
#ifndef VS_INSTALL_MODULEDIR
#define VS_INSTALL_MODULEDIR "/usr/local/lib/vsplat-modules"
#endif

/* The module folder of the prefix a program linked with the installed
 * libvsplat.a found it in: defined by a one-line source that the CMake
 * package (vsplatConfig.cmake) adds to such programs, so that an install
 * made with `cmake --install --prefix P` works wherever the program lives;
 * absent (NULL) otherwise. */
extern const char vs_oiio_install_moduledir[] __attribute__((weak));

/* Try one path: the table, or NULL with the reason appended to `why`. */
static const vs_oiio_api *try_open(const char *path, void **handle, char *why, size_t cap)
{
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    size_t used = strlen(why);
    if (!h) {
        const char *e = dlerror();
        snprintf(why + used, cap - used, "%s%s", used ? "; " : "", e ? e : path);
        return NULL;
    }
    const vs_oiio_api *(*entry)(void) = NULL;
    *(void **)&entry = dlsym(h, VS_OIIO_MODULE_ENTRY);
    const vs_oiio_api *api = entry ? entry() : NULL;
    if (!api) {
        snprintf(why + used, cap - used, "%s%s: no %s", used ? "; " : "", path, VS_OIIO_MODULE_ENTRY);
        dlclose(h);
        return NULL;
    }
    *handle = h;
#ifdef VS_LSAN_EARLY
    pthread_once(&lsan_once, lsan_register);
#endif
    return api;
}

const vs_oiio_api *vs_oiio(vs_context *ctx)
{
    if (ctx->oiio) return ctx->oiio;
    char why[1024] = "";
    const char *env = getenv(VS_OIIO_MODULE_ENV);
    if (env && *env) {
        ctx->oiio = try_open(env, &ctx->oiio_handle, why, sizeof why);
        if (!ctx->oiio)
            vs_set_error(ctx, VS_ERR_IO, "image I/O: cannot load the OpenImageIO module %s=%s (%s)",
                         VS_OIIO_MODULE_ENV, env, why);
        return ctx->oiio;
    }
    /* the folder of the binary that holds this code: libvsplat.so, or a
     * program linked with libvsplat.a */
    char dir[PATH_MAX] = "";
    Dl_info info;
    if (dladdr((void *)vs_oiio, &info) && info.dli_fname && strlen(info.dli_fname) < sizeof dir) {
        const char *src = info.dli_fname;
        char real[PATH_MAX];
        if (realpath(src, real)) src = real;
        snprintf(dir, sizeof dir, "%s", src);
        char *slash = strrchr(dir, '/');
        if (slash) *slash = '\0';
        else snprintf(dir, sizeof dir, ".");
    }
    /* beside it (libvsplat.so, build/vsplat), one or two folders up (the
     * build tree's tests/, bench/, tests/fuzz/), under ../LIBDIR (bin/) */
    static const char up_libdir[] = "/../" VS_INSTALL_LIBDIR;
    const char *rel[] = {"", "/..", "/../..", up_libdir};
    char path[PATH_MAX + 64];
    for (size_t i = 0; dir[0] && i < sizeof rel / sizeof *rel; i++) {
        snprintf(path, sizeof path, "%s%s/vsplat-modules/%s", dir, rel[i], VS_OIIO_MODULE_NAME);
        if (access(path, R_OK)) continue;
        if ((ctx->oiio = try_open(path, &ctx->oiio_handle, why, sizeof why))) return ctx->oiio;
    }
    const char *pkg = vs_oiio_install_moduledir;
    if (pkg && pkg[0]) {
        snprintf(path, sizeof path, "%s/%s", pkg, VS_OIIO_MODULE_NAME);
        if (!access(path, R_OK) && (ctx->oiio = try_open(path, &ctx->oiio_handle, why, sizeof why)))
            return ctx->oiio;
    }
    snprintf(path, sizeof path, "%s/%s", VS_INSTALL_MODULEDIR, VS_OIIO_MODULE_NAME);
    if (!access(path, R_OK) && (ctx->oiio = try_open(path, &ctx->oiio_handle, why, sizeof why))) return ctx->oiio;
    vs_set_error(ctx, VS_ERR_IO,
                 "image I/O: cannot load the OpenImageIO module %s (looked in vsplat-modules/ in, one and two "
                 "folders above, and under ../%s from %s, and in %s%s%s%s%s); set %s to its path",
                 VS_OIIO_MODULE_NAME, VS_INSTALL_LIBDIR, dir[0] ? dir : "(unknown)", pkg && pkg[0] ? pkg : "",
                 pkg && pkg[0] ? " and " : "", VS_INSTALL_MODULEDIR,
                 why[0] ? ": " : "", why, VS_OIIO_MODULE_ENV);
    return NULL;
}
