/* Helpers for the tessellate/ suites. */
#ifndef XYL_TESS_UTIL_H
#define XYL_TESS_UTIL_H

#include "test_util.h"

#include <xylem/xyl_tessellate.h>

/* An empty batches object; fails the test if there is no memory for one. */
static inline xyl_tess_batches *tu_batches_create(void)
{
    xyl_tess_batches *b = NULL;
    xyl_diag d = {0};
    if (xyl_tess_batches_create(NULL, &b, &d) != XYL_OK) fail_msg("batches: %s", d.message);
    return b;
}

/* A copy of batches in arrays of the test's own, as a caller that culls or edits the records
 * would make one: the tests change it to see what the backends accept. */
typedef struct tu_batches {
    xyl_tess_batches view; /* points at the arrays below */
    xyl_tess_instance *instances;
    xyl_tess_draw_cmd *cmds;
    xyl_tess_batch *batches;
} tu_batches;

static inline void tu_batches_copy(const xyl_tess_batches *b, tu_batches *out)
{
    size_t ni = b->instance_count ? b->instance_count : 1, nc = b->cmd_count ? b->cmd_count : 1;
    out->instances = malloc(ni * sizeof *out->instances);
    out->cmds = malloc(nc * sizeof *out->cmds);
    out->batches = malloc(nc * sizeof *out->batches);
    assert_true(out->instances && out->cmds && out->batches);
    if (b->instance_count)
        memcpy(out->instances, b->instances, b->instance_count * sizeof *out->instances);
    if (b->cmd_count) {
        memcpy(out->cmds, b->cmds, b->cmd_count * sizeof *out->cmds);
        memcpy(out->batches, b->batches, b->cmd_count * sizeof *out->batches);
    }
    out->view = *b;
    out->view.instances = out->instances;
    out->view.cmds = out->cmds;
    out->view.batches = out->batches;
}

static inline void tu_batches_free(tu_batches *t)
{
    free(t->instances);
    free(t->cmds);
    free(t->batches);
    memset(t, 0, sizeof *t);
}

/* An allocator that counts its live blocks and can be told to refuse. */
typedef struct tu_counting_alloc {
    size_t live, calls;
    bool refuse;
} tu_counting_alloc;

static inline void *tu_counted_alloc(size_t size, void *user)
{
    tu_counting_alloc *c = user;
    if (c->refuse) return NULL;
    void *p = malloc(size);
    if (p) ++c->live, ++c->calls;
    return p;
}

static inline void tu_counted_free(void *p, void *user)
{
    tu_counting_alloc *c = user;
    if (p) --c->live;
    free(p);
}

static inline xyl_allocator tu_counting_allocator(tu_counting_alloc *c)
{
    xyl_allocator a = {tu_counted_alloc, tu_counted_free, c};
    return a;
}

#endif /* XYL_TESS_UTIL_H */
