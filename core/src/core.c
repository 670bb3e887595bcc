/* Results, diagnostics, allocation, frame math and file helpers shared by all modules. */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "xyl_internal.h"

/* One table, indexed by code, so names cannot drift from the enum. */
static const char *const result_names[XYL_RESULT_COUNT_] = {
    [XYL_OK] = "ok",
    [XYL_ERR_INVALID_ARGUMENT] = "invalid argument",
    [XYL_ERR_OUT_OF_MEMORY] = "out of memory",
    [XYL_ERR_INVALID_GRAMMAR] = "invalid grammar",
    [XYL_ERR_LIMIT_EXCEEDED] = "limit exceeded",
    [XYL_ERR_NON_FINITE] = "non-finite number",
    [XYL_ERR_INVALID_SKELETON] = "invalid skeleton",
    [XYL_ERR_PARSE] = "parse error",
    [XYL_ERR_TRUNCATED] = "truncated input",
    [XYL_ERR_IO] = "input/output error",
    [XYL_ERR_NOT_FOUND] = "not found",
    [XYL_ERR_UNSUPPORTED] = "unsupported",
};

const char *xyl_result_string(xyl_result r)
{
    if ((unsigned)r >= (unsigned)XYL_RESULT_COUNT_ || !result_names[r]) return "unknown result";
    return result_names[r];
}

/* ---- allocation: xyl__alloc, xyl__calloc and xyl__free are in alloc.c ------------------- */

bool xyl__grow_slow(const xyl_allocator *a, void **ptr, size_t *cap, size_t used, size_t need,
                    size_t elem)
{
    if (need == 0) need = 1; /* an array is never NULL after a successful grow */
    if (need <= *cap && *ptr) return true;
    size_t ncap = *cap ? *cap : 16;
    while (ncap < need) {
        if (ncap > SIZE_MAX / 2) return false;
        ncap *= 2;
    }
    size_t bytes;
    if (!xyl__mul_ok(ncap, elem, &bytes)) return false;
    void *p = xyl__alloc(a, bytes);
    if (!p) return false;
    if (*ptr && used) memcpy(p, *ptr, used * elem);
    xyl__free(a, *ptr);
    *ptr = p;
    *cap = ncap;
    return true;
}

/* ---- sorting ------------------------------------------------------------------------------ */

typedef int (*cmp_fn)(const void *, const void *);

/* Elements are moved word by word where their size allows (the sorts' elements are 8 or 16
 * bytes). */
static void swap_elems(unsigned char *a, unsigned char *b, size_t size)
{
    size_t i = 0;
    for (; i + 8 <= size; i += 8) {
        uint64_t x, y;
        memcpy(&x, a + i, 8);
        memcpy(&y, b + i, 8);
        memcpy(a + i, &y, 8);
        memcpy(b + i, &x, 8);
    }
    for (; i < size; ++i) {
        unsigned char t = a[i];
        a[i] = b[i];
        b[i] = t;
    }
}

static void insertion_sort(unsigned char *b, size_t n, size_t size, cmp_fn cmp)
{
    for (size_t i = 1; i < n; ++i)
        for (size_t j = i; j > 0 && cmp(b + (j - 1) * size, b + j * size) > 0; --j)
            swap_elems(b + (j - 1) * size, b + j * size, size);
}

/* Moves the element at root down the max-heap of the first n elements. */
static void sift_down(unsigned char *b, size_t root, size_t n, size_t size, cmp_fn cmp)
{
    for (size_t child; (child = 2 * root + 1) < n; root = child) {
        if (child + 1 < n && cmp(b + child * size, b + (child + 1) * size) < 0) ++child;
        if (cmp(b + root * size, b + child * size) >= 0) return;
        swap_elems(b + root * size, b + child * size, size);
    }
}

static void heap_sort(unsigned char *b, size_t n, size_t size, cmp_fn cmp)
{
    for (size_t i = n / 2; i-- > 0;) sift_down(b, i, n, size, cmp);
    for (size_t end = n - 1; end > 0; --end) {
        swap_elems(b, b + end * size, size);
        sift_down(b, 0, end, size, cmp);
    }
}

/* Introsort: quicksort with the median of three as pivot, insertion sort for short runs, and
 * heapsort where the partitions stay unbalanced (depth), so O(n log n) always. */
