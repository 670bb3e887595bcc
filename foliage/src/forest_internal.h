/* What the forest's GL renderer (forest_gl.c) takes from forest.c: a species' leaf levels (a
 * few LODs of its table, each drawn as its ranges) and the per-frame LOD choice, a flat loop
 * over the 16-byte instances that also buckets them by species and level. Not installed. */
#ifndef XYL_FOREST_INTERNAL_H
#define XYL_FOREST_INTERNAL_H

#include "xyl_internal.h"
#include "xylem/xyl_foliage.h"

#define XYL__FOREST_BUCKETS_PER_SPECIES (XYL_FOREST_MAX_LEVELS + 1) /* the levels, billboard */

typedef struct xyl__forest_range {
    uint32_t first, count; /* leaf records [first, first + count) of the species' array */
} xyl__forest_range;

typedef struct xyl__forest_level {
    float error;          /* species units: the largest error of its sectors' LODs */
    uint32_t leaves;      /* leaves drawn */
    uint32_t first_range; /* its ranges in the plan's array */
    uint32_t range_count;
} xyl__forest_level;

typedef struct xyl__forest_plan {
    xyl__forest_level levels[XYL_FOREST_MAX_LEVELS];
    uint32_t level_count;
    xyl__forest_range *ranges; /* from the plan's allocator */
    uint32_t range_count;
} xyl__forest_plan;

/* Level k of a sector of n originals and m merges is LOD min(m, n - ceil(n / 2^k)): each
 * level about halves the leaves, the last is the coarsest LOD (one leaf a sector unless the
 * thresholds stopped the chain); at most max_levels (1 .. XYL_FOREST_MAX_LEVELS) levels, the
 * last one then the coarsest. Errors: those of a table reaching outside the array
 * (XYL_ERR_INVALID_ARGUMENT), a foliage without leaves (XYL_ERR_INVALID_ARGUMENT),
 * XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl__forest_plan_make(const xyl_foliage *f, uint32_t max_levels,
                                 const xyl_allocator *alloc, xyl__forest_plan *out,
                                 xyl_diag *diag);
void xyl__forest_plan_free(xyl__forest_plan *p, const xyl_allocator *alloc);

/* A species as the choice reads it. Level k is allowed when the distance d from the eye to
 * the instance's sphere, in species units (d / scale), is at least threshold_k; with the sphere's
 * radius r that is |eye - centre|^2 >= ((threshold_k + r) scale)^2, so the loop compares
 * squares and needs no square root or division. */
typedef struct xyl__forest_choice_species {
    float center_y, radius; /* a sphere on the +Y axis that holds the tree however it turns */
    float refine2[XYL__FOREST_BUCKETS_PER_SPECIES];  /* (threshold_k + r)^2: level k kept */
    float coarsen2[XYL__FOREST_BUCKETS_PER_SPECIES]; /* (threshold_k (1 + h) + r)^2: level k
                                                        taken from a finer one */
    uint32_t top;           /* the coarsest level allowed: level_count - 1, or level_count
                               (the billboard) */
    uint32_t level_count;
    /* the cross-fade (xyl__forest_choice.fade): level k's band is the species-unit distances
     * to the centre from band_lo[k] = threshold_k + r to band_lo[k] + 1 / band_inv[k] (below
     * (band_end[k] scale)^2 = band_end2[k] s^2 in squares), where level fine[k] (the coarsest
     * one with a smaller threshold) hands over to level k; band_end2[k] 0: no band */
    float band_lo[XYL__FOREST_BUCKETS_PER_SPECIES];
    float band_inv[XYL__FOREST_BUCKETS_PER_SPECIES];
    float band_end2[XYL__FOREST_BUCKETS_PER_SPECIES];
    uint8_t fine[XYL__FOREST_BUCKETS_PER_SPECIES];
} xyl__forest_choice_species;

