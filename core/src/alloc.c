/* The library's allocation entry points: the caller's xyl_allocator, or the default one.
 *
 * The default allocator is malloc/free for small blocks. Blocks from XYL__LARGE_BLOCK (16 KiB)
 * on get their own mapping: whole 4 KiB pages, and from 1 MiB on whole 2 MiB pages, aligned and
 * marked for transparent huge pages. Fresh memory was the largest single cost of meshing big
 * trees: its first touch faults once per 4 KiB page, a huge page once per 2 MiB, and glibc gave
 * big blocks back after every build (docs/memory.md). The mappings come from mmap, not from
 * malloc's heap: 2 MiB-aligned blocks inside the heap fragment it (measured: posix_memalign
 * plus madvise made 4-32 MiB arrays slower).
 *
 * Freed mapped blocks are kept in a small cache (XYL__CACHE_SLOTS blocks, XYL__CACHE_BYTES in
 * all) and handed out again to a request of about their size: building the same tree again (a
 * viewer tuning parameters, a benchmark) then writes memory that is already mapped and possibly
 * still in cache. xyl_memory_trim returns the cache to the system.
 *
 * Every default block starts with a header that says which of the two it is. Sanitizer builds
 * keep malloc for every block, so each has redzones and leak checks. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS, madvise */

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "xyl_internal.h"

#if defined(XYL__LARGE_BLOCKS)
#include <pthread.h>
#include <stdatomic.h>
#include <sys/mman.h>
#endif

/* A custom allocator needs both hooks; one with only one hook counts as zero-filled (malloc and
 * free), so a missing free can never leak. */
static bool custom(const xyl_allocator *a)
{
    return a && a->alloc && a->free;
}

typedef union block_head {
    size_t mapped; /* length of the block's own mapping; 0: from malloc */
    max_align_t align;
} block_head;

#if defined(XYL__LARGE_BLOCKS)

#define HUGE_PAGE ((size_t)2 << 20)
#define SMALL_PAGE ((size_t)4096) /* or a multiple of the page size: mmap rounds up */

/* Freed mappings, oldest first. */
static struct {
    block_head *block[XYL__CACHE_SLOTS];
    size_t count, bytes;
} cache;
static pthread_mutex_t cache_lock = PTHREAD_MUTEX_INITIALIZER;
static atomic_size_t blocks_in_use; /* mapped blocks handed out and not freed: for the tests */

/* A zero-filled mapping of len bytes (a multiple of SMALL_PAGE), or NULL. From one huge page
 * on it is HUGE_PAGE-aligned and marked for huge pages. */
static block_head *map_large(size_t len)
{
    bool huge = len >= HUGE_PAGE;
    size_t span = huge ? len + HUGE_PAGE : len;
    char *p = mmap(NULL, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) return NULL;
    char *start = p;
    if (huge) {
        start = (char *)(((uintptr_t)p + HUGE_PAGE - 1) & ~(uintptr_t)(HUGE_PAGE - 1));
        size_t head = (size_t)(start - p), tail = span - head - len;
        if (head) munmap(p, head);
        if (tail) munmap(start + len, tail);
#if defined(MADV_HUGEPAGE)
        (void)madvise(start, len, MADV_HUGEPAGE); /* a hint: without it the pages are small */
#endif
    }
    block_head *h = (block_head *)(void *)start;
    h->mapped = len;
    return h;
}

/* The smallest cached block of len to 2 len bytes, taken out of the cache; or NULL. */
static block_head *cache_take(size_t len)
{
    block_head *h = NULL;
    pthread_mutex_lock(&cache_lock);
    size_t best = cache.count;
    for (size_t i = 0; i < cache.count; ++i) {
        size_t l = cache.block[i]->mapped;
        if (l >= len && l / 2 <= len && (best == cache.count || l < cache.block[best]->mapped))
            best = i;
    }
    if (best < cache.count) {
        h = cache.block[best];
        cache.bytes -= h->mapped;
        memmove(cache.block + best, cache.block + best + 1,
                (cache.count - best - 1) * sizeof cache.block[0]);
        --cache.count;
    }
    pthread_mutex_unlock(&cache_lock);
    return h;
}

/* Keeps h for reuse, evicting the oldest blocks to make room; unmaps whatever does not fit. */
static void cache_put(block_head *h)
{
    block_head *evicted[XYL__CACHE_SLOTS + 1];
    size_t n = 0;
    if (h->mapped > XYL__CACHE_BYTES) {
        evicted[n++] = h;
    } else {
        pthread_mutex_lock(&cache_lock);
        size_t drop = 0;
        while (drop < cache.count && (cache.count - drop == XYL__CACHE_SLOTS ||
                                      cache.bytes + h->mapped > XYL__CACHE_BYTES)) {
            cache.bytes -= cache.block[drop]->mapped;
            evicted[n++] = cache.block[drop++];
        }
        memmove(cache.block, cache.block + drop, (cache.count - drop) * sizeof cache.block[0]);
        cache.count -= drop;
        cache.block[cache.count++] = h;
        cache.bytes += h->mapped;
        pthread_mutex_unlock(&cache_lock);
    }
    for (size_t i = 0; i < n; ++i) munmap(evicted[i], evicted[i]->mapped);
}

