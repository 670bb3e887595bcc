/* The regeneration worker (view_regrow.h). */
#define _POSIX_C_SOURCE 200809L

#include "view_regrow.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

const char *const view_stage_names[VIEW_STAGE_COUNT] = {"grammar", "derive", "turtle", "stems",
                                                        "patches", "foliage"};

typedef enum object_kind { OBJ_TEXT, OBJ_GRAMMAR, OBJ_STRING, OBJ_SKELETON, OBJ_MESH, OBJ_PATCHES,
                           OBJ_FOLIAGE } object_kind;

typedef struct retired {
    object_kind kind;
    void *ptr;
} retired;

struct view_regrow {
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t work, finished;
    bool quit;
    /* under mu */
    view_params pending;
    bool has_pending;
    uint64_t submitted, done;
    bool busy;
    view_stage stage;
    double started;
    view_regrow_status last;  /* failed, error, diag of the last finished request */
    view_tree *published;     /* newest good tree not yet adopted (owned struct) */
    retired *graveyard;
    size_t graveyard_count, graveyard_cap;
    /* the worker's own */
    view_tree cache;          /* the last good tree: its objects are shared with the main thread */
    view_params built;        /* the parameters of cache */
    bool has_built;
};

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void destroy_object(object_kind kind, void *p)
{
    switch (kind) {
    case OBJ_TEXT: free(p); break;
    case OBJ_GRAMMAR: xyl_grammar_destroy(p); break;
    case OBJ_STRING: xyl_lstring_destroy(p); break;
    case OBJ_SKELETON: xyl_skeleton_destroy(p); break;
    case OBJ_MESH: xyl_mesh_destroy(p); break;
    case OBJ_PATCHES: xyl_tess_patches_destroy(p); break;
    case OBJ_FOLIAGE: xyl_foliage_destroy(p); break;
    }
}

/* The objects of a tree in one list, so that old and new trees compare object by object. */
static void objects_of(const view_tree *t, void *out[8])
{
    out[0] = t->text, out[1] = t->lsys, out[2] = t->grammar, out[3] = t->string;
    out[4] = t->skeleton, out[5] = t->mesh, out[6] = t->patches, out[7] = t->foliage;
}
static const object_kind object_kinds[8] = {OBJ_TEXT, OBJ_TEXT, OBJ_GRAMMAR, OBJ_STRING,
                                            OBJ_SKELETON, OBJ_MESH, OBJ_PATCHES, OBJ_FOLIAGE};

/* Destroys the objects of `next` that `keep` does not hold (a failed attempt's own objects). */
static void drop_new(const view_tree *next, const view_tree *keep)
{
    void *a[8], *b[8];
    objects_of(next, a);
    objects_of(keep, b);
    for (int i = 0; i < 8; ++i)
        if (a[i] && a[i] != b[i]) destroy_object(object_kinds[i], a[i]);
}

/* Under mu: the objects of `old` that `next` replaced go to the graveyard. */
static void retire_replaced(view_regrow *w, const view_tree *old, const view_tree *next)
{
    void *a[8], *b[8];
    objects_of(old, a);
    objects_of(next, b);
    for (int i = 0; i < 8; ++i) {
        if (!a[i] || a[i] == b[i]) continue;
        if (w->graveyard_count == w->graveyard_cap) {
            size_t cap = w->graveyard_cap ? w->graveyard_cap * 2 : 32;
            retired *g = realloc(w->graveyard, cap * sizeof *g);
            if (!g) continue; /* out of memory: leaked rather than freed while still shown */
            w->graveyard = g, w->graveyard_cap = cap;
        }
        w->graveyard[w->graveyard_count++] = (retired){object_kinds[i], a[i]};
    }
}

/* ---- the stages ------------------------------------------------------------------------------ */

static bool derive_changed(const view_params *a, const view_params *b)
{
    return a->has_depth != b->has_depth || (a->has_depth && a->depth != b->depth) ||
           a->has_seed != b->has_seed || (a->has_seed && a->seed != b->seed);
}