typedef struct xyl__forest_choice {
    const xyl__forest_choice_species *species;
    uint32_t species_count;
    float eye[3];
    bool cull;              /* false: every instance counts as visible */
    /* the view cone around the frustum (xyl__forest_cone): a sphere (c, r) is kept when
     * t = dot(c - eye, axis) + r / sin(angle) > 0 and t^2 >= cos^2(angle) |c - eye + axis
     * r / sin(angle)|^2, the cone's apex moved back so that it holds every sphere touching
     * the frustum's side planes */
    float axis[3], inv_sin, cos2;
    bool full;              /* every instance at level 0 */
    bool fade;              /* cross-fades over the species' bands instead of hysteresis */
} xyl__forest_choice;

/* The visible instances nearest the eye at a leaf level (not a billboard), gathered during the
 * choice: a max-heap on the squared distance from the eye to the instance's sphere centre,
 * index[0] the farthest kept. Ties keep the earlier instance. */
#define XYL__FOREST_NEAR_MAX 64 /* = XYL_FOREST_MAX_PER_LEAF (xyl_forest_gl.h) */
typedef struct xyl__forest_near {
    uint32_t max;   /* how many to keep, <= XYL__FOREST_NEAR_MAX; 0: none */
    uint32_t count; /* out: how many were kept */
    uint32_t index[XYL__FOREST_NEAR_MAX];
    float key[XYL__FOREST_NEAR_MAX];
} xyl__forest_near;

/* The LOD byte of an instance in the sorted, uploaded copy (never of the stored one): 0 draws
 * every pixel; otherwise bits 0..6 hold q in 1..63 and bit 7 the side: the finer level's copy
 * keeps the dither thresholds [q / 64, 1), the coarser one's (bit 7 set) [0, q / 64)
 * (xyl_dither.h; xyl_forest_keep in xyl_foliage_shared.h reads it). */
#define XYL__FOREST_FADE_COARSE 128u

/* Chooses every instance's level (written into its LOD bits), counts the visible ones per
 * bucket (species * XYL__FOREST_BUCKETS_PER_SPECIES + level) into counts (zeroed first) and
 * keeps each visible instance's bucket in bucket[i] (UINT16_MAX: culled). With c->fade, an
 * instance inside a band also gets the finer level's bucket in fine_bucket[i] and the coarser
 * level's share q (1..63, in 64ths) in share[i] (0: drawn at one level; fine_bucket is then
 * not written), and is counted in both buckets; without, fine_bucket and share may be NULL.
 * near (may be NULL) gathers the nearest visible instances at leaf levels in the same pass;
 * they stay in their buckets. Returns the visible instances drawn at two levels. */
size_t xyl__forest_choose(const xyl__forest_choice *c, xyl_forest_instance *inst, size_t n,
                          uint16_t *bucket, uint16_t *fine_bucket, uint8_t *share,
                          uint32_t *counts, xyl__forest_near *near);

/* The visible instances copied into sorted, bucket after bucket, with the LOD byte of each
 * copy replaced by its fade (XYL__FOREST_FADE_COARSE; 0 without one): sorted holds up to the
 * sum of counts, which is n plus the instances drawn twice. offsets[b] (bucket_total + 1
 * entries) receives where each bucket starts. share NULL: no instance fades. */
void xyl__forest_sort(const xyl_forest_instance *inst, size_t n, const uint16_t *bucket,
                      const uint16_t *fine_bucket, const uint8_t *share,
                      const uint32_t *counts, uint32_t bucket_total, uint32_t *offsets,
                      xyl_forest_instance *sorted);

/* The cone from the eye that holds the frustum of a column-major GL view_proj: its axis and
 * 1 / sin and cos^2 of its half-angle. false (nothing culled) for a frustum without a finite
 * cone: parallel or diverging side planes (an orthographic matrix), a half-angle near 90
 * degrees. */
bool xyl__forest_cone(const float m[16], float axis[3], float *inv_sin, float *cos2);

#endif
