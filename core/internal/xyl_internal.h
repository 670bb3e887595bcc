/* Library-internal helpers shared by all modules: allocation, diagnostics, double-precision
 * vector math with safe normalisation, and the named epsilons. Not installed. */
#ifndef XYL_INTERNAL_H
#define XYL_INTERNAL_H

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "xylem/xyl_core.h"

/* Scale-relative tolerances, in one place. */
#define XYL__EPS_REL 1e-12       /* relative tolerance on double lengths */
#define XYL__EPS_NORMALIZE 1e-300 /* below this squared length a vector has no direction */
#define XYL__EPS_COLLINEAR 1e-9  /* 1 - cos(angle) under which two directions count as equal */

#define XYL__PI 3.14159265358979323846

/* For helpers written once for a run-time count and inlined where the count is a constant. */
#if defined(__GNUC__)
#define XYL__ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define XYL__ALWAYS_INLINE inline
#endif

/* ---- allocation ---------------------------------------------------------------------------- */

/* The default allocator (alloc.c) maps blocks of XYL__LARGE_BLOCK bytes and more (its header
 * included) on their own, with transparent huge pages, and caches up to XYL__CACHE_SLOTS freed
 * ones, XYL__CACHE_BYTES together; on Linux, outside sanitizer builds (XYL__LARGE_BLOCKS). */
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer)
#define XYL__SANITIZED 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define XYL__SANITIZED 1
#endif
#if defined(__linux__) && !defined(XYL__SANITIZED)
#define XYL__LARGE_BLOCKS 1
#endif
#define XYL__LARGE_BLOCK ((size_t)16 << 10)
#define XYL__CACHE_SLOTS 64
#define XYL__CACHE_BYTES ((size_t)128 << 20)

/* Mapped blocks handed out and not yet freed (0 without XYL__LARGE_BLOCKS): a leak check for
 * the blocks the sanitizers do not see. */
size_t xyl__alloc_blocks_in_use(void);
void *xyl__alloc(const xyl_allocator *a, size_t size);
void *xyl__calloc(const xyl_allocator *a, size_t count, size_t size); /* overflow-checked, zeroed */
void xyl__free(const xyl_allocator *a, void *p);
/* Blocks with an alignment (a power of two; below max_align_t's it is raised to it) and a
 * realloc, on top of an allocator that has neither: what Vulkan's allocation callbacks ask of
 * the caller's xyl_allocator. A block is over-allocated and keeps its base pointer and size just
 * below the pointer returned. xyl__realloc_aligned(a, NULL, ...) allocates; size 0 frees and
 * returns NULL; on failure NULL and the old block stays valid. */
void *xyl__alloc_aligned(const xyl_allocator *a, size_t size, size_t align);
void *xyl__realloc_aligned(const xyl_allocator *a, void *old, size_t size, size_t align);
void xyl__free_aligned(const xyl_allocator *a, void *p);
/* Grows *ptr (of *cap elements of elem bytes, *used of which are live) to hold at least need
 * elements; doubling. Returns false on overflow or allocation failure (then *ptr unchanged).
 * The usual case, room left, is decided inline; xyl__grow_slow does the rest. */
bool xyl__grow_slow(const xyl_allocator *a, void **ptr, size_t *cap, size_t used, size_t need,
                    size_t elem);
static inline bool xyl__grow(const xyl_allocator *a, void **ptr, size_t *cap, size_t used,
                             size_t need, size_t elem)
{
    if (need - 1 < *cap && *ptr) return true; /* need 0 wraps round: the slow path's case */
    return xyl__grow_slow(a, ptr, cap, used, need, elem);
}
/* a * b without overflow, false if it would overflow. */
static inline bool xyl__mul_ok(size_t a, size_t b, size_t *out)
{
    if (b != 0 && a > SIZE_MAX / b) return false;
    *out = a * b;
    return true;
}
/* count elements of size bytes (at least one), overflow-checked and NOT zeroed: for arrays the
 * caller fills completely, where calloc's zeroing would be a wasted pass over fresh pages. */
static inline void *xyl__alloc_array(const xyl_allocator *a, size_t count, size_t size)
{
    size_t bytes;
    if (!xyl__mul_ok(count ? count : 1, size, &bytes)) return NULL;
    return xyl__alloc(a, bytes);
}

/* Sorts n elements of size bytes in place by cmp, as qsort does but without allocating (the C
 * library's qsort may take a buffer from malloc, past the caller's allocator). An introsort,
 * O(n log n) and not stable: cmp must order every two elements that are not interchangeable. */
void xyl__sort(void *base, size_t n, size_t size, int (*cmp)(const void *, const void *));

/* ---- diagnostics --------------------------------------------------------------------------- */