static void intro_sort(unsigned char *b, size_t n, size_t size, cmp_fn cmp, unsigned depth)
{
    while (n > 12) {
        if (depth-- == 0) {
            heap_sort(b, n, size, cmp);
            return;
        }
        unsigned char *mid = b + n / 2 * size, *last = b + (n - 1) * size;
        if (cmp(mid, b) < 0) swap_elems(mid, b, size);
        if (cmp(last, mid) < 0) {
            swap_elems(last, mid, size);
            if (cmp(mid, b) < 0) swap_elems(mid, b, size);
        }
        swap_elems(b, mid, size); /* the pivot to the front; last (>= it) stops the scan up */
        size_t i = 0, j = n;
        for (;;) {
            do ++i;
            while (cmp(b + i * size, b) < 0);
            do --j;
            while (cmp(b + j * size, b) > 0);
            if (i >= j) break;
            swap_elems(b + i * size, b + j * size, size);
        }
        swap_elems(b, b + j * size, size); /* [0, j) <= pivot = [j] <= (j, n) */
        size_t right = n - j - 1;
        if (j < right) {
            intro_sort(b, j, size, cmp, depth);
            b += (j + 1) * size;
            n = right;
        } else {
            intro_sort(b + (j + 1) * size, right, size, cmp, depth);
            n = j;
        }
    }
    insertion_sort(b, n, size, cmp);
}

void xyl__sort(void *base, size_t n, size_t size, int (*cmp)(const void *, const void *))
{
    unsigned depth = 0;
    for (size_t m = n; m > 1; m >>= 1) depth += 2;
    intro_sort(base, n, size, cmp, depth);
}

/* ---- diagnostics --------------------------------------------------------------------------- */

xyl_result xyl__fail(xyl_diag *diag, xyl_result code, uint32_t line, uint32_t column,
                     int64_t index, const char *fmt, ...)
{
    if (!diag) return code;
    diag->code = code;
    diag->line = line;
    diag->column = column;
    diag->index = index;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(diag->message, sizeof diag->message, fmt, ap);
    va_end(ap);
    return code;
}

void xyl__diag_ok(xyl_diag *diag)
{
    if (!diag) return;
    diag->code = XYL_OK;
    diag->message[0] = '\0';
    diag->line = 0;
    diag->column = 0;
    diag->index = -1;
}

void xyl__warn(xyl_diag *diag, const char *fmt, ...)
{
    if (!diag) return;
    if (diag->warning_count++ != 0) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(diag->warning, sizeof diag->warning, fmt, ap);
    va_end(ap);
}

/* ---- vectors and frames -------------------------------------------------------------------- */

xyl__dvec3 xyl__d3_any_orthogonal(xyl__dvec3 n)
{
    /* Duff et al. 2017, "Building an orthonormal basis, revisited": exact for unit n. */
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    xyl__dvec3 t = xyl__d3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    return xyl__d3_normalize_or(t, xyl__d3(1, 0, 0));
}

xyl__dvec3 xyl__d3_rotate(xyl__dvec3 v, xyl__dvec3 axis, double angle)
{
    return xyl__d3_rotate_cs(v, axis, cos(angle), sin(angle));
}

xyl__dvec3 xyl__d3_rotate_cs(xyl__dvec3 v, xyl__dvec3 axis, double c, double s)
{
    xyl__dvec3 kxv = xyl__d3_cross(axis, v);
    double kdv = xyl__d3_dot(axis, v);
    return xyl__d3_add(xyl__d3_add(xyl__d3_scale(v, c), xyl__d3_scale(kxv, s)),
                       xyl__d3_scale(axis, kdv * (1.0 - c)));
}

void xyl__frame_orthonormalize(xyl__frame *f)
{
    f->h = xyl__d3_normalize_or(f->h, xyl__d3(0, 1, 0));
    xyl__dvec3 l = xyl__d3_sub(f->l, xyl__d3_scale(f->h, xyl__d3_dot(f->l, f->h)));
    /* the fallback only when l has no direction: computing it for every call was 15 % of
     * interpreting a 10^5-segment tree */
    if (!xyl__d3_normalize_ok(l, &f->l)) f->l = xyl__d3_any_orthogonal(f->h);
    f->u = xyl__d3_cross(f->h, f->l);
}

