/* Refinement patterns: for each level, the (i, j) lattice of a quad and of a triangle with
 * counter-clockwise index lists, all in one vertex array and one index array so a draw picks a
 * level by offsets alone. */
#include <string.h>

#include "tess_internal.h"
#include "xyl_internal.h"

static uint32_t pack(uint32_t i, uint32_t j, uint32_t local)
{
    return i | j << XYL_TESS_PATTERN_SHIFT_J | local << XYL_TESS_PATTERN_SHIFT_LOCAL;
}

static void quad_pattern(uint32_t l, uint32_t *v, uint32_t *idx)
{
    uint32_t local = 0;
    for (uint32_t j = 0; j <= l; ++j)
        for (uint32_t i = 0; i <= l; ++i, ++local) *v++ = pack(i, j, local);
    for (uint32_t j = 0; j < l; ++j)
        for (uint32_t i = 0; i < l; ++i) {
            uint32_t a = j * (l + 1) + i, b = a + 1, c = a + l + 2, d = a + l + 1;
            *idx++ = a; *idx++ = b; *idx++ = c;
            *idx++ = a; *idx++ = c; *idx++ = d;
        }
}

/* Row j holds l + 1 - j points; row_start(j) = j (l + 1) - j (j - 1) / 2. */
static uint32_t tri_at(uint32_t l, uint32_t i, uint32_t j)
{
    return j * (l + 1) - j * (j - 1) / 2 + i;
}

static void tri_pattern(uint32_t l, uint32_t *v, uint32_t *idx)
{
    uint32_t local = 0;
    for (uint32_t j = 0; j <= l; ++j)
        for (uint32_t i = 0; i + j <= l; ++i, ++local) *v++ = pack(i, j, local);
    for (uint32_t j = 0; j < l; ++j)
        for (uint32_t i = 0; i + j < l; ++i) {
            *idx++ = tri_at(l, i, j); *idx++ = tri_at(l, i + 1, j); *idx++ = tri_at(l, i, j + 1);
            if (i + j + 1 < l) {
                *idx++ = tri_at(l, i + 1, j);
                *idx++ = tri_at(l, i + 1, j + 1);
                *idx++ = tri_at(l, i, j + 1);
            }
        }
}

typedef struct patterns_impl {
    xyl_tess_patterns pub;
    xyl_allocator alloc;
} patterns_impl;

xyl_result xyl_tess_patterns_create(uint32_t max_level, const xyl_allocator *alloc,
                                    xyl_tess_patterns **out, xyl_diag *diag)
{
    if (!out) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out is required");
    if (max_level == 0) max_level = XYL_TESS_MAX_LEVEL;
    if (max_level > XYL_TESS_MAX_LEVEL)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "max level %u is above %d", max_level, XYL_TESS_MAX_LEVEL);
    xyl_allocator a = alloc ? *alloc : (xyl_allocator){0};
    patterns_impl *t = xyl__calloc(&a, 1, sizeof *t);
    if (!t) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    t->alloc = a;
    uint32_t nv = 0, ni = 0;
    for (uint32_t l = 1; l <= max_level; ++l) {
        xyl_tess_pattern_range *q = &t->pub.ranges[0][l], *tr = &t->pub.ranges[1][l];
        q->first_vertex = nv; q->vertex_count = (l + 1) * (l + 1);
        q->first_index = ni; q->index_count = 6 * l * l;
        nv += q->vertex_count; ni += q->index_count;
        tr->first_vertex = nv; tr->vertex_count = (l + 1) * (l + 2) / 2;
        tr->first_index = ni; tr->index_count = 3 * l * l;
        nv += tr->vertex_count; ni += tr->index_count;
    }
    uint32_t *v = xyl__calloc(&a, nv, sizeof(uint32_t));
    uint32_t *idx = xyl__calloc(&a, ni, sizeof(uint32_t));
    if (!v || !idx) {
        xyl__free(&a, v);
        xyl__free(&a, idx);
        xyl__free(&a, t);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for patterns");
    }
    for (uint32_t l = 1; l <= max_level; ++l) {
        const xyl_tess_pattern_range *q = &t->pub.ranges[0][l], *tr = &t->pub.ranges[1][l];
        quad_pattern(l, v + q->first_vertex, idx + q->first_index);
        tri_pattern(l, v + tr->first_vertex, idx + tr->first_index);
    }
    t->pub.vertices = v;
    t->pub.vertex_count = nv;
    t->pub.indices = idx;
    t->pub.index_count = ni;
    t->pub.max_level = max_level;
    xyl__diag_ok(diag);
    *out = &t->pub;
    return XYL_OK;
}

void xyl_tess_patterns_destroy(xyl_tess_patterns *patterns)
{
    if (!patterns) return;
    patterns_impl *t = (patterns_impl *)patterns;
    xyl_allocator a = t->alloc;
    xyl__free(&a, (void *)t->pub.vertices);
    xyl__free(&a, (void *)t->pub.indices);
    xyl__free(&a, t);
}