/* Fills diag (if not NULL) and returns code. line/column 0 and index -1 mean "none". */
xyl_result xyl__fail(xyl_diag *diag, xyl_result code, uint32_t line, uint32_t column,
                     int64_t index, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;
/* Sets diag to success (code XYL_OK, empty message) without touching warnings. */
void xyl__diag_ok(xyl_diag *diag);
/* Counts a warning; keeps the text of the first one. */
void xyl__warn(xyl_diag *diag, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* ---- screen-space budgets ------------------------------------------------------------------ */

/* The world size of one pixel per unit of distance from the eye, for a vertical field of view
 * (radians; <= 0: 0.8) over viewport_height pixels (0: 1080): 2 tan(fovy / 2) / height. The one
 * pixel -> world formula: the tessellation's levels (its pixels per world unit at distance 1 is
 * the inverse), the foliage's LOD pick and xyl_tess_view_world_error all use it. */
static inline double xyl__world_per_px(float fovy, uint32_t viewport_height)
{
    double f = fovy > 0.0f ? fovy : 0.8;
    double h = viewport_height ? viewport_height : 1080;
    return 2.0 * tan(0.5 * f) / h;
}

/* ---- double vectors ------------------------------------------------------------------------ */

typedef struct xyl__dvec3 {
    double x, y, z;
} xyl__dvec3;

static inline xyl__dvec3 xyl__d3(double x, double y, double z)
{
    xyl__dvec3 r = {x, y, z};
    return r;
}
static inline xyl__dvec3 xyl__d3_add(xyl__dvec3 a, xyl__dvec3 b)
{
    return xyl__d3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline xyl__dvec3 xyl__d3_sub(xyl__dvec3 a, xyl__dvec3 b)
{
    return xyl__d3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline xyl__dvec3 xyl__d3_scale(xyl__dvec3 a, double s)
{
    return xyl__d3(a.x * s, a.y * s, a.z * s);
}
static inline double xyl__d3_dot(xyl__dvec3 a, xyl__dvec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline xyl__dvec3 xyl__d3_cross(xyl__dvec3 a, xyl__dvec3 b)
{
    return xyl__d3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double xyl__d3_len(xyl__dvec3 a)
{
    return sqrt(xyl__d3_dot(a, a));
}
static inline bool xyl__d3_finite(xyl__dvec3 a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}
/* Unit vector along a; returns fallback (assumed unit) when a has no direction or is not
 * finite, so the result is never NaN. */
static inline xyl__dvec3 xyl__d3_normalize_or(xyl__dvec3 a, xyl__dvec3 fallback)
{
    double l2 = xyl__d3_dot(a, a);
    if (!(l2 > XYL__EPS_NORMALIZE) || !isfinite(l2)) return fallback;
    return xyl__d3_scale(a, 1.0 / sqrt(l2));
}
/* The unit vector along a into *out, as xyl__d3_normalize_or computes it; false (and *out
 * untouched) when a has no direction, so a costly fallback need only be computed then. */
static inline bool xyl__d3_normalize_ok(xyl__dvec3 a, xyl__dvec3 *out)
{
    double l2 = xyl__d3_dot(a, a);
    if (!(l2 > XYL__EPS_NORMALIZE) || !isfinite(l2)) return false;
    *out = xyl__d3_scale(a, 1.0 / sqrt(l2));
    return true;
}
/* Some unit vector orthogonal to unit n, chosen deterministically (Frisvad-style branchless
 * basis, robust near n = -z). */
xyl__dvec3 xyl__d3_any_orthogonal(xyl__dvec3 n);
/* Rotates v about unit axis by angle (Rodrigues). */
xyl__dvec3 xyl__d3_rotate(xyl__dvec3 v, xyl__dvec3 axis, double angle);
/* The same with the angle's cosine c and sine s given (to turn several vectors by one angle). */
xyl__dvec3 xyl__d3_rotate_cs(xyl__dvec3 v, xyl__dvec3 axis, double c, double s);

/* A right-handed orthonormal frame: heading, left, up = heading x left. */
typedef struct xyl__frame {
    xyl__dvec3 h, l, u;
} xyl__frame;

/* Re-orthonormalises a frame in place (Gram-Schmidt from h, then l; u = h x l). */
void xyl__frame_orthonormalize(xyl__frame *f);
/* Largest |dot - kronecker| over the frame's 6 pairs: 0 for a perfect frame. */
double xyl__frame_error(const xyl__frame *f);

static inline xyl_vec3 xyl__to_f3(xyl__dvec3 a)
{
    xyl_vec3 r = {(float)a.x, (float)a.y, (float)a.z};
    return r;
}
static inline xyl__dvec3 xyl__from_f3(xyl_vec3 a)
{
    return xyl__d3(a.x, a.y, a.z);
}

/* ---- files --------------------------------------------------------------------------------- */

/* Writes size bytes to path through a temporary file in the same folder and a rename, so path is
 * either the old file or the complete new one. The temporary name comes from a. */
xyl_result xyl__write_file_atomic(const char *path, const void *data, size_t size,
                                  const xyl_allocator *a, xyl_diag *diag);
/* Reads a whole file (at most max_bytes) into a NUL-terminated buffer from a; through read(2),
 * not stdio, whose buffers would come from malloc. */
xyl_result xyl__read_file(const char *path, size_t max_bytes, const xyl_allocator *a, char **out,
                          size_t *size, xyl_diag *diag);

#endif /* XYL_INTERNAL_H */
