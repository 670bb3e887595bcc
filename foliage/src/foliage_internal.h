/* What the files of foliage/ share: resolved limits, the leaf rules, and the tolerances. Not
 * installed; the tests include it. */
#ifndef XYL_FOLIAGE_INTERNAL_H
#define XYL_FOLIAGE_INTERNAL_H

#include "xyl_internal.h"
#include "xylem/xyl_foliage.h"

#define XYL__FOLIAGE_MAX_LEAVES ((uint64_t)1 << 24)     /* default of limits.max_leaves */
#define XYL__FOLIAGE_MAX_LEAVES_CAP ((uint64_t)1 << 30) /* 2n - 1 leaves fit an int32 index */
#define XYL__FOLIAGE_MAX_COORDINATE 1e6                 /* default of limits.max_coordinate */
/* |cosine| up to which a caller's normal, axis and side count as orthogonal. */
#define XYL__LEAF_ORTHO_TOLERANCE 1e-3

typedef struct xyl__foliage_limits {
    uint64_t max_leaves;
    double max_coordinate;
} xyl__foliage_limits;

/* Defaults for zero fields; XYL_ERR_INVALID_ARGUMENT for a limit out of range. */
xyl_result xyl__foliage_limits_resolve(const xyl_foliage_limits *in, xyl__foliage_limits *out,
                                       xyl_diag *diag);
/* The rules of xyl_foliage_check_leaves for leaf i alone (the counts' sum aside). */
xyl_result xyl__leaf_check(const xyl_leaf *leaf, size_t i, const xyl__foliage_limits *limits,
                           xyl_diag *diag);
/* A checked leaf with its defaults filled in (count, uv) and its frame made exactly
 * orthonormal: normal normalised, axis orthogonal to it with its length kept,
 * side = |side| unit(axis x normal). */
xyl_leaf xyl__leaf_tidy(const xyl_leaf *leaf);

/* Corner k of a leaf: centre + (k & 1 ? 1 : -1) side + (k & 2 ? 1 : -1) axis. */
void xyl__leaf_corners(const xyl_leaf *leaf, xyl__dvec3 out[4]);
/* The least float >= v: a bound computed in double stays a bound. */
float xyl__round_up(double v);

/* ---- the GPU record (pack.c) ---- */

/* binary16 bits of f, to nearest with ties to even; beyond 65504 (after rounding) infinity. */
uint16_t xyl__half_from_float(float f);
float xyl__float_from_half(uint16_t h);
/* What a shader reads from a record: centre, half-axes, normalize(cross(side, axis)), texture
 * rectangle; count 1 and node -1, which the record does not hold. For tests. */
xyl_leaf xyl__foliage_unpack_gpu(const xyl_foliage_gpu_leaf *g);

/* ---- the grid of live leaf centres (leaf_grid.c) ---- */

/* A hint to start loading the line at p: the search is bound by memory latency. */
#if defined(__GNUC__)
#define XYL__PREFETCH(p) __builtin_prefetch(p)
#else
#define XYL__PREFETCH(p) ((void)(p))
#endif

#define XYL__GRID_K 8          /* candidate partners a query finds */
#define XYL__GRID_SCAN_CAP 64  /* live leaves one query looks at, at most */

typedef struct xyl__grid_item {
    float p[3];    /* the leaf's centre */
    uint32_t leaf; /* an extra item's is UINT32_MAX once the leaf is dead */
} xyl__grid_item;

/* A cell: its items of the last build, items[start .. end), and its first extra item (-1 for
 * none), in one place so that a query's look at a cell is one cache miss, not two. */
typedef struct xyl__cell_range {
    uint32_t start, end;
    int32_t extra;
} xyl__cell_range;

/* A leaf made since the last build, in its cell's list (newest first). */
typedef struct xyl__grid_extra {
    xyl__grid_item item;
    int32_t next, prev; /* -1 for none */
} xyl__grid_extra;

typedef struct xyl__grid {
    double min[3], h, inv_h; /* cubes of side h from min */
    int32_t dim[3];
    int64_t ring1_step[26];  /* cell index offsets of the 26 neighbours, in the query's order */
    size_t cells, cell_cap, item_cap, extra_cap, bytes;
    xyl__cell_range *range;  /* per cell */
    xyl__grid_item *items;   /* the live leaves of the last build, by cell */
    xyl__grid_extra *extra;  /* leaves made since the last build */
    uint32_t *slot;          /* per leaf: its item, or its extra item | 1 << 31 */
    uint32_t *sort, *live;   /* build scratch */
    uint32_t item_count, extra_count, built_live;
} xyl__grid;

