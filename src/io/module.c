/* Loading the C++ adapter modules: image I/O through OpenImageIO
 * (src/io/oiio_adapter.h says why it is a module) and DICOM through GDCM
 * (src/io/dicom_adapter.h).  The handles live in the context, like every
 * other cache; modules are opened RTLD_NODELETE because OpenImageIO keeps
 * threads and static objects that must outlive any dlclose. */
#include "context.h"
#include "dicom_adapter.h"
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
 * absent (NULL) otherwise.  Every module is installed there. */
extern const char vs_oiio_install_moduledir[] __attribute__((weak));

/* What one module is called, and where the context keeps it. */
typedef struct module_spec {
    const char *what;  /* "image I/O: cannot load the OpenImageIO module" */
    const char *name;  /* file name in vsplat-modules/                    */
    const char *entry; /* the one exported function, returning the table */
    const char *env;   /* variable that gives its path                   */
} module_spec;

/* Try one path: the table, or NULL with the reason appended to `why`. */
static const void *try_open(const char *path, const char *entry_name, void **handle, char *why,
                            size_t cap)
{
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    size_t used = strlen(why);
    if (!h) {
        const char *e = dlerror();
        snprintf(why + used, cap - used, "%s%s", used ? "; " : "", e ? e : path);
        return NULL;
    }
    const void *(*entry)(void) = NULL;
    *(void **)&entry = dlsym(h, entry_name);
    const void *api = entry ? entry() : NULL;
    if (!api) {
        snprintf(why + used, cap - used, "%s%s: no %s", used ? "; " : "", path, entry_name);
        dlclose(h);
        return NULL;
    }
    *handle = h;
#ifdef VS_LSAN_EARLY
    pthread_once(&lsan_once, lsan_register);
#endif
    return api;
}

/* The module's table, searched as src/io/oiio_adapter.h describes; NULL
 * with the context's error saying why and where it looked. */
static const void *load_module(vs_context *ctx, const module_spec *m, void **handle)
{
    const void *api = NULL;
    char why[1024] = "";
    const char *env = getenv(m->env);
    if (env && *env) {
        api = try_open(env, m->entry, handle, why, sizeof why);
        if (!api) vs_set_error(ctx, VS_ERR_IO, "%s %s=%s (%s)", m->what, m->env, env, why);
        return api;
    }
    /* the folder of the binary that holds this code: libvsplat.so, or a
     * program linked with libvsplat.a */
    char dir[PATH_MAX] = "";
    Dl_info info;
    if (dladdr((void *)load_module, &info) && info.dli_fname && strlen(info.dli_fname) < sizeof dir) {
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
        snprintf(path, sizeof path, "%s%s/vsplat-modules/%s", dir, rel[i], m->name);
        if (access(path, R_OK)) continue;
        if ((api = try_open(path, m->entry, handle, why, sizeof why))) return api;
    }
    const char *pkg = vs_oiio_install_moduledir;
    if (pkg && pkg[0]) {
        snprintf(path, sizeof path, "%s/%s", pkg, m->name);
        if (!access(path, R_OK) && (api = try_open(path, m->entry, handle, why, sizeof why))) return api;
    }
    snprintf(path, sizeof path, "%s/%s", VS_INSTALL_MODULEDIR, m->name);
    if (!access(path, R_OK) && (api = try_open(path, m->entry, handle, why, sizeof why))) return api;
    vs_set_error(ctx, VS_ERR_IO,
                 "%s %s (looked in vsplat-modules/ in, one and two folders above, and under ../%s from %s, "
                 "and in %s%s%s%s%s); set %s to its path",
                 m->what, m->name, VS_INSTALL_LIBDIR, dir[0] ? dir : "(unknown)", pkg && pkg[0] ? pkg : "",
                 pkg && pkg[0] ? " and " : "", VS_INSTALL_MODULEDIR, why[0] ? ": " : "", why, m->env);
    return NULL;
}

const vs_oiio_api *vs_oiio(vs_context *ctx)
{
    static const module_spec spec = {"image I/O: cannot load the OpenImageIO module", VS_OIIO_MODULE_NAME,
                                     VS_OIIO_MODULE_ENTRY, VS_OIIO_MODULE_ENV};
    if (!ctx->oiio) ctx->oiio = load_module(ctx, &spec, &ctx->oiio_handle);
    return ctx->oiio;
}

const vs_dicom_api *vs_dicom(vs_context *ctx)
{
    static const module_spec spec = {"DICOM: cannot load the GDCM module", VS_DICOM_MODULE_NAME,
                                     VS_DICOM_MODULE_ENTRY, VS_DICOM_MODULE_ENV};
    if (!ctx->dicom) ctx->dicom = load_module(ctx, &spec, &ctx->dicom_handle);
    return ctx->dicom;
}