static bool turtle_changed(const xyl_turtle_desc *a, const xyl_turtle_desc *b)
{
    return a->radius_mode != b->radius_mode || a->radius_exponent != b->radius_exponent ||
           a->tip_radius != b->tip_radius || a->angle_mode != b->angle_mode ||
           a->murray_min_angle != b->murray_min_angle || a->murray_max_angle != b->murray_max_angle ||
           a->merge_collinear != b->merge_collinear;
}

static bool stems_changed(const xyl_stems_desc *a, const xyl_stems_desc *b)
{
    return a->sides != b->sides || a->normals != b->normals || a->subdivision != b->subdivision ||
           a->joints != b->joints || a->base != b->base || a->root_flare != b->root_flare ||
           a->error_world != b->error_world || a->sides_refined != b->sides_refined;
}

static bool foliage_changed(const view_params *a, const view_params *b)
{
    return a->leaves != b->leaves || a->leaf_aspect != b->leaf_aspect ||
           a->leaf_jitter != b->leaf_jitter || a->leaf_sectors != b->leaf_sectors;
}

static void set_stage(view_regrow *w, view_stage s)
{
    pthread_mutex_lock(&w->mu);
    w->stage = s;
    pthread_mutex_unlock(&w->mu);
}

static xyl_result build_foliage(const view_params *p, const xyl_skeleton *sk, xyl_foliage **out,
                                xyl_diag *d)
{
    xyl_foliage_leaves_desc ld = {0};
    ld.shape.aspect = p->leaf_aspect;
    ld.shape.size_jitter = p->leaf_jitter;
    ld.shape.seed = p->has_seed ? p->seed : 0;
    size_t n = 0;
    xyl_result r = xyl_foliage_leaves_from_skeleton(sk, &ld, NULL, 0, &n, d);
    xyl_leaf *leaves = r == XYL_OK ? malloc((n ? n : 1) * sizeof *leaves) : NULL;
    if (r == XYL_OK && !leaves) {
        snprintf(d->message, sizeof d->message, "out of memory for %zu leaves", n);
        r = XYL_ERR_OUT_OF_MEMORY;
    }
    if (r == XYL_OK) r = xyl_foliage_leaves_from_skeleton(sk, &ld, leaves, n, &n, d);
    xyl_foliage_desc fd = {0};
    fd.leaves = leaves;
    fd.leaf_count = n;
    fd.sectors = p->leaf_sectors;
    if (r == XYL_OK) r = xyl_foliage_build(&fd, out, d);
    free(leaves);
    return r;
}

/* Grows `next` from p, reusing what `cache` (built from `built`, if has_built) already holds.
 * On failure *stage is where it failed. */