typedef struct xyl__nearby {
    uint32_t count, scanned;
    uint32_t idx[XYL__GRID_K]; /* nearest first; ties: lower index */
    double d2[XYL__GRID_K];    /* squared distances */
} xyl__nearby;

typedef bool (*xyl__accept_fn)(void *ctx, uint32_t leaf);

/* Room for the leaves of a collapse of n: at most n live, 2n - 1 in all. */
xyl_result xyl__grid_init(xyl__grid *g, uint32_t n, const xyl_allocator *a);
void xyl__grid_free(xyl__grid *g, const xyl_allocator *a);
/* Builds from leaves 0 .. count - 1, all live. */
void xyl__grid_build(xyl__grid *g, const xyl_leaf *leaves, uint32_t count);
/* Builds again from the grid's own live leaves. */
void xyl__grid_rebuild(xyl__grid *g, const xyl_leaf *leaves);
/* True when a rebuild is due: a quarter of the leaves live at the last build are new. */
bool xyl__grid_full(const xyl__grid *g);
void xyl__grid_insert(xyl__grid *g, const xyl_leaf *leaves, uint32_t leaf);
void xyl__grid_remove(xyl__grid *g, uint32_t leaf);
/* The XYL__GRID_K live leaves nearest to centre other than self, within squared distance
 * max_d2 and accepted by accept (NULL: all), among at most XYL__GRID_SCAN_CAP looked at.
 * Returns the cells it scanned. */
uint64_t xyl__grid_nearest(const xyl__grid *g, uint32_t self, xyl_vec3 centre, double max_d2,
                           xyl__accept_fn accept, void *ctx, xyl__nearby *out);

/* ---- leaf collapse (collapse.c) ---- */

/* The terms of a pair's cost, each in [0, 1]: centre distance / scale, angle between normals
 * / pi, |count difference| / count sum, |area difference| / area sum, distance of the pair's
 * midpoint from the trunk axis / radius. */
#define XYL__COLLAPSE_TERMS 5
/* This library's default weights of the five terms: balanced merges (count and area) keep the
 * merge forest shallow, which the linear array's breadth-first order needs for small errors;
 * docs/foliage.md has the comparison they were chosen by. */
#define XYL__COLLAPSE_WEIGHTS {1.0, 0.05, 2.0, 2.0, 0.05}

typedef struct xyl__collapse_options {
    double weights[XYL__COLLAPSE_TERMS];
    double max_distance;      /* between centres, world units; INFINITY: no threshold */
    double max_angle;         /* between normals, radians; INFINITY: no threshold */
    xyl__dvec3 axis_origin;   /* the trunk axis */
    xyl__dvec3 axis_direction; /* unit */
    double scale;             /* the distance term's unit: the foliage's size */
    double radius;            /* the interiority term's unit: the farthest centre from the axis */
} xyl__collapse_options;

typedef struct xyl__collapse_stats {
    uint64_t queries, cost_evaluations, cells_scanned, leaves_scanned, grid_builds, heap_compactions;
    size_t bytes; /* scratch memory of the collapse */
} xyl__collapse_stats;

/* Default weights, no thresholds, the vertical (+Y) axis through the count-weighted centroid
 * (a count of 0 counts 1), and the units of xyl__collapse_units. */
void xyl__collapse_defaults(const xyl_leaf *leaves, uint32_t n, xyl__collapse_options *o);
/* o->scale: the larger of the centres' bounding-box diagonal and the largest leaf's length or
 * width (never 0); o->radius: the farthest centre from o's axis (o->scale if all are on it). */
void xyl__collapse_units(const xyl_leaf *leaves, uint32_t n, xyl__collapse_options *o);
/* The cost of merging p and q (p the one of lower index), rounded to float as the chain
 * orders pairs. */
float xyl__collapse_cost(const xyl_leaf *p, const xyl_leaf *q, const xyl__collapse_options *o);
/* The leaf that replaces p and q (p the one of lower index) and, in *err (unless NULL), a
 * bound of the distance from the originals it stands for to it, given theirs: the larger of
 * a child's bound plus its corners' distance from the new quad. xyl__collapse's errors are
 * tighter (exact) and do not use it. */
