/* xyl_foliage.h: leaves as quads, leaf-collapse levels of detail that draw as two ranges of one
 * array, and the 32-byte GPU leaf record (docs/foliage.md).
 *
 * How to use
 *     xyl_diag diag = {0};
 *     // leaves from a skeleton's leaf attachments: count, then fill
 *     xyl_foliage_leaves_desc ld = {0};            // zero = aspect 0.5, no stalk, no jitter
 *     size_t n = 0;
 *     xyl_foliage_leaves_from_skeleton(sk, &ld, NULL, 0, &n, &diag);
 *     xyl_leaf *leaves = malloc((n ? n : 1) * sizeof *leaves);
 *     if (xyl_foliage_leaves_from_skeleton(sk, &ld, leaves, n, &n, &diag)) puts(diag.message);
 *
 *     // or your own leaves, checked with the rules every call that takes leaves applies
 *     if (xyl_foliage_check_leaves(mine, count, NULL, &diag)) printf("leaf %lld: %s\n",
 *                                                  (long long)diag.index, diag.message);
 *
 *     // the collapse chain, its linear array and LOD table
 *     xyl_foliage_desc fd = {0};                 // zero = library weights, no thresholds
 *     fd.leaves = leaves; fd.leaf_count = n;
 *     xyl_foliage *f = NULL;
 *     if (xyl_foliage_build(&fd, &f, &diag)) puts(diag.message);
 *
 *     // 32 bytes a leaf for a GPU buffer (shaders/xyl_foliage_shared.h reads them in GLSL),
 *     // once per species
 *     xyl_foliage_gpu_leaf *gpu = malloc((f->leaf_count ? f->leaf_count : 1) * sizeof *gpu);
 *     xyl_foliage_pack_gpu(f->leaves, f->leaf_count, gpu, &diag);
 *
 *     // each frame, per tree: the LOD of each sector from the view, two draws of the one array
 *     xyl_foliage_view v = {0};                  // zero = 0.8 rad, 1080 px, 0.5 px budget
 *     v.eye[0] = ex; v.eye[1] = ey; v.eye[2] = ez;   // in the tree's coordinates
 *     uint32_t lod[1];                           // one per sector (f->sector_count)
 *     xyl_foliage_pick(f, &v, lod, 1, &diag);
 *     const xyl_foliage_sector *s = &f->sectors[0];
 *     const xyl_foliage_lod *l = &s->lods[lod[0]];
 *     draw(s->base, l->a); draw(s->base + l->b, l->c);
 *
 *     // a .glb of the leaves (and, optionally, the stem mesh) with the LOD tables in extras
 *     xyl_foliage_glb_desc gd = {0};             // zero = leaves only, no texture, cutoff 0.5
 *     gd.stems = stem_mesh;
 *     if (xyl_foliage_write_glb_file(f, &gd, "tree.glb", &diag)) puts(diag.message);
 *     xyl_foliage_destroy(f);
 *
 * Every call is reentrant; only xyl_foliage_build and the GLB writers allocate (through their
 * desc's allocator; the memory writer only to split the stems' UV seams). A
 * foliage is immutable once built, so threads may read it at once.
 * The same input (seed included) gives bit-identical leaves, arrays and tables.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_FOLIAGE_H
#define XYL_FOLIAGE_H

#include <stddef.h>

#include <xylem/xyl_core.h>
#include <xylem/xyl_mesh.h>
#include <xylem/xyl_skeleton.h>
#include "xyl_foliage_shared.h" /* shaders/ in the source tree, next to this file once installed */