double xyl__frame_error(const xyl__frame *f)
{
    const xyl__dvec3 *v[3] = {&f->h, &f->l, &f->u};
    double worst = 0.0;
    for (int i = 0; i < 3; ++i) {
        for (int j = i; j < 3; ++j) {
            double e = fabs(xyl__d3_dot(*v[i], *v[j]) - (i == j ? 1.0 : 0.0));
            if (e > worst || isnan(e)) worst = isnan(e) ? INFINITY : e;
        }
    }
    return worst;
}

/* ---- files --------------------------------------------------------------------------------- */

/* Makes a rename durable: fsync the folder that holds path (best effort; the rename itself is
 * already atomic). path is modified. */
static void sync_parent(char *path)
{
    char *slash = strrchr(path, '/');
    const char *dir = ".";
    if (slash == path) dir = "/";
    else if (slash) {
        *slash = '\0';
        dir = path;
    }
    int fd = open(dir, O_RDONLY);
    if (fd < 0) return;
    (void)fsync(fd);
    close(fd);
}

xyl_result xyl__write_file_atomic(const char *path, const void *data, size_t size,
                                  const xyl_allocator *a, xyl_diag *diag)
{
    if (!path || !*path || (!data && size))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "no output path");
    size_t plen = strlen(path);
    char *tmp = plen < SIZE_MAX - 16 ? xyl__alloc(a, plen + 16) : NULL;
    if (!tmp) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    memcpy(tmp, path, plen);
    memcpy(tmp + plen, ".tmp-XXXXXX", 12);
    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        xyl__free(a, tmp);
        return xyl__fail(diag, XYL_ERR_IO, 0, 0, -1, "cannot create a file next to '%s': %s", path,
                         strerror(e));
    }
    const char *p = data;
    size_t left = size;
    while (left > 0) {
        ssize_t n = write(fd, p, left);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            int e = errno;
            close(fd);
            unlink(tmp);
            xyl__free(a, tmp);
            return xyl__fail(diag, XYL_ERR_IO, 0, 0, -1, "cannot write '%s': %s", path,
                             strerror(e));
        }
        p += n;
        left -= (size_t)n;
    }
    /* mkstemp makes 0600 files; give the output the usual permissions. */
    mode_t mask = umask(0);
    umask(mask);
    if (fchmod(fd, 0666 & ~mask) != 0 || fsync(fd) != 0 || close(fd) != 0) {
        int e = errno;
        unlink(tmp);
        xyl__free(a, tmp);
        return xyl__fail(diag, XYL_ERR_IO, 0, 0, -1, "cannot finish '%s': %s", path, strerror(e));
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        xyl__free(a, tmp);
        return xyl__fail(diag, XYL_ERR_IO, 0, 0, -1, "cannot rename onto '%s': %s", path,
                         strerror(e));
    }
    sync_parent(tmp);
    xyl__free(a, tmp);
    return XYL_OK;
}

xyl_result xyl__read_file(const char *path, size_t max_bytes, const xyl_allocator *a, char **out,
                          size_t *size, xyl_diag *diag)
{
    if (!path || !out || !size)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "no input path");
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return xyl__fail(diag, XYL_ERR_IO, 0, 0, -1, "cannot open '%s': %s", path,
                         strerror(errno));
    size_t cap = 0, used = 0;
    char *buf = NULL;
    xyl_result r = XYL_OK;
    for (;;) {
        if (!xyl__grow(a, (void **)&buf, &cap, used, used + 65536 + 1, 1)) {
            r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory reading '%s'",
                          path);
            break;
        }
        ssize_t n = read(fd, buf + used, cap - used - 1);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            r = xyl__fail(diag, XYL_ERR_IO, 0, 0, -1, "cannot read '%s': %s", path,
                          strerror(errno));
            break;
        }
        used += (size_t)n;
        if (used > max_bytes) {
            r = xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                          "'%s' is larger than the limit of %zu bytes", path, max_bytes);
            break;
        }
        if (n == 0) break;
    }
    close(fd);
    if (r != XYL_OK) {
        xyl__free(a, buf);
        return r;
    }
    buf[used] = '\0';
    *out = buf;
    *size = used;
    return XYL_OK;
}
