/* The GDCM module's calls run in a child process, one per batch of files.
 * GDCM as Debian builds it keeps its assertions, and some malformed files
 * trip one (found by tests/fuzz/fuzz_dicom.c): abort() would end the
 * caller's program, where a bad file must only be an error.  The child
 * calls the module file after file, sends each result through a pipe as it
 * goes and _exits (no atexit handlers, no flushing of the parent's
 * buffers); when it dies, the file it was on gets the error.  One child per
 * batch, not per file: GDCM sets up its dictionaries on first use, which a
 * child would otherwise repeat for every file. */
#include "dicom_guard.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

typedef struct reply {
    int status;
    int type;
    char err[256];
} reply;

static int write_all(int fd, const void *p, size_t n)
{
    const char *c = p;
    while (n) {
        ssize_t w = write(fd, c, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return 0;
        c += w;
        n -= (size_t)w;
    }
    return 1;
}

static int read_all(int fd, void *p, size_t n)
{
    char *c = p;
    while (n) {
        ssize_t r = read(fd, c, n);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return 0;
        c += r;
        n -= (size_t)r;
    }
    return 1;
}

/* The child's side: every file in turn, a reply and (on success) its
 * payload each; stops after the first failure. */
/* Sanitizer builds reserve terabytes of address space: no cap there. */
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define VS_CAP_CHILD 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define VS_CAP_CHILD 0
#endif
#endif
#ifndef VS_CAP_CHILD
#define VS_CAP_CHILD 1
#endif

/* GDCM allocates a length it read before it reads the bytes, and after
 * failing a file in its declared syntax it rereads it little-endian with
 * VRs guessed, where lengths are misread (up to 4 GiB for a kilobyte
 * file, fuzz_dicom).  The element walk refuses the cases found; this caps
 * whatever it misses: the child's address space grows by at most 1 GiB
 * plus twice the pixel buffer, and an allocation past it fails inside
 * GDCM (std::bad_alloc, caught by the adapter) instead of taking memory. */
static void cap_child(size_t bytes)
{
#if VS_CAP_CHILD
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long long pages = 0;
    const int ok = f && fscanf(f, "%llu", &pages) == 1;
    if (f) fclose(f);
    if (!ok) return;
    const rlim_t cap = (rlim_t)pages * (rlim_t)sysconf(_SC_PAGESIZE) + ((rlim_t)1 << 30) + 2 * (rlim_t)bytes;
    struct rlimit r = {cap, cap};
    (void)setrlimit(RLIMIT_AS, &r);
#else
    (void)bytes;
#endif
}

static void child(int fd, const vs_dicom_api *api, char *const *paths, int n, int rows, int cols, void *buf,
                  size_t bytes)
{
    cap_child(bytes);
    /* a failed assertion's text is GDCM's, not ours to print; and the
     * crash is the parent's to report, not a handler's the program (or a
     * fuzzer) installed */
    int nul = open("/dev/null", O_WRONLY);
    if (nul >= 0) dup2(nul, STDERR_FILENO);
    static const int sigs[] = {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL};
    for (size_t k = 0; k < sizeof sigs / sizeof *sigs; k++) signal(sigs[k], SIG_DFL);
    for (int i = 0; i < n; i++) {
        reply r;
        memset(&r, 0, sizeof r);
        vs_dicom_header h;
        vs_dicom_sample t = VS_DCM_OTHER;
        if (!buf) r.status = api->read_header(paths[i], &h, r.err, sizeof r.err);
        else r.status = api->read_pixels(paths[i], rows, cols, buf, bytes, &t, r.err, sizeof r.err);
        r.type = (int)t;
        if (!write_all(fd, &r, sizeof r)) _exit(1);
        if (r.status != VS_OK) _exit(0);
        if (!(buf ? write_all(fd, buf, bytes) : write_all(fd, &h, sizeof h))) _exit(1);
    }
    _exit(0);
}

/* Run a batch; `take` gets each file's result in order.  On failure
 * *failed is the file's index and err its message. */
static vs_status batch(const vs_dicom_api *api, char *const *paths, int n, int rows, int cols, size_t bytes,
                       vs_dicom_header *headers, vs_dicom_sink take, void *user, int *failed, char *err,
                       size_t errcap)
{
    *failed = 0;
    void *buf = NULL;
    if (!headers && !(buf = malloc(bytes ? bytes : 1))) {
        snprintf(err, errcap, "out of memory");
        return VS_ERR_OUT_OF_MEMORY;
    }
    int fd[2];
    if (pipe(fd) != 0) {
        free(buf);
        snprintf(err, errcap, "cannot create a pipe: %s", strerror(errno));
        return VS_ERR_IO;
    }
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        free(buf);
        snprintf(err, errcap, "cannot start a process to parse DICOM: %s", strerror(errno));
        return VS_ERR_IO;
    }
    if (pid == 0) {
        close(fd[0]);
        child(fd[1], api, paths, n, rows, cols, buf, bytes);
    }
    close(fd[1]);
    vs_status st = VS_OK;
    int died = 0, i = 0;
    for (; i < n && st == VS_OK && !died; i++) {
        reply r;
        if (!read_all(fd[0], &r, sizeof r)) { died = 1; break; }
        r.err[sizeof r.err - 1] = '\0';
        if (r.status != VS_OK) {
            st = (vs_status)r.status;
            snprintf(err, errcap, "%s", r.err);
            break;
        }
        if (headers) {
            if (!read_all(fd[0], &headers[i], sizeof headers[i])) { died = 1; break; }
        } else {
            if (!read_all(fd[0], buf, bytes)) { died = 1; break; }
            take(user, i, buf, (vs_dicom_sample)r.type);
        }
    }
    close(fd[0]);
    int ws = 0;
    while (waitpid(pid, &ws, 0) < 0 && errno == EINTR) {
    }
    free(buf);
    if (died) {
        st = VS_ERR_FORMAT;
        if (WIFSIGNALED(ws))
            snprintf(err, errcap, "malformed DICOM: GDCM stopped on it (%s)", strsignal(WTERMSIG(ws)));
        else snprintf(err, errcap, "malformed DICOM: GDCM stopped on it");
    }
    *failed = i < n ? i : n - 1;
    return st;
}

vs_status vs_dicom_headers_guarded(const vs_dicom_api *api, char *const *paths, int n, vs_dicom_header *out,
                                   int *failed, char *err, size_t errcap)
{
    if (n <= 0) return VS_OK;
    return batch(api, paths, n, 0, 0, 0, out, NULL, NULL, failed, err, errcap);
}

vs_status vs_dicom_pixels_guarded(const vs_dicom_api *api, char *const *paths, int n, int rows, int cols,
                                  size_t bytes, vs_dicom_sink take, void *user, int *failed, char *err,
                                  size_t errcap)
{
    if (n <= 0) return VS_OK;
    return batch(api, paths, n, rows, cols, bytes, NULL, take, user, failed, err, errcap);
}