static xyl_result grow(view_regrow *w, const view_params *p, view_tree *next, view_stage *stage,
                       xyl_diag *d)
{
    const view_tree *c = &w->cache;
    const view_params *b = &w->built;
    bool dirty = !w->has_built;
    xyl_result r = XYL_OK;
    double t0;

    *stage = VIEW_STAGE_GRAMMAR;
    set_stage(w, *stage);
    char *text = view_params_tuned_text(p, false);
    next->lsys = view_params_tuned_text(p, true);
    if (!text || !next->lsys) {
        free(text);
        snprintf(d->message, sizeof d->message, "out of memory for the grammar text");
        return XYL_ERR_OUT_OF_MEMORY;
    }
    if (dirty || strcmp(text, c->text) != 0) {
        next->text = text;
        t0 = now_ms();
        xyl_grammar_desc gd = {0};
        gd.source = text;
        next->grammar = NULL;
        r = xyl_grammar_parse(&gd, &next->grammar, d);
        next->ms[*stage] = now_ms() - t0, next->ran[*stage] = dirty = true;
        if (r) return r;
    } else {
        free(text);
    }

    *stage = VIEW_STAGE_DERIVE;
    set_stage(w, *stage);
    if (dirty || derive_changed(p, b)) {
        xyl_grammar_info info;
        xyl_grammar_get_info(next->grammar, &info);
        xyl_derive_desc dd = {0};
        dd.has_depth = p->has_depth, dd.depth = p->depth;
        dd.has_seed = p->has_seed, dd.seed = p->seed;
        dd.limits.max_modules = VIEW_MAX_MODULES;
        next->depth = p->has_depth ? p->depth : info.depth;
        next->seed = p->has_seed ? p->seed : info.seed;
        t0 = now_ms();
        next->string = NULL;
        r = xyl_lsystem_derive(next->grammar, &dd, &next->string, d);
        next->ms[*stage] = now_ms() - t0, next->ran[*stage] = dirty = true;
        if (r) return r;
    }

    *stage = VIEW_STAGE_TURTLE;
    set_stage(w, *stage);
    bool skeleton_new = false;
    if (dirty || turtle_changed(&p->turtle, &b->turtle)) {
        t0 = now_ms();
        next->skeleton = NULL;
        r = xyl_lsystem_interpret(next->grammar, next->string, &p->turtle, &next->skeleton, d);
        next->ms[*stage] = now_ms() - t0, next->ran[*stage] = dirty = skeleton_new = true;
        if (r) return r;
    }

    *stage = VIEW_STAGE_STEMS;
    set_stage(w, *stage);
    if (dirty || stems_changed(&p->stems, &b->stems)) {
        t0 = now_ms();
        next->mesh = NULL;
        r = xyl_stems_build(next->skeleton, &p->stems, &next->mesh, &next->stems_stats, d);
        next->ms[*stage] = now_ms() - t0, next->ran[*stage] = dirty = true;
        if (r) return r;
    }

    *stage = VIEW_STAGE_PATCHES;
    set_stage(w, *stage);
    if (dirty || p->variant != b->variant) {
        xyl_tess_patches_desc pd = {0};
        pd.variant = p->variant;
        t0 = now_ms();
        next->patches = NULL;
        r = xyl_tess_patches_create(next->mesh, &pd, &next->patches, d);
        next->ms[*stage] = now_ms() - t0, next->ran[*stage] = true;
        if (r) return r;
    }

    *stage = VIEW_STAGE_FOLIAGE;
    set_stage(w, *stage);
    if (!w->has_built || skeleton_new || foliage_changed(p, b) ||
        (p->leaves && p->has_seed != b->has_seed) || (p->leaves && p->seed != b->seed)) {
        next->foliage = NULL;
        t0 = now_ms();
        if (p->leaves) r = build_foliage(p, next->skeleton, &next->foliage, d);
        next->ms[*stage] = now_ms() - t0, next->ran[*stage] = p->leaves;
    }
    return r;
}

static void *worker_main(void *arg)
{
    view_regrow *w = arg;
    view_params p;
    view_params_init(&p);
    pthread_mutex_lock(&w->mu);
    for (;;) {
        while (!w->quit && !w->has_pending) pthread_cond_wait(&w->work, &w->mu);
        if (w->quit) break;
        view_params tmp = p;
        p = w->pending, w->pending = tmp; /* take the request; its text is ours now */
        w->has_pending = false;
        uint64_t gen = w->submitted;
        w->busy = true;
        w->started = now_ms();
        pthread_mutex_unlock(&w->mu);

        view_tree next = w->cache;
        next.generation = gen;
        next.lsys = NULL;
        memset(next.ran, 0, sizeof next.ran);
        view_stage stage = VIEW_STAGE_GRAMMAR;
        xyl_diag d = {0};
        xyl_result r = grow(w, &p, &next, &stage, &d);
        view_tree *pub = NULL;
        bool built = false, ran = false;
        for (int i = 0; i < VIEW_STAGE_COUNT; ++i) ran |= next.ran[i];
        if (r == XYL_OK && !ran && w->has_built) {
            /* Nothing that shapes the tree changed: the tree on screen stays, with its times. */
            drop_new(&next, &w->cache);
        } else if (r == XYL_OK) {
            pub = malloc(sizeof *pub);
            built = pub && view_params_copy(&w->built, &p);
            if (!built) {
                snprintf(d.message, sizeof d.message, "out of memory publishing the tree");
                r = XYL_ERR_OUT_OF_MEMORY;
            }
        }
        if (r != XYL_OK) {
            free(pub);
            pub = NULL;
            drop_new(&next, &w->cache);
        }

        pthread_mutex_lock(&w->mu);
        if (built) {
            retire_replaced(w, &w->cache, &next);
            w->cache = next;
            w->has_built = true;
            *pub = next;
            if (w->published) free(w->published); /* never adopted: its objects are retired or live */
            w->published = pub;
        }
        w->last.failed = r != XYL_OK;
        w->last.failed_stage = stage;
        w->last.error = r;
        w->last.diag = d;
        w->done = gen;
        w->busy = w->has_pending;
        pthread_cond_broadcast(&w->finished);
    }
    pthread_mutex_unlock(&w->mu);
    view_params_free(&p);
    return NULL;
}