xyl_leaf xyl__leaf_merge(const xyl_leaf *p, const xyl_leaf *q, float err_p, float err_q, float *err);
double xyl__leaf_quad_distance(xyl__dvec3 x, const xyl_leaf *l);
/* Runs the chain on leaves[0 .. n) (checked and tidy), greedily in cost order. On success
 * leaves[n .. n + *merges) are the merged leaves in the order they were made, merge k joined
 * children[2k] < children[2k + 1], error[i] is the farthest any point of the originals leaf i
 * stands for lies from its quad, rounded up, or a child's error where that is larger (0 for
 * the originals). leaves and error hold 2n - 1, children 2n - 2 (at least 1 each).
 * Errors: XYL_ERR_OUT_OF_MEMORY only. */
xyl_result xyl__collapse(xyl_leaf *leaves, float *error, uint32_t *children, uint32_t n,
                         const xyl__collapse_options *o, const xyl_allocator *a, uint32_t *merges,
                         xyl__collapse_stats *stats, xyl_diag *diag);

/* The errors of a chain (leaves[0 .. n + m), children as xyl__collapse gives them) into
 * error[0 .. n + m): 0 for the originals; for a merged leaf the farthest corner of the
 * originals it stands for from its quad (the distance to a convex quad is convex, so that is
 * the farthest point), or a child's error where that is larger, so that errors never decrease
 * towards the roots; rounded up to float. The originals are laid out depth first, so a merged
 * leaf measures one run of them: the work is the sum of the merged leaves' original counts, n
 * times the mean depth of the merge forest. Once that passes budget, the merged leaves left
 * take the sum bound instead: the larger of a child's error plus its corners' distance from
 * the quad (sound, looser). Errors: XYL_ERR_OUT_OF_MEMORY only (nothing written). */
xyl_result xyl__collapse_errors(const xyl_leaf *leaves, float *error, const uint32_t *children,
                                uint32_t n, uint32_t m, uint64_t budget, const xyl_allocator *a);
/* The budget xyl__collapse gives it: n (4 bits(n) + 16), several times the mean depth of
 * the forests of random crowns (about 1.15 log2 n), and linear-logarithmic whatever the
 * forest's shape. */
uint64_t xyl__collapse_error_budget(uint32_t n);

/* ---- the linear LOD array (linearize.c) ---- */

/* Reorders a chain made by xyl__collapse (leaves[0 .. n + m) in cost order, children, error)
 * in place into the linear array: the originals by decreasing LOD of death, then the merged
 * leaves in the reverse breadth-first order of the merge forest. Writes each leaf's link
 * (array indices offset by base; source[x] the desc index of original x) and lods[0 .. m].
 * Errors: XYL_ERR_OUT_OF_MEMORY only. */
xyl_result xyl__linearize(xyl_leaf *leaves, const float *error, const uint32_t *children,
                          uint32_t n, uint32_t m, uint32_t base, const uint32_t *source,
                          xyl_leaf_link *links, xyl_foliage_lod *lods, const xyl_allocator *a,
                          xyl_diag *diag);

/* ---- the CPU rasteriser of leaf quads (raster.c) ---- */

#define XYL__VIEWS 20                /* the vertices of a regular dodecahedron */
#define XYL__RASTER_MAX 8192         /* the widest and tallest image */
#define XYL__RASTER_NONE UINT32_MAX  /* the id of a pixel no leaf covers */

/* An orthographic view: the point at the image's centre, a right-handed unit frame with
 * toward pointing from the scene to the eye (right x up = toward), and the world half-width
 * of the image; pixels are square, so the height follows from the image's aspect. */
typedef struct xyl__ortho_view {
    xyl__dvec3 center, right, up, toward;
    double half;
} xyl__ortho_view;

/* An owned width x height image, row 0 at the top: per pixel the depth of the nearest leaf
 * (along toward, relative to the view's centre: larger is nearer; -inf for none), its id and
 * its shade (0 for none). */
typedef struct xyl__raster {
    uint32_t width, height;
    float *depth;
    uint32_t *id;
    float *shade;
} xyl__raster;

/* A cleared image; XYL_ERR_INVALID_ARGUMENT for a size of 0 or over XYL__RASTER_MAX,
 * XYL_ERR_OUT_OF_MEMORY (nothing left allocated). */
