/* The tuning viewer's worker thread: regrows the tree from a view_params, running only the stages
 * below the first one whose inputs changed (a new level regrows nothing, a new ring count runs
 * the mesher and the patches, not the grammar). A failed regeneration publishes nothing: the last
 * good tree stays, and the message says what failed.
 *
 * Sharing: a published view_tree's objects are read by the main thread while the worker reads
 * the same (immutable) objects to grow the next tree. The worker never destroys an object it
 * published: one it replaces is retired, and view_regrow_adopt destroys the retired ones once the
 * main thread has switched to a tree that no longer holds them. */
#ifndef XYL_SAMPLES_VIEW_REGROW_H
#define XYL_SAMPLES_VIEW_REGROW_H

#include <xylem/xyl_foliage.h>
#include <xylem/xyl_lsystem.h>
#include <xylem/xyl_stems.h>
#include <xylem/xyl_tessellate.h>

#include "view_params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Derived strings stop here (the library's default is 1 << 27): a depth slider pulled too far
 * fails in a second or two with XYL_ERR_LIMIT_EXCEEDED instead of filling the memory. */
#define VIEW_MAX_MODULES (UINT64_C(1) << 23)

typedef enum view_stage {
    VIEW_STAGE_GRAMMAR,  /* tuned text -> xyl_grammar */
    VIEW_STAGE_DERIVE,   /* depth, seed -> module string */
    VIEW_STAGE_TURTLE,   /* radii, angles -> skeleton */
    VIEW_STAGE_STEMS,    /* ring sides, subdivision, normals, joints -> stem mesh */
    VIEW_STAGE_PATCHES,  /* handle rule -> PN patch records */
    VIEW_STAGE_FOLIAGE,  /* leaves and their LODs (from the skeleton) */
    VIEW_STAGE_COUNT
} view_stage;

extern const char *const view_stage_names[VIEW_STAGE_COUNT];

/* One good tree, immutable. */
typedef struct view_tree {
    uint64_t generation;         /* the request it answers */
    char *text;                  /* the grammar with the tuned values (no #depth / #seed) */
    char *lsys;                  /* the same with #depth and #seed: the .lsys export */
    xyl_grammar *grammar;
    xyl_lstring *string;
    xyl_skeleton *skeleton;
    xyl_mesh *mesh;
    xyl_tess_patches *patches;
    xyl_foliage *foliage;        /* NULL with leaves off */
    xyl_stems_stats stems_stats;
    uint32_t depth;              /* used */
    uint64_t seed;
    double ms[VIEW_STAGE_COUNT]; /* the time of each stage when it last ran */
    bool ran[VIEW_STAGE_COUNT];  /* whether it ran for this tree (false: kept from before) */
} view_tree;

typedef struct view_regrow_status {
    bool busy;
    view_stage stage;            /* running now, when busy */
    double busy_ms;              /* since the running request started */
    uint64_t submitted, done;    /* requests: the last one submitted, the last one finished */
    bool failed;                 /* the last finished request failed */
    view_stage failed_stage;
    xyl_result error;
    xyl_diag diag;               /* its message, line and column */
} view_regrow_status;

typedef struct view_regrow view_regrow;

/* Starts the worker; NULL when out of memory or no thread can be had (message in err). */
view_regrow *view_regrow_start(char *err, size_t cap);
/* Asks for the tree of p (copied); a request still waiting is replaced. Returns its generation,
 * or 0 when out of memory. */
uint64_t view_regrow_submit(view_regrow *w, const view_params *p);
void view_regrow_status_get(view_regrow *w, view_regrow_status *out);
/* Waits until every submitted request has finished. */
void view_regrow_wait(view_regrow *w);
/* The newest published tree if it is newer than *current (then *current is replaced, the old
 * struct freed and the retired objects destroyed): returns true when it changed. Main thread. */
bool view_regrow_adopt(view_regrow *w, view_tree **current);
/* Stops the worker and destroys everything it holds, *current's objects included. */
void view_regrow_stop(view_regrow *w, view_tree **current);

#ifdef __cplusplus
}
#endif

#endif