/* ---- the main thread's side ------------------------------------------------------------------ */

view_regrow *view_regrow_start(char *err, size_t cap)
{
    view_regrow *w = calloc(1, sizeof *w);
    if (!w) {
        snprintf(err, cap, "out of memory");
        return NULL;
    }
    view_params_init(&w->pending);
    view_params_init(&w->built);
    pthread_mutex_init(&w->mu, NULL);
    pthread_cond_init(&w->work, NULL);
    pthread_cond_init(&w->finished, NULL);
    int e = pthread_create(&w->thread, NULL, worker_main, w);
    if (e) {
        snprintf(err, cap, "no worker thread: %s", strerror(e));
        pthread_cond_destroy(&w->finished);
        pthread_cond_destroy(&w->work);
        pthread_mutex_destroy(&w->mu);
        free(w);
        return NULL;
    }
    return w;
}

uint64_t view_regrow_submit(view_regrow *w, const view_params *p)
{
    view_params copy;
    view_params_init(&copy);
    if (!view_params_copy(&copy, p)) return 0;
    pthread_mutex_lock(&w->mu);
    view_params_free(&w->pending);
    w->pending = copy;
    w->has_pending = true;
    w->busy = true;
    uint64_t gen = ++w->submitted;
    pthread_cond_signal(&w->work);
    pthread_mutex_unlock(&w->mu);
    return gen;
}

void view_regrow_status_get(view_regrow *w, view_regrow_status *out)
{
    pthread_mutex_lock(&w->mu);
    *out = w->last;
    out->busy = w->busy;
    out->stage = w->stage;
    out->busy_ms = w->busy ? now_ms() - w->started : 0.0;
    out->submitted = w->submitted;
    out->done = w->done;
    pthread_mutex_unlock(&w->mu);
}

void view_regrow_wait(view_regrow *w)
{
    pthread_mutex_lock(&w->mu);
    while (w->done < w->submitted) pthread_cond_wait(&w->finished, &w->mu);
    pthread_mutex_unlock(&w->mu);
}

bool view_regrow_adopt(view_regrow *w, view_tree **current)
{
    pthread_mutex_lock(&w->mu);
    view_tree *pub = w->published;
    w->published = NULL;
    retired *g = NULL;
    size_t n = 0;
    if (pub) {
        /* Everything retired so far was replaced before pub was grown: pub holds none of it. */
        g = w->graveyard, n = w->graveyard_count;
        w->graveyard = NULL, w->graveyard_count = w->graveyard_cap = 0;
    }
    pthread_mutex_unlock(&w->mu);
    if (!pub) return false;
    free(*current);
    *current = pub;
    for (size_t i = 0; i < n; ++i) destroy_object(g[i].kind, g[i].ptr);
    free(g);
    return true;
}

void view_regrow_stop(view_regrow *w, view_tree **current)
{
    if (!w) return;
    pthread_mutex_lock(&w->mu);
    w->quit = true;
    pthread_cond_signal(&w->work);
    pthread_mutex_unlock(&w->mu);
    pthread_join(w->thread, NULL);
    view_regrow_adopt(w, current);
    void *a[8];
    objects_of(&w->cache, a);
    for (int i = 0; i < 8; ++i)
        if (a[i]) destroy_object(object_kinds[i], a[i]);
    for (size_t i = 0; i < w->graveyard_count; ++i)
        destroy_object(w->graveyard[i].kind, w->graveyard[i].ptr);
    free(w->graveyard);
    free(*current);
    *current = NULL;
    view_params_free(&w->pending);
    view_params_free(&w->built);
    pthread_cond_destroy(&w->finished);
    pthread_cond_destroy(&w->work);
    pthread_mutex_destroy(&w->mu);
    free(w);
}