#endif /* XYL__LARGE_BLOCKS */

size_t xyl__alloc_blocks_in_use(void)
{
#if defined(XYL__LARGE_BLOCKS)
    return atomic_load(&blocks_in_use);
#else
    return 0;
#endif
}

size_t xyl_memory_trim(void)
{
    size_t released = 0;
#if defined(XYL__LARGE_BLOCKS)
    block_head *all[XYL__CACHE_SLOTS];
    pthread_mutex_lock(&cache_lock);
    size_t n = cache.count;
    memcpy(all, cache.block, n * sizeof all[0]);
    released = cache.bytes;
    cache.count = 0;
    cache.bytes = 0;
    pthread_mutex_unlock(&cache_lock);
    for (size_t i = 0; i < n; ++i) munmap(all[i], all[i]->mapped);
#endif
    return released;
}

/* *zeroed tells whether the block is known to be zero-filled. */
static void *alloc_default(size_t size, bool *zeroed)
{
    *zeroed = false;
    if (size > SIZE_MAX / 2) return NULL; /* also keeps the rounding below from overflowing */
    size_t bytes = size + sizeof(block_head);
    block_head *h = NULL;
#if defined(XYL__LARGE_BLOCKS)
    if (bytes >= XYL__LARGE_BLOCK) {
        /* whole huge pages from half a huge page on; below, small pages (a huge page is
         * zeroed whole on first touch) */
        size_t page = bytes >= HUGE_PAGE / 2 ? HUGE_PAGE : SMALL_PAGE;
        size_t len = (bytes + page - 1) & ~(page - 1);
        if (!(h = cache_take(len)) && (h = map_large(len))) *zeroed = true;
        if (h) {
            atomic_fetch_add(&blocks_in_use, 1);
            return h + 1;
        }
        /* no mapping (address space or map-count limits): malloc may still have room */
    }
#endif
    if (!(h = malloc(bytes))) return NULL;
    h->mapped = 0;
    return h + 1;
}

void *xyl__alloc(const xyl_allocator *a, size_t size)
{
    if (size == 0) size = 1;
    if (custom(a)) return a->alloc(size, a->user);
    bool zeroed;
    return alloc_default(size, &zeroed);
}

void *xyl__calloc(const xyl_allocator *a, size_t count, size_t size)
{
    size_t bytes;
    if (!xyl__mul_ok(count, size, &bytes)) return NULL;
    if (bytes == 0) bytes = 1;
    bool zeroed = false;
    void *p = custom(a) ? a->alloc(bytes, a->user) : alloc_default(bytes, &zeroed);
    if (p && !zeroed) memset(p, 0, bytes);
    return p;
}

void xyl__free(const xyl_allocator *a, void *p)
{
    if (!p) return;
    if (custom(a)) {
        a->free(p, a->user);
        return;
    }
    block_head *h = (block_head *)p - 1;
#if defined(XYL__LARGE_BLOCKS)
    if (h->mapped) {
        atomic_fetch_sub(&blocks_in_use, 1);
        cache_put(h);
        return;
    }
#endif
    free(h);
}

/* ---- aligned blocks (xyl__alloc_aligned) -------------------------------------------------- */

typedef struct aligned_head {
    void *base;
    size_t size;
} aligned_head;

void *xyl__alloc_aligned(const xyl_allocator *a, size_t size, size_t align)
{
    const size_t min_align = _Alignof(max_align_t);
    if (align < min_align) align = min_align; /* also aligns the head below the block */
    if (size > SIZE_MAX - align - sizeof(aligned_head)) return NULL;
    char *base = xyl__alloc(a, size + align + sizeof(aligned_head));
    if (!base) return NULL;
    uintptr_t at = ((uintptr_t)(base + sizeof(aligned_head)) + align - 1) & ~(uintptr_t)(align - 1);
    aligned_head *h = (aligned_head *)at - 1;
    h->base = base;
    h->size = size;
    return (void *)at;
}

void xyl__free_aligned(const xyl_allocator *a, void *p)
{
    if (p) xyl__free(a, ((aligned_head *)p - 1)->base);
}

void *xyl__realloc_aligned(const xyl_allocator *a, void *old, size_t size, size_t align)
{
    if (!old) return xyl__alloc_aligned(a, size, align);
    if (size == 0) {
        xyl__free_aligned(a, old);
        return NULL;
    }
    void *p = xyl__alloc_aligned(a, size, align);
    if (!p) return NULL;
    size_t keep = ((aligned_head *)old - 1)->size;
    memcpy(p, old, keep < size ? keep : size);
    xyl__free_aligned(a, old);
    return p;
}
