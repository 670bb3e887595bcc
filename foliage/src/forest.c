/* Forest instances (xyl_foliage.h, "forest instances"): the 16-byte record, a jittered grid of
 * them, a species' leaf levels and the per-frame LOD choice the GL forest renderer runs. The
 * choice is a flat loop over the instances: no pointers, no per-instance allocation, so 100 000
 * of them take well under a millisecond. */
#include <math.h>
#include <string.h>

#include "forest_internal.h"

#define TWO_PI 6.283185307179586

/* ---- the record ----------------------------------------------------------------------------- */

xyl_result xyl_forest_instance_pack(const xyl_forest_instance_values *v, xyl_forest_instance *out,
                                    xyl_diag *diag)
{
    if (!v || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "values and out are required");
    if (!isfinite(v->position[0]) || !isfinite(v->position[1]) || !isfinite(v->position[2]) ||
        !isfinite(v->rotation) || !isfinite(v->scale))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1,
                         "an instance's position, rotation or scale is not finite");
    if (v->scale < XYL_FOREST_MIN_SCALE || v->scale > XYL_FOREST_MAX_SCALE)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "an instance scale of %g: from 1/64 to 4", (double)v->scale);
    if (v->species >= XYL_FOREST_MAX_SPECIES)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "species %u: an instance holds species 0 to %d", v->species,
                         XYL_FOREST_MAX_SPECIES - 1);
    if (v->lod >= XYL_FOREST_MAX_LEVELS && v->lod != XYL_FOREST_LOD_BILLBOARD)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "LOD %u: a leaf level 0 to %d or XYL_FOREST_LOD_BILLBOARD (%u)", v->lod,
                         XYL_FOREST_MAX_LEVELS - 1, XYL_FOREST_LOD_BILLBOARD);
    double turns = (double)v->rotation / TWO_PI;
    turns -= floor(turns);
    uint32_t rot = (uint32_t)lround(turns * XYL_FOREST_ROTATION_STEPS) % XYL_FOREST_ROTATION_STEPS;
    long q = lround((double)v->scale * XYL_FOREST_SCALE_STEPS) - 1;
    uint32_t scale = (uint32_t)(q < 0 ? 0 : q > 255 ? 255 : q);
    memcpy(out->position, v->position, sizeof out->position);
    out->bits = v->lod | v->species << 8 | rot << 14 | scale << 24;
    return XYL_OK;
}

void xyl_forest_instance_unpack(const xyl_forest_instance *in, xyl_forest_instance_values *out)
{
    if (!in || !out) return;
    memcpy(out->position, in->position, sizeof out->position);
    uint32_t p = in->bits;
    out->lod = p & 255u;
    out->species = (p >> 8) & 63u;
    out->rotation = (float)((p >> 14 & 1023u) * (TWO_PI / XYL_FOREST_ROTATION_STEPS));
    out->scale = (float)((double)((p >> 24) + 1u) / XYL_FOREST_SCALE_STEPS);
}

/* ---- the grid ------------------------------------------------------------------------------- */

static uint64_t splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double uniform01(uint64_t *s)
{
    return (double)(splitmix(s) >> 11) * (1.0 / 9007199254740992.0);
}

static xyl_result check_grid(const xyl_forest_grid_desc *d, size_t capacity, xyl_diag *diag)
{
    uint64_t cap = d->max_instances ? d->max_instances : XYL_FOREST_DEFAULT_MAX_INSTANCES;
    if (cap > XYL_FOREST_LIMIT_MAX_INSTANCES)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "max_instances %llu is over the limit of %llu",
                         (unsigned long long)cap, (unsigned long long)XYL_FOREST_LIMIT_MAX_INSTANCES);
    if (d->count > cap)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%llu instances exceed max_instances (%llu)",
                         (unsigned long long)d->count, (unsigned long long)cap);
    if (d->count == 0 || capacity < d->count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "a forest of %llu instances into room for %zu: at least one, and room "
                         "for all", (unsigned long long)d->count, capacity);
    if (!isfinite(d->spacing) || !isfinite(d->jitter) || !isfinite(d->scale_min) ||
        !isfinite(d->scale_max))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "a grid value is not finite");
    bool unit = d->scale_min == 0.0f && d->scale_max == 0.0f;
    if (!(d->spacing > 0.0f) || d->jitter < 0.0f || d->jitter > 1.0f ||
        (!unit && (d->scale_min < XYL_FOREST_MIN_SCALE || d->scale_max > XYL_FOREST_MAX_SCALE ||
                   d->scale_min > d->scale_max)) ||
        d->species_count > XYL_FOREST_MAX_SPECIES)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "grid: spacing > 0, jitter in [0, 1], scales within [1/64, 4] with "
                         "min <= max, at most %d species", XYL_FOREST_MAX_SPECIES);
    return XYL_OK;
}