xyl_result xyl__raster_init(xyl__raster *r, uint32_t width, uint32_t height, const xyl_allocator *a);
void xyl__raster_free(xyl__raster *r, const xyl_allocator *a);
void xyl__raster_clear(xyl__raster *r);
/* Draws one leaf (a tidy or checked one) with the given id and shade where it is nearer than
 * what is there (ties: what was drawn first stays). A pixel is covered when its centre lies
 * inside the projected quad, or on a top or left edge of it (vertices snapped to 1/256 pixel);
 * a quad seen edge-on covers nothing. */
void xyl__raster_leaf(xyl__raster *r, const xyl__ortho_view *v, const xyl_leaf *leaf, uint32_t id,
                      float shade);
/* Draws the triangle p[0], p[1], p[2] (either winding) by the same rules; a degenerate one
 * covers nothing. */
void xyl__raster_triangle(xyl__raster *r, const xyl__ortho_view *v, const xyl__dvec3 p[3], uint32_t id,
                          float shade);
/* Draws leaves[i] with id i and the Lambert shade |normal . light| (double-sided leaves). */
void xyl__raster_leaves(xyl__raster *r, const xyl__ortho_view *v, const xyl_leaf *leaves, size_t n,
                        xyl__dvec3 light);
/* The fixed light of the image error: unit (1, 2, 3) / sqrt(14). */
xyl__dvec3 xyl__raster_light(void);
/* The 20 views from the vertices of a regular dodecahedron, each an orthographic square
 * framing the sphere (center, radius) with up as near world +Y as it can be: views 0-7 look
 * from (+-1, +-1, +-1) / sqrt(3) (bit 0 of the view: +x, bit 1: +y, bit 2: +z), then for
 * i = 0 .. 3 from (0, a, b), (a, b, 0), (b, 0, a) / sqrt(3) in turn, a = +-1/phi (+ when bit 0
 * of i is set), b = +-phi (+ when bit 1 is). */
void xyl__dodecahedron_views(xyl__dvec3 center, double radius, xyl__ortho_view out[XYL__VIEWS]);

/* ---- the viewpoint-driven collapse (viewpoint.c) ---- */

#define XYL__VIEWPOINT_RESOLUTION 128 /* default z-buffer width and height per view */

typedef struct xyl__viewpoint_options {
    uint32_t resolution;  /* z-buffer width and height of each of the 20 views, 1 .. XYL__RASTER_MAX */
    uint32_t cell_leaves; /* N': the candidates, the nearest live leaves, 1 .. XYL__GRID_K */
    uint32_t refresh;     /* merges between renders of the views; 0: max(live / 16, 8) */
    double max_distance;  /* between centres; INFINITY: no threshold */
    double max_angle;     /* between normals, radians; INFINITY: no threshold */
} xyl__viewpoint_options;

typedef struct xyl__viewpoint_stats {
    uint64_t renders, queries, candidates;
    size_t bytes; /* scratch memory */
} xyl__viewpoint_stats;

/* Runs the viewpoint-driven chain on leaves[0 .. n) (checked and tidy) with the same output as
 * xyl__collapse: leaves[n .. n + *merges) the merged leaves in the order they were made, merge
 * k joined children[2k] < children[2k + 1], error[] the bounds. The least visible live leaf
 * (its pixels summed over the 20 views) merges with the one of its cell_leaves nearest live
 * leaves that changes the mutual information I(V, L) least; a leaf with no candidate within
 * the thresholds is passed over. Deterministic. Errors: XYL_ERR_OUT_OF_MEMORY only. */
xyl_result xyl__collapse_viewpoint(xyl_leaf *leaves, float *error, uint32_t *children, uint32_t n,
                                   const xyl__viewpoint_options *o, const xyl_allocator *a,
                                   uint32_t *merges, xyl__viewpoint_stats *stats, xyl_diag *diag);

/* xyl_foliage_view's checks and defaults (xyl_foliage_pick's rules): the eye, and the world
 * error the budget allows per unit of distance. */
xyl_result xyl__foliage_view_resolve(const xyl_foliage_view *view, double eye[3],
                                     double *per_distance, xyl_diag *diag);

/* The radius of leaf k's sphere in the per-leaf cut (xyl_foliage_cut): its quad's half
 * diagonal grown by its error. */
double xyl__foliage_node_radius(const xyl_leaf *leaf, const xyl_leaf_link *link);

#endif
