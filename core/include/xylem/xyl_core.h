/* xyl_core.h: the types every xylem module shares.
 *
 * How to use
 *   - Every fallible call returns an xyl_result; XYL_OK is 0. xyl_result_string() names a code.
 *   - Pass an optional xyl_diag* to get details (message, line/column, offending index) of the
 *     last failure of that call, and warnings it raised. There is no global error state.
 *   - Pass an xyl_allocator in a desc (or as the `alloc` argument of a call without one, NULL
 *     for the default) to route all allocations of that call; a zero-filled allocator means
 *     the default allocator (docs/memory.md).
 *   - Angles in the C API are radians.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_CORE_H
#define XYL_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32) && defined(XYL_SHARED)
#  ifdef XYL_BUILDING
#    define XYL_API __declspec(dllexport)
#  else
#    define XYL_API __declspec(dllimport)
#  endif
#elif defined(__GNUC__)
#  define XYL_API __attribute__((visibility("default")))
#else
#  define XYL_API
#endif

#define XYL_VERSION_MAJOR 0
#define XYL_VERSION_MINOR 1
#define XYL_VERSION_PATCH 0

/* Result codes. The order is part of the ABI; new codes are appended. */
typedef enum xyl_result {
    XYL_OK = 0,
    XYL_ERR_INVALID_ARGUMENT,  /* a NULL where an object is needed, an option out of range */
    XYL_ERR_OUT_OF_MEMORY,     /* the allocator returned NULL or a size overflowed */
    XYL_ERR_INVALID_GRAMMAR,   /* grammar text does not parse or is inconsistent (line/column in diag) */
    XYL_ERR_LIMIT_EXCEEDED,    /* an explicit limit (depth, modules, bytes, nesting, ...) was reached */
    XYL_ERR_NON_FINITE,        /* a NaN or infinity in input or produced by an expression */
    XYL_ERR_INVALID_SKELETON,  /* a skeleton breaks its invariants (parent order, radius > 0, ...) */
    XYL_ERR_PARSE,             /* a file (e.g. .skel) is malformed (line/column in diag) */
    XYL_ERR_TRUNCATED,         /* a file ends before the data it announced */
    XYL_ERR_IO,                /* the operating system refused a read or write */
    XYL_ERR_NOT_FOUND,         /* a named thing (preset, ...) does not exist */
    XYL_ERR_UNSUPPORTED,       /* valid request that this build cannot do */
    XYL_RESULT_COUNT_
} xyl_result;

/* A short, stable, human-readable name of a result ("invalid grammar"). Never NULL. */
XYL_API const char *xyl_result_string(xyl_result r);

#define XYL_DIAG_MESSAGE_SIZE 256

/* Caller-owned details of a call. Zero-fill before use (or reuse: each call overwrites
 * code/message/line/column/index, and adds to the warning fields). */
typedef struct xyl_diag {
    xyl_result code;                        /* the code the call returned */
    char message[XYL_DIAG_MESSAGE_SIZE];    /* one line a person understands; "" on success */
    uint32_t line;                          /* 1-based line in the input text, 0 if none */
    uint32_t column;                        /* 1-based column (bytes), 0 if none */
    int64_t index;                          /* offending element (node, module, ...), -1 if none */
    uint32_t warning_count;                 /* warnings raised (e.g. clamped fork angles) */
    char warning[XYL_DIAG_MESSAGE_SIZE];    /* the first warning's text */
} xyl_diag;

/* Allocation hooks. Zero-filled means the default allocator; so does a struct with only one of
 * the two hooks set. The default is malloc/free for small blocks; on Linux, blocks of 16 KiB
 * and more get their own mapping (transparent huge pages from 1 MiB on), and up to 128 MiB of
 * freed ones are kept for the next call that needs about as much (docs/memory.md). */
typedef struct xyl_allocator {
    void *(*alloc)(size_t size, void *user);
    void (*free)(void *ptr, void *user);
    void *user;
} xyl_allocator;

/* Returns the default allocator's cache of freed big blocks to the system; the bytes released.
 * Thread-safe; never needed for correctness. */
XYL_API size_t xyl_memory_trim(void);

typedef struct xyl_vec3 {
    float x, y, z;
} xyl_vec3;

#ifdef __cplusplus
}
#endif

#endif /* XYL_CORE_H */