xyl_result xyl_forest_grid(const xyl_forest_grid_desc *d, xyl_forest_instance *out,
                           size_t capacity, xyl_diag *diag)
{
    if (!d || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "desc and out are required");
    xyl_result r = check_grid(d, capacity, diag);
    if (r != XYL_OK) return r;
    uint64_t side = (uint64_t)ceil(sqrt((double)d->count));
    while (side * side < d->count) ++side;
    bool unit = d->scale_min == 0.0f && d->scale_max == 0.0f;
    double smin = unit ? 1.0 : d->scale_min, smax = unit ? 1.0 : d->scale_max;
    uint32_t species = d->species_count ? d->species_count : 1;
    double origin = -0.5 * (double)(side - 1) * d->spacing;
    uint64_t state = d->seed;
    for (uint64_t i = 0; i < d->count; ++i) {
        double jx = (uniform01(&state) - 0.5) * d->jitter * d->spacing;
        double jz = (uniform01(&state) - 0.5) * d->jitter * d->spacing;
        xyl_forest_instance_values v = {{0, 0, 0}, 0, 1, 0, 0};
        v.position[0] = (float)(origin + (double)(i % side) * d->spacing + jx);
        v.position[2] = (float)(origin + (double)(i / side) * d->spacing + jz);
        v.rotation = (float)(uniform01(&state) * TWO_PI);
        v.scale = (float)(smin + (smax - smin) * uniform01(&state));
        v.species = (uint32_t)(splitmix(&state) % species);
        r = xyl_forest_instance_pack(&v, &out[i], diag);
        if (r != XYL_OK) return r; /* unreachable: the desc was checked */
    }
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ---- a species' leaf levels ----------------------------------------------------------------- */

static uint32_t sector_lod(const xyl_foliage_sector *s, uint32_t level)
{
    uint64_t n = s->original_count;
    uint64_t keep = level >= 63 ? 1 : (n + ((uint64_t)1 << level) - 1) >> level;
    uint64_t lod = n - (keep ? keep : 1);
    return lod > s->merged_count ? s->merged_count : (uint32_t)lod;
}

static bool all_coarsest(const xyl_foliage *f, uint32_t level)
{
    for (uint32_t s = 0; s < f->sector_count; ++s)
        if (sector_lod(&f->sectors[s], level) < f->sectors[s].merged_count) return false;
    return true;
}

xyl_result xyl__forest_plan_make(const xyl_foliage *f, uint32_t max_levels,
                                 const xyl_allocator *alloc, xyl__forest_plan *out,
                                 xyl_diag *diag)
{
    xyl__forest_plan p;
    memset(&p, 0, sizeof p);
    uint32_t cap = max_levels < 1 ? 1 : max_levels > XYL_FOREST_MAX_LEVELS ? XYL_FOREST_MAX_LEVELS
                                                                            : max_levels;
    p.level_count = 1;
    while (p.level_count < cap && !all_coarsest(f, p.level_count - 1)) ++p.level_count;
    p.ranges = xyl__alloc_array(alloc, (size_t)p.level_count * 2 * f->sector_count,
                                sizeof *p.ranges);
    if (!p.ranges) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    for (uint32_t k = 0; k < p.level_count; ++k) {
        xyl__forest_level *lv = &p.levels[k];
        lv->first_range = p.range_count;
        for (uint32_t s = 0; s < f->sector_count; ++s) {
            const xyl_foliage_sector *sec = &f->sectors[s];
            uint32_t lod = k + 1 == p.level_count && k > 0 ? sec->merged_count : sector_lod(sec, k);
            const xyl_foliage_lod *l = &sec->lods[lod];
            lv->error = fmaxf(lv->error, l->error);
            lv->leaves += l->a + l->c;
            if (l->a) p.ranges[p.range_count++] = (xyl__forest_range){sec->base, l->a};
            if (l->c) p.ranges[p.range_count++] = (xyl__forest_range){sec->base + l->b, l->c};
        }
        lv->range_count = p.range_count - lv->first_range;
        /* errors never decrease, so a farther eye never picks a finer level */
        if (k > 0 && lv->error < p.levels[k - 1].error) lv->error = p.levels[k - 1].error;
    }
    (void)diag;
    *out = p;
    return XYL_OK;
}

void xyl__forest_plan_free(xyl__forest_plan *p, const xyl_allocator *alloc)
{
    xyl__free(alloc, p->ranges);
    memset(p, 0, sizeof *p);
}

/* ---- the choice ----------------------------------------------------------------------------- */

/* Plane k of the clip-space frustum: row 3 +- row (k / 2), inside where >= 0; normalised. */
static void clip_plane(const float m[16], int k, double out[4])
{
    int row = k / 2;
    double sign = k % 2 ? -1.0 : 1.0, len = 0.0;
    for (int c = 0; c < 4; ++c) out[c] = (double)m[4 * c + 3] + sign * m[4 * c + row];
    for (int c = 0; c < 3; ++c) len += out[c] * out[c];
    len = sqrt(len);
    for (int c = 0; c < 4; ++c) out[c] = len > 0.0 ? out[c] / len : 0.0;
}

bool xyl__forest_cone(const float m[16], float axis[3], float *inv_sin, float *cos2)
{
    double near[4], side[4][4];
    clip_plane(m, 4, near); /* row 3 + row 2: its normal looks along the view */
    for (int k = 0; k < 4; ++k) clip_plane(m, k, side[k]);
    /* a side plane through the apex at half-angle h to the axis has dot(normal, axis) = sin h */
    double tan2[2] = {0.0, 0.0};
    for (int k = 0; k < 4; ++k) {
        double sh = side[k][0] * near[0] + side[k][1] * near[1] + side[k][2] * near[2];
        if (!(sh > 1e-4 && sh < 0.999)) return false;
        double t = sh / sqrt(1.0 - sh * sh);
        tan2[k / 2] = fmax(tan2[k / 2], t * t);
    }
    double t2 = tan2[0] + tan2[1]; /* the corner's half-angle */
    double c2 = 1.0 / (1.0 + t2), s = sqrt(t2 / (1.0 + t2));
    if (!(s > 1e-4 && c2 > 1e-4)) return false;
    for (int c = 0; c < 3; ++c) axis[c] = (float)near[c];
    *inv_sin = (float)(1.0 / s);
    *cos2 = (float)c2;
    return true;
}

static const float scale_of[256] = {
#define S4(q) (q + 1) / 64.0f, (q + 2) / 64.0f, (q + 3) / 64.0f, (q + 4) / 64.0f
#define S16(q) S4(q), S4(q + 4), S4(q + 8), S4(q + 12)
#define S64(q) S16(q), S16(q + 16), S16(q + 32), S16(q + 48)
    S64(0), S64(64), S64(128), S64(192)
#undef S64
#undef S16
#undef S4
};

/* An instance's level at the squared distance d2 (its scale squared s2) with the fade: the
 * coarsest level whose threshold it meets, and inside that level's band the finer level's share
 * handed over so far, in 64ths of the dither (*q 1..63; 0: one level). The result depends on
 * the distance alone, whatever level the instance came from. */
static uint32_t faded_level(const xyl__forest_choice_species *s, uint32_t lv, float d2, float s2,
                            float scale, uint32_t *q)
{
    while (lv < s->top && s->refine2[lv + 1] * s2 <= d2) ++lv;
    while (lv > 0 && s->refine2[lv] * s2 > d2) --lv;
    *q = 0;
    if (lv == 0 || !(d2 < s->band_end2[lv] * s2)) return lv;
    float t = (sqrtf(d2) / scale - s->band_lo[lv]) * s->band_inv[lv];
    float k = floorf(t * 64.0f + 0.5f);
    if (k >= 64.0f) return lv;
    if (k <= 0.0f) return s->fine[lv];
    *q = (uint32_t)k;
    return lv;
}

/* Offers instance i at squared distance d2 to the heap of the nearest (xyl__forest_near). */
static void near_offer(xyl__forest_near *h, uint32_t i, float d2)
{
    uint32_t m = h->max, n = h->count;
    if (n == m && !(d2 < h->key[0])) return;
    uint32_t at = n < m ? n++ : 0; /* push, or replace the farthest (the root) */
    if (at) { /* sift up */
        while (at && h->key[(at - 1) / 2] < d2) {
            h->index[at] = h->index[(at - 1) / 2], h->key[at] = h->key[(at - 1) / 2];
            at = (at - 1) / 2;
        }
    } else if (n == m && m > 1) { /* sift down from the root */
        for (;;) {
            uint32_t c = 2 * at + 1;
            if (c >= n) break;
            if (c + 1 < n && h->key[c + 1] > h->key[c]) ++c;
            if (!(h->key[c] > d2)) break;
            h->index[at] = h->index[c], h->key[at] = h->key[c];
            at = c;
        }
    }
    h->index[at] = i, h->key[at] = d2;
    h->count = n;
}

size_t xyl__forest_choose(const xyl__forest_choice *c, xyl_forest_instance *inst, size_t n,
                          uint16_t *bucket, uint16_t *fine_bucket, uint8_t *share,
                          uint32_t *counts, xyl__forest_near *near)
{
    if (near) near->count = 0;
    bool gather = near && near->max > 0;
    /* four interleaved histograms: consecutive instances mostly fall into one bucket, and one
     * counter incremented back to back would chain every store to the next load */
    enum { LANES = 4 };
    size_t total = (size_t)c->species_count * XYL__FOREST_BUCKETS_PER_SPECIES, twice = 0;
    uint32_t lanes[LANES][XYL_FOREST_MAX_SPECIES * XYL__FOREST_BUCKETS_PER_SPECIES];
    for (int l = 0; l < LANES; ++l) memset(lanes[l], 0, total * sizeof lanes[l][0]);
    for (size_t i = 0; i < n; ++i) {
        uint32_t p = inst[i].bits, sp = (p >> 8) & 63u;
        const xyl__forest_choice_species *s = &c->species[sp];
        float scale = scale_of[p >> 24], s2 = scale * scale;
        float cx = inst[i].position[0], cy = inst[i].position[1] + s->center_y * scale,
              cz = inst[i].position[2];
        float dx = c->eye[0] - cx, dy = c->eye[1] - cy, dz = c->eye[2] - cz;
        float d2 = dx * dx + dy * dy + dz * dz;
        uint32_t cur = p & 255u, q = 0;
        uint32_t lv = cur == XYL_FOREST_LOD_BILLBOARD ? s->level_count : cur;
        if (lv > s->top) lv = s->top;
        if (c->full) {
            lv = 0;
        } else if (c->fade) {
            lv = faded_level(s, lv, d2, s2, scale, &q);
        } else {
            while (lv < s->top && s->coarsen2[lv + 1] * s2 <= d2) ++lv;
            while (lv > 0 && s->refine2[lv] * s2 > d2) --lv;
        }
        uint32_t bits = (p & ~255u) | (lv == s->level_count ? XYL_FOREST_LOD_BILLBOARD : lv);
        if (bits != p) inst[i].bits = bits; /* a still forest dirties no cache line */
        /* the sphere against the view cone, its apex moved back by r / sin(angle) */
        float back = s->radius * scale * c->inv_sin;
        float t = -(dx * c->axis[0] + dy * c->axis[1] + dz * c->axis[2]) + back;
        float l2 = d2 + 2.0f * back * (t - back) + back * back;
        bool seen = !c->cull || (t > 0.0f && t * t >= c->cos2 * l2);
        uint32_t b = sp * XYL__FOREST_BUCKETS_PER_SPECIES + lv;
        bucket[i] = seen ? (uint16_t)b : UINT16_MAX;
        lanes[i & (LANES - 1)][b] += seen;
        if (gather && seen && lv < s->level_count) near_offer(near, (uint32_t)i, d2);
        if (c->fade) {
            q = seen ? q : 0;
            share[i] = (uint8_t)q;
            if (q) {
                uint32_t fb = sp * XYL__FOREST_BUCKETS_PER_SPECIES + s->fine[lv];
                fine_bucket[i] = (uint16_t)fb;
                ++lanes[i & (LANES - 1)][fb];
                ++twice;
            }
        }
    }
    for (size_t b = 0; b < total; ++b)
        counts[b] = lanes[0][b] + lanes[1][b] + lanes[2][b] + lanes[3][b];
    return twice;
}

void xyl__forest_sort(const xyl_forest_instance *inst, size_t n, const uint16_t *bucket,
                      const uint16_t *fine_bucket, const uint8_t *share,
                      const uint32_t *counts, uint32_t bucket_total, uint32_t *offsets,
                      xyl_forest_instance *sorted)
{
    uint32_t at = 0;
    for (uint32_t b = 0; b < bucket_total; ++b) {
        offsets[b] = at;
        at += counts[b];
    }
    offsets[bucket_total] = at;
    uint32_t fill[XYL_FOREST_MAX_SPECIES * XYL__FOREST_BUCKETS_PER_SPECIES];
    memcpy(fill, offsets, bucket_total * sizeof *fill);
    for (size_t i = 0; i < n; ++i) {
        if (bucket[i] == UINT16_MAX) continue;
        xyl_forest_instance x = inst[i];
        uint32_t q = share ? share[i] : 0;
        x.bits = (x.bits & ~255u) | (q ? q | XYL__FOREST_FADE_COARSE : 0u);
        sorted[fill[bucket[i]]++] = x;
        if (!q) continue;
        x.bits = (x.bits & ~255u) | q;
        sorted[fill[fine_bucket[i]]++] = x;
    }
}