#ifdef __cplusplus
extern "C" {
#endif

/* The C view of the GPU leaf record; std430 in GLSL (xyl_foliage_shared.h says what precision
 * each field keeps). */
#if !defined(__cplusplus)
_Static_assert(sizeof(xyl_foliage_gpu_leaf) == XYL_FOLIAGE_GPU_LEAF_SIZE, "one leaf in 32 bytes");
_Static_assert(offsetof(xyl_foliage_gpu_leaf, axis) == 12, "halves follow the vec3 centre");
_Static_assert(offsetof(xyl_foliage_gpu_leaf, side) == 18, "side halves follow axis halves");
_Static_assert(offsetof(xyl_foliage_gpu_leaf, uv) == 24, "unorm16 rectangle in the last 8");
#endif
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "xyl_foliage_gpu_leaf pairs 16-bit fields into little-endian GLSL words"
#endif

/* ---- leaves -----------------------------------------------------------------------------------
 *
 * A leaf is a flat quad: the points center + s side + t axis for s, t in [-1, 1]. (side, axis,
 * normal) is a right-handed frame like (x, y, z): seen from the side the normal points to, the
 * axis runs up from the stalk end to the tip and the side runs to the right, so
 * normal = normalize(cross(side, axis)) and the texture reads the right way round. Corner
 * (s, t) takes the texture coordinate (u0 + (s + 1) / 2 (u1 - u0), v0 + (t + 1) / 2 (v1 - v0)):
 * v0 at the stalk end, v1 at the tip. */
typedef struct xyl_leaf {
    xyl_vec3 center;  /* world units */
    xyl_vec3 normal;  /* unit */
    xyl_vec3 axis;    /* half-axis from the centre towards the tip; |axis| = half the length */
    xyl_vec3 side;    /* half-axis across, along axis x normal; |side| = half the width */
    float uv[4];      /* texture rectangle u0, v0, u1, v1, each in [0, 1]; default (all 0):
                         0, 0, 1, 1 */
    uint32_t count;   /* original leaves this one stands for; default (0): 1 */
    int32_t node;     /* skeleton node the leaf hangs from, -1 if none */
} xyl_leaf;

/* Every bound is explicit; exceeding one is XYL_ERR_LIMIT_EXCEEDED, never a silent cut. */
typedef struct xyl_foliage_limits {
    uint64_t max_leaves;  /* leaves one call takes; default (0): 1 << 24, at most 1 << 30 */
    float max_coordinate; /* "huge": a centre coordinate or a half-axis length above this;
                             default (0): 1e6 world units, where a float centre still resolves
                             1/16 of a unit */
} xyl_foliage_limits;

/* Checks leaves with the rules xyl_foliage_build applies, and writes nothing:
 *   - every number finite (else XYL_ERR_NON_FINITE);
 *   - |axis| > 0 and |side| > 0 (a leaf of size 0 is XYL_ERR_INVALID_ARGUMENT), a normal with
 *     a direction, node >= -1, uv in [0, 1] (else XYL_ERR_INVALID_ARGUMENT);
 *   - normal, axis and side orthogonal within 1e-3 (|cosine| of each pair), and right-handed
 *     (side x axis along +normal); a calling program's leaves that are off by rounding pass, and
 *     the build re-orthogonalises them exactly (normal normalised, axis made orthogonal to it
 *     with its length kept, side = |side| unit(axis x normal)); else XYL_ERR_INVALID_ARGUMENT;
 *   - |centre coordinates|, |axis| and |side| <= limits.max_coordinate, the count of leaves
 *     <= limits.max_leaves, and the counts' sum below 2^32 (else XYL_ERR_LIMIT_EXCEEDED).
 * diag.index names the first bad leaf. Zero leaves are fine (leaves may then be NULL).
 * limits may be NULL (defaults). Coincident leaves and leaves all in one plane are valid.
 * Allocates nothing. */
XYL_API xyl_result xyl_foliage_check_leaves(const xyl_leaf *leaves, size_t count,
                                            const xyl_foliage_limits *limits, xyl_diag *diag);

/* The shape given to a skeleton's leaf attachments (xyl_skel_leaf: pos, heading, left, up,
 * size). The blade lies in the plane of heading and left, its normal is up, its axis runs along
 * heading; its base is stalk * length past the attachment point along heading. */
typedef struct xyl_leaf_shape {
    float aspect;      /* width / length; default (0): 0.5 */
    float stalk;       /* stalk length as a fraction of the blade length, >= 0; default 0 */
    float size_jitter; /* length = size (1 + size_jitter r), r uniform in [-1, 1) per leaf;
                          [0, 1); default 0 */
    float roll_jitter; /* the blade turns about its axis by roll_jitter r' radians, r' uniform
                          in [-1, 1) per leaf; [0, pi]; default 0 */
    uint64_t seed;     /* the jitter's seed; leaf i's numbers depend on seed and i only */
    float uv[4];       /* every leaf's texture rectangle; default (all 0): 0, 0, 1, 1 */
} xyl_leaf_shape;

typedef struct xyl_foliage_leaves_desc {
    xyl_leaf_shape shape;
    xyl_foliage_limits limits;
} xyl_foliage_leaves_desc;

/* One leaf per attachment of the skeleton, in its order, with count 1 and the attachment's
 * node. Count-then-fill: with leaves == NULL sets *count to skeleton->leaf_count and returns
 * XYL_OK; with capacity < that, XYL_ERR_INVALID_ARGUMENT. A skeleton without leaf attachments
 * gives *count = 0 and XYL_OK. desc may be NULL (defaults). Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL skeleton or count, a shape option out of range, an attachment of size <= 0 or whose
 * heading or up has no direction or which are parallel), XYL_ERR_NON_FINITE (an option or an
 * attachment that is NaN / inf), XYL_ERR_LIMIT_EXCEEDED (too many leaves, a huge coordinate).
 * diag.index names the attachment. Nothing is written unless every leaf is good. Allocates
 * nothing, so its desc has no allocator. */
XYL_API xyl_result xyl_foliage_leaves_from_skeleton(const xyl_skeleton *skeleton,
                                                    const xyl_foliage_leaves_desc *desc,
                                                    xyl_leaf *leaves, size_t capacity,
                                                    size_t *count, xyl_diag *diag);

#define XYL_FOLIAGE_MAX_SECTORS 256

/* ---- levels of detail ------------------------------------------------------------------------
 *
 * Leaf collapse (Hidalgo, Abad, Camahort): the pair of live leaves with the smallest weighted
 * cost is merged into one leaf, again and again, until one leaf is left or no pair passes the
 * thresholds. Each merge removes exactly one leaf; LOD i is the foliage after i merges. The
 * merged leaf: the plane through the count-weighted centre with the count-weighted normal, both
 * leaves projected on it, the main axis through the projected centres, the quad the bounding
 * rectangle of both projections along that axis with its width scaled so that its area is the
 * mean of the two leaves' areas and the rectangle's; count the sum, texture rectangle and node
 * those of the larger leaf.
 *
 * All the leaves, n originals and m merged, lie in ONE array, and LOD i draws as two ranges of
 * it, [0, a) and [b, b + c) with a + c = n - i: two draws, no index buffer, one array for all
 * the instances of a species; an instance keeps only its LOD. With sectors, each sector is
 * such an array of its own, one after another in the one array, with its own LODs. */

/* The weights of the five terms of a pair's cost, each term in [0, 1]. All 0: this library's
 * defaults, 1, 0.05, 2, 2, 0.05, chosen for the smallest LOD errors on random crowns; the
 * paper's own values were not at hand (docs/foliage.md). Otherwise taken as given. */
typedef struct xyl_collapse_weights {
    float distance;    /* |centre difference| / the foliage's size (the diagonal of the centres'
                          bounding box, at least the largest leaf's length) */
    float angle;       /* the angle between the normals / pi */
    float count;       /* |difference of represented leaf counts| / their sum */
    float area;        /* |area difference| / area sum */
    float interiority; /* the distance of the pair's midpoint from the trunk axis / the largest
                          such distance of a leaf centre: inner pairs merge first */
} xyl_collapse_weights;

typedef struct xyl_foliage_desc {
    const xyl_leaf *leaves;   /* checked as xyl_foliage_check_leaves does */
    size_t leaf_count;        /* 0 is fine: an empty foliage */
    xyl_collapse_weights weights; /* default (all 0): 1, 0.05, 2, 2, 0.05 */
    float max_distance;       /* pairs whose centres lie farther apart never merge; world units;
                                 default (0): no threshold */
    float max_angle;          /* pairs whose normals differ by more never merge; radians;
                                 default (0): no threshold */
    xyl_vec3 axis_origin;     /* the trunk axis, of the interiority term and the sectors: a point */
    xyl_vec3 axis_direction;  /* default (all 0): the vertical (+Y) line through the leaves'
                                 count-weighted centroid (axis_origin ignored) */
    uint32_t sectors;         /* the crown split by azimuth about the trunk axis into this many
                                 equal sectors, each collapsed on its own with its own LODs
                                 (ERA); default (0): 1, at most XYL_FOLIAGE_MAX_SECTORS */
    xyl_foliage_limits limits;
    xyl_allocator alloc;      /* every allocation of the build and of the foliage it makes */
} xyl_foliage_desc;

/* LOD i of a sector: its two ranges (relative to the sector's base) and its error. */
typedef struct xyl_foliage_lod {
    uint32_t a;   /* draw [0, a) of the sector: the originals still live */
    uint32_t b;   /* and [b, b + c): the merged leaves still live */
    uint32_t c;   /* a + c = n - i for LOD i of a sector of n originals */
    float error;  /* world units: no point of an original leaf lies farther than this from the
                     leaf that stands for it in this LOD; 0 for LOD 0, never decreasing */
} xyl_foliage_lod;

/* Where a leaf of the array comes from and goes to; array indices are the whole array's. */
typedef struct xyl_leaf_link {
    int32_t children[2]; /* the two leaves this one replaced (lower first); -1 for an original */
    int32_t parent;      /* the leaf that replaced this one; -1 if none (a leaf of the coarsest
                            LOD) */
    float error;         /* world units: the farthest any point of the originals it stands for
                            lies from its quad (an upper bound); 0 for an original */
    uint32_t source;     /* an original's index in desc->leaves; UINT32_MAX for a merged leaf */
} xyl_leaf_link;

/* The sector's leaves are [base, base + original_count + merged_count) of the array:
 * originals first, stored by decreasing LOD of death, so the live ones are a prefix; then
 * merged leaves in the order the chain makes them, which is also the order they die in. */
typedef struct xyl_foliage_sector {
    uint32_t base;
    uint32_t original_count; /* n */
    uint32_t merged_count;   /* m: merges, so LODs 0 .. m; m = n - 1 unless thresholds stop the
                                chain (or n = 0) */
    const xyl_foliage_lod *lods; /* m + 1: lods[i] after i merges, ranges relative to base */
    xyl_vec3 center;             /* a sphere around its original leaves (merged leaves of coarse */
    float radius;                /* LODs may reach out of it); radius 0 for an empty sector */
} xyl_foliage_sector;

/* Read-only view; the arrays belong to the foliage. */
typedef struct xyl_foliage {
    const xyl_leaf *leaves;       /* leaf_count: sector after sector */
    const xyl_leaf_link *links;   /* leaf_count */
    size_t leaf_count;            /* originals and merged leaves */
    size_t original_count;
    size_t coarsest_count;        /* leaves of the coarsest LODs together: one per sector, more
                                     where the thresholds stopped the chain */
    const xyl_foliage_sector *sectors;
    uint32_t sector_count;
    xyl_vec3 axis_origin, axis_direction; /* the trunk axis used (direction unit) */
    xyl_vec3 azimuth_zero;                /* unit, across the axis: sector s holds the leaves
                                             whose centres lie at azimuths [s, s + 1) 2 pi / S
                                             from it towards axis_direction x azimuth_zero
                                             (the world axis least aligned with the trunk's:
                                             +X for the default axis); on the axis: sector 0 */
    xyl_vec3 center;                      /* a sphere around all the original leaves */
    float radius;
} xyl_foliage;

/* Checks the leaves and options, runs the collapse chain of each sector and lays out the array
 * and the LOD tables. Zero leaves give an empty foliage (each sector one LOD of nothing) and
 * XYL_OK, as does a sector without leaves.
 * Deterministic: the same desc gives the same bits (ties between pairs of equal cost go to the
 * lower leaf indices). Expected time O(n log n), memory O(n). Errors: those of
 * xyl_foliage_check_leaves (diag.index = the leaf), XYL_ERR_INVALID_ARGUMENT (NULL desc or
 * out, a negative weight or threshold, too many sectors), XYL_ERR_NON_FINITE (an option),
 * XYL_ERR_OUT_OF_MEMORY. On failure *out is untouched and nothing is left allocated. */
XYL_API xyl_result xyl_foliage_build(const xyl_foliage_desc *desc, xyl_foliage **out,
                                     xyl_diag *diag);
/* NULL is fine. */
XYL_API void xyl_foliage_destroy(xyl_foliage *foliage);

/* ---- choosing a LOD ------------------------------------------------------------------------
 *
 * The coarsest LOD whose error, seen from the eye at the distance of the sector's bounding
 * sphere, stays under a pixel budget: LOD i is allowed when
 *     lods[i].error <= error_px * 2 d tan(fovy / 2) / viewport_height,
 * d = |eye - center| - radius. The same four fields and defaults as xyl_tess_view's (tessellate
 * has more, for its levels), repeated here rather than shared through core, which knows no
 * cameras, so that neither module depends on the other: copy them over. */
typedef struct xyl_foliage_view {
    float eye[3];             /* camera position in the foliage's coordinates (an instance's
                                 transform applied inversely) */
    float fovy;               /* vertical field of view, radians, in (0, pi); default (0): 0.8 */
    uint32_t viewport_height; /* pixels; default (0): 1080 */
    float error_px;           /* screen-space budget, pixels; default (0): 0.5 */
} xyl_foliage_view;

/* One LOD per sector into lods[0 .. sector_count): the coarsest within the budget; the finest
 * (0) when the eye is inside the sector's sphere, the coarsest (merged_count) far enough away.
 * Never coarser as the eye comes nearer. view may be NULL (the defaults with the eye at the
 * origin). Errors: XYL_ERR_INVALID_ARGUMENT (NULL foliage or lods, capacity < sector_count,
 * fovy outside [0, pi), a negative budget), XYL_ERR_NON_FINITE (a view field); lods is then
 * untouched. Allocates nothing. */
XYL_API xyl_result xyl_foliage_pick(const xyl_foliage *foliage, const xyl_foliage_view *view,
                                    uint32_t *lods, size_t capacity, xyl_diag *diag);

/* ---- the GPU record ------------------------------------------------------------------------ */

/* Packs count leaves into out[0 .. count), one 32-byte xyl_foliage_gpu_leaf each (layout and
 * precision in xyl_foliage_shared.h): the centre as is, each half-axis component rounded to the
 * nearest half float (ties to even), each texture coordinate to the nearest unorm16. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL arrays with a count, a texture coordinate outside [0, 1]),
 * XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED (a half-axis component beyond 65504, the largest
 * half); diag.index names the leaf, and out is untouched. Allocates nothing. */
XYL_API xyl_result xyl_foliage_pack_gpu(const xyl_leaf *leaves, size_t count,
                                        xyl_foliage_gpu_leaf *out, xyl_diag *diag);

/* ---- glTF export ----------------------------------------------------------------------------
 *
 * A .glb with the node "leaves": the whole array (f->leaves, sector after sector) as one
 * primitive, leaf k as vertices 4k .. 4k + 3 and indices 6k .. 6k + 5 (two triangles), with
 * POSITION, NORMAL and TEXCOORD_0 (the leaf's rectangle, v flipped to glTF's downward v: the tip
 * end at the image's top), a double-sided alpha-masked material, and the LOD tables in the
 * node's extras (docs/foliage.md, "Export", gives the schema). With stems, the stem mesh goes
 * first as the node "stems", as xyl_mesh_write_file writes it. Drawing LOD i of a sector is
 * then indices [6 base, 6 (base + a)) and [6 (base + b), 6 (base + b + c)). */
#define XYL_FOLIAGE_GLB_VERTICES_PER_LEAF 4
#define XYL_FOLIAGE_GLB_INDICES_PER_LEAF 6

typedef struct xyl_foliage_glb_desc {
    const xyl_mesh *stems;            /* optional (NULL: leaves only): written as it is by
                                         xyl_mesh_write_file, in the same file */
    const unsigned char *texture_png; /* optional: PNG bytes embedded as the material's base
                                         colour texture (the library decodes no image; it
                                         checks the signature and IHDR header); NULL: the
                                         material has a leaf-green base colour factor */
    size_t texture_png_size;          /* 0 with texture_png NULL */
    float alpha_cutoff;               /* the material's alphaCutoff, [0, 1]; default (0): 0.5 */
    xyl_allocator alloc;              /* the file variant's buffer and the stems' seam split */
} xyl_foliage_glb_desc;

/* Count-then-fill: *size = the file's bytes (out NULL is fine then); with out and capacity <
 * *size, XYL_ERR_INVALID_ARGUMENT and out untouched. A foliage with no leaves gives a valid file
 * whose "leaves" node has no mesh but still its extras (each sector one LOD of nothing); a
 * texture is then left out, since no material uses it. desc may be NULL (defaults, leaves only).
 * Errors: XYL_ERR_INVALID_ARGUMENT (NULL foliage, out and size both NULL, alpha_cutoff outside
 * [0, 1], texture bytes and size not both given, bytes that are not a PNG, a bad stem mesh),
 * XYL_ERR_NON_FINITE (alpha_cutoff, the stem mesh), XYL_ERR_LIMIT_EXCEEDED (a file over the
 * 4 GiB a GLB's length fields hold), XYL_ERR_OUT_OF_MEMORY (the stems' seam split; a mesh
 * without seams needs no memory). foliage must come from xyl_foliage_build. */
XYL_API xyl_result xyl_foliage_write_glb_memory(const xyl_foliage *foliage,
                                                const xyl_foliage_glb_desc *desc, void *out,
                                                size_t capacity, size_t *size, xyl_diag *diag);
/* The same file to path, atomically: path is either the old file or the complete new one, and
 * on failure no file is left behind. Errors: those of the memory variant, XYL_ERR_IO (cannot
 * write), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_foliage_write_glb_file(const xyl_foliage *foliage,
                                              const xyl_foliage_glb_desc *desc, const char *path,
                                              xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_FOLIAGE_H */
