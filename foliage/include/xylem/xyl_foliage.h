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
 *     // or one leaf per connected component of an OBJ leaf mesh (count, then fill), or one
 *     // template leaf from such a mesh as the shape of every attachment
 *     xyl_foliage_leaves_from_obj(obj_text, obj_size, NULL, NULL, 0, &n, &diag);
 *     xyl_leaf_shape_from_template(&template_leaf, NULL, &ld.shape, &diag);
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
 *     // or per leaf: the coarsest leaf within the budget in each cluster (count, then fill)
 *     size_t cut_n = 0;
 *     xyl_foliage_cut(f, &v, NULL, 0, &cut_n, &diag);
 *
 *     // how a LOD looks against all the leaves: its leaves (count, then fill), then RMSE and
 *     // coverage over 20 views, and the Hausdorff distance
 *     size_t m = 0;
 *     xyl_foliage_gather(f, lod, 1, NULL, 0, &m, &diag);
 *     xyl_leaf *approx = malloc((m ? m : 1) * sizeof *approx);
 *     xyl_foliage_gather(f, lod, 1, approx, m, &m, &diag);
 *     xyl_foliage_image_error e;
 *     xyl_foliage_image_error_of(leaves, n, approx, m, NULL, &e, &diag);
 *
 *     // a .glb of the leaves (and, optionally, the stem mesh) with the LOD tables in extras
 *     xyl_foliage_glb_desc gd = {0};             // zero = leaves only, no texture, cutoff 0.5
 *     gd.stems = stem_mesh;
 *     if (xyl_foliage_write_glb_file(f, &gd, "tree.glb", &diag)) puts(diag.message);
 *     xyl_foliage_destroy(f);
 *
 * Every call is reentrant; only xyl_foliage_build, xyl_foliage_leaves_from_obj,
 * xyl_foliage_image_error_of / _triangles and the GLB writers allocate (through their desc's
 * allocator; the GLB memory writer only to split the stems' UV seams). A foliage is immutable
 * once built, so threads may read it at once.
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

/* ---- leaves from a leaf mesh ------------------------------------------------------------------
 *
 * A Wavefront OBJ text whose faces are leaves: each connected component (faces sharing a vertex
 * index) becomes one quad, as Zhang reduces a leaf mesh: the plane fitted to the component by
 * area-weighted least squares, the long axis of its area in that plane running from the stalk
 * end to the tip end, and the bounding rectangle of the component projected on the plane along
 * that axis (docs/foliage.md, "Leaves from a mesh"). */

/* Which end of a component's long axis is the stalk end: the end nearer stalk_point when one
 * is given; else, with two or more components, the end nearer the vertical (+Y) line through
 * the whole mesh's centroid (leaves point away from their stem, whose axis foliage takes to be
 * vertical by default); else, or where the ends are tied (within 1e-6 of the length), the
 * lower end in Y, then the end nearer the origin. */
typedef struct xyl_leaf_mesh_desc {
    float planarity;      /* the farthest a vertex may lie from its component's fitted plane, as
                             a fraction of the longer side of its quad; default (0): 0.1; >= 0 */
    bool has_stalk_point; /* true: every component's stalk end is the end nearer stalk_point */
    xyl_vec3 stalk_point;
    float uv[4];          /* every leaf's texture rectangle; default (all 0): 0, 0, 1, 1 */
    xyl_foliage_limits limits; /* max_leaves bounds the components, max_coordinate every vertex
                                  coordinate */
    xyl_allocator alloc;  /* the call's scratch memory (about 28 bytes a vertex, 20 a face, 4 a
                             face corner, 80 a leaf); nothing stays allocated */
} xyl_leaf_mesh_desc;

/* One leaf per connected component of the faces of an OBJ text (text[0 .. size), no NUL
 * needed), in the order of the components' first faces, each with count 1 and node -1.
 * Read: "v x y z [w]" (or with r g b [a] after x y z), "f" with three or more corners "i", "i/t", "i//n" or "i/t/n" (negative i counts back from the last vertex so far;
 * a face may use only vertices defined before it), comments, blank lines, LF or CRLF. vt, vn,
 * vp, o, g, s, l, p, usemtl and mtllib lines are skipped; any other record is an error. Vertices
 * no face uses are ignored; text without faces gives *count = 0 and XYL_OK.
 * Count-then-fill: with leaves == NULL sets *count and returns XYL_OK (the whole text is read
 * and checked either way); with capacity < the count, XYL_ERR_INVALID_ARGUMENT. desc may be
 * NULL (defaults). Errors, with diag.line (and column for the text's own errors):
 *   - XYL_ERR_PARSE: a malformed record or number, an index 0 or out of range, a NUL byte;
 *   - XYL_ERR_TRUNCATED: the text ends inside a record (its last line, without a line break,
 *     is missing fields);
 *   - XYL_ERR_NON_FINITE: a NaN or infinity;
 *   - XYL_ERR_LIMIT_EXCEEDED: a coordinate beyond limits.max_coordinate, more components than
 *     limits.max_leaves, more than 2^32 - 2 vertices or faces;
 *   - XYL_ERR_INVALID_ARGUMENT: NULL text (with size > 0) or count, an option out of range, a
 *     component of zero area (collinear or coincident vertices) or beyond the planarity, or
 *     whose quad would break the leaf rules; diag.index names the component (the leaf) and
 *     diag.line its first face;
 *   - XYL_ERR_OUT_OF_MEMORY.
 * Nothing is written unless every leaf is good. Memory linear in the text; time linear (near
 * linear: a union-find joins the components). */
XYL_API xyl_result xyl_foliage_leaves_from_obj(const char *text, size_t size,
                                               const xyl_leaf_mesh_desc *desc, xyl_leaf *leaves,
                                               size_t capacity, size_t *count, xyl_diag *diag);

/* The shape that gives every leaf attachment a copy of a template leaf (say the one leaf of a
 * single-leaf mesh from xyl_foliage_leaves_from_obj): its aspect |side| / |axis|, its stalk
 * (how far the quad's stalk end, center - axis, lies from stalk_point along the axis, over the
 * quad's length; NULL stalk_point: the origin, where modelling tools put a leaf's pivot) and
 * its texture rectangle. The attachment's size then sets the blade's length, its frame the
 * blade's direction. shape's other fields (jitters, seed) are kept. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL template_leaf or shape, a template the leaf rules refuse, a
 * stalk point more than 1e-6 of the length past the stalk end towards the tip: a negative
 * stalk), XYL_ERR_NON_FINITE (a NaN or infinity); shape is then untouched. Allocates nothing. */
XYL_API xyl_result xyl_leaf_shape_from_template(const xyl_leaf *template_leaf,
                                                const xyl_vec3 *stalk_point,
                                                xyl_leaf_shape *shape, xyl_diag *diag);

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

/* What the chain merges by. */
typedef enum xyl_foliage_cost {
    XYL_FOLIAGE_COST_HIDALGO = 0,  /* the weighted five-term cost of the pair (weights above) */
    XYL_FOLIAGE_COST_VIEWPOINT = 1 /* viewpoint-driven (Sulan Zhang): the least visible leaf,
                                      seen from the 20 vertices of a dodecahedron around the
                                      sector, merges with the candidate near it that changes
                                      the mutual information between views and leaves least
                                      (docs/foliage.md); the weights are not used, the
                                      thresholds are */
} xyl_foliage_cost;

typedef struct xyl_foliage_viewpoint {
    uint32_t resolution;  /* z-buffer width and height of each view, pixels across the
                             sector's bounding sphere; default (0): 128, at most 4096 */
    uint32_t cell_leaves; /* N': the candidates, the nearest live leaves to the least visible
                             one; default (0): 8, at most 8 */
} xyl_foliage_viewpoint;

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
    xyl_foliage_cost cost;    /* default (0): XYL_FOLIAGE_COST_HIDALGO */
    xyl_foliage_viewpoint viewpoint; /* options of XYL_FOLIAGE_COST_VIEWPOINT */
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

/* ---- choosing per leaf (the cut) -------------------------------------------------------------
 *
 * Per-leaf LOD in the spirit of BroadLeaf: instead of one LOD per sector, each cluster of the
 * collapse forest shows the coarsest leaf that is within the budget from where the eye is. Leaf
 * k is within the budget when
 *     links[k].error <= error_px * 2 tan(fovy / 2) / viewport_height * max(d_k, 0),
 *     d_k = |eye - leaves[k].center| - r_k,  r_k = sqrt(|axis|^2 + |side|^2) + links[k].error,
 * the distance from the eye to a sphere around the leaf's quad grown by its error, which holds
 * every original it stands for. The cut draws leaf k when it is within the budget and none of
 * its ancestors (parent, parent's parent, ...) is: on every path from an original up to its
 * root the topmost leaf within the budget. Originals (error 0) always pass, so every original
 * is stood for by exactly one drawn leaf, whatever the errors and spheres (no monotonicity is
 * assumed: a leaf's error is its own bound against the originals, not against its children).
 * The same test as xyl_foliage_gl_draw_adaptive, in double here. */

/* The leaves of the cut, as indices into f->leaves in increasing order. Count-then-fill: with
 * out == NULL sets *count and returns XYL_OK; with capacity < *count,
 * XYL_ERR_INVALID_ARGUMENT. view as xyl_foliage_pick takes it (NULL: the defaults, eye at the
 * origin) with the same errors (XYL_ERR_NON_FINITE, XYL_ERR_INVALID_ARGUMENT); NULL f or count:
 * XYL_ERR_INVALID_ARGUMENT. An empty foliage gives *count = 0. Allocates nothing; time
 * O(leaves + drawn leaves * depth of the forest). */
XYL_API xyl_result xyl_foliage_cut(const xyl_foliage *f, const xyl_foliage_view *view,
                                   uint32_t *out, size_t capacity, size_t *count,
                                   xyl_diag *diag);

/* ---- the leaves of a LOD and its image error --------------------------------------------- */

/* The leaves drawn for one LOD per sector (lods[s] for sector s, as xyl_foliage_pick gives
 * them): the two ranges of each sector, sector after sector. Count-then-fill: with out == NULL
 * sets *count and returns XYL_OK; with capacity < *count, XYL_ERR_INVALID_ARGUMENT. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL foliage, lods or count, lod_count != sector_count, a LOD
 * beyond its sector's merged_count: diag.index = the sector); out is then untouched.
 * Allocates nothing. */
XYL_API xyl_result xyl_foliage_gather(const xyl_foliage *f, const uint32_t *lods, size_t lod_count,
                                      xyl_leaf *out, size_t capacity, size_t *count, xyl_diag *diag);

/* Grows the box lo..hi to hold every original leaf's quad (a box around its four corners);
 * start from +INFINITY / -INFINITY for the leaves' own box, or from another box (the stems') to
 * take the leaves in. A NULL foliage leaves the box as it is. */
XYL_API void xyl_foliage_bounds(const xyl_foliage *f, float lo[3], float hi[3]);

#define XYL_FOLIAGE_IMAGE_VIEWS 20              /* the vertices of a regular dodecahedron */
#define XYL_FOLIAGE_IMAGE_MAX_RESOLUTION 4096

typedef struct xyl_foliage_image_desc {
    uint32_t resolution;      /* pixels across the framed sphere (each view is resolution x
                                 resolution); default (0): 256, at most 4096 */
    float hausdorff_step;     /* world spacing of the points sampled on each quad for the
                                 Hausdorff distance, which is then exact to within
                                 step / sqrt(2) below; default (0): one pixel, 2 radius /
                                 resolution */
    uint64_t max_samples;     /* points sampled for the Hausdorff distance, both sets together;
                                 default (0): 1 << 26 */
    xyl_foliage_limits limits;/* the leaf rules, as xyl_foliage_check_leaves */
    xyl_allocator alloc;      /* every allocation of the call (freed before it returns) */
} xyl_foliage_image_desc;

/* How far an approximation of a leaf set looks from it. The image of a view: each pixel the
 * Lambert shade |normal . light| of the nearest leaf whose projection covers the pixel's
 * centre (leaves are double-sided; light the fixed unit (1, 2, 3) / sqrt(14)), 0 where none
 * does. */
typedef struct xyl_foliage_image_error {
    double rmse[XYL_FOLIAGE_IMAGE_VIEWS];     /* per view: root mean square of the shade
                                                 difference over all its pixels */
    double coverage[XYL_FOLIAGE_IMAGE_VIEWS]; /* per view: pixels covered in exactly one of
                                                 the two images / pixels covered in either
                                                 (0 when neither covers any) */
    double rmse_mean, rmse_worst;             /* over the 20 views */
    double coverage_mean, coverage_worst;
    double hausdorff;   /* symmetric Hausdorff distance between the two sets as surfaces, world
                           units (INFINITY when approx is empty) */
    xyl_vec3 center;    /* the sphere the views frame: the reference's */
    float radius;
    uint32_t resolution;/* the resolution used */
} xyl_foliage_image_error;

/* Renders both sets from the 20 views (the vertices of a regular dodecahedron around the
 * REFERENCE's bounding sphere, each an orthographic square framing it) into
 * resolution x resolution images and compares them pixel by pixel; and measures the
 * Hausdorff distance by sampling each quad on a grid of spacing at most hausdorff_step
 * (corners and edges included) and taking each sample's exact distance to the other set's
 * quads: the result h satisfies H - step / sqrt(2) <= h <= H for the true H.
 * Deterministic. Errors: XYL_ERR_INVALID_ARGUMENT (NULL reference, approx with a count,
 * desc or out; an empty reference; a resolution over 4096; a negative step), those of
 * xyl_foliage_check_leaves for either set (diag.index = the leaf; the message says which
 * set), XYL_ERR_NON_FINITE (the step), XYL_ERR_LIMIT_EXCEEDED (more samples than
 * max_samples), XYL_ERR_OUT_OF_MEMORY. desc may be NULL (defaults). On failure *out is
 * untouched. Time O(views (n + resolution^2) + samples); memory about 24 resolution^2 bytes
 * plus the sets' grids. */
XYL_API xyl_result xyl_foliage_image_error_of(const xyl_leaf *reference, size_t reference_count,
                                              const xyl_leaf *approx, size_t approx_count,
                                              const xyl_foliage_image_desc *desc,
                                              xyl_foliage_image_error *out, xyl_diag *diag);

/* The same measures for a triangle mesh against the reference leaves: another simplifier's
 * output (or leaves drawn as triangles) judged exactly as a leaf set is. Triangles are
 * double-sided, shaded by their face normal; a degenerate one covers no pixel but counts in the
 * Hausdorff distance as the segment or point it is. positions holds xyz per vertex, indices
 * three per triangle. Errors: those of xyl_foliage_image_error_of for the reference and the
 * desc; for the mesh XYL_ERR_INVALID_ARGUMENT (NULL arrays with a count, an index beyond
 * vertex_count: diag.index = the triangle), XYL_ERR_NON_FINITE and XYL_ERR_LIMIT_EXCEEDED (a
 * coordinate beyond limits.max_coordinate: diag.index = the vertex; more triangles than
 * limits.max_leaves). Zero triangles: images of nothing and a Hausdorff distance of INFINITY. */
XYL_API xyl_result xyl_foliage_image_error_triangles(const xyl_leaf *reference, size_t reference_count,
                                                     const float *positions, size_t vertex_count,
                                                     const uint32_t *indices, size_t triangle_count,
                                                     const xyl_foliage_image_desc *desc,
                                                     xyl_foliage_image_error *out, xyl_diag *diag);

/* The resolution at which xyl_foliage_pick would start to pick LOD lod of sector sector (the
 * view of the whole foliage's sphere, 2 radius across, whose pixel is lods[lod].error /
 * error_px world units): floor(2 radius error_px / error), at least 1, and
 * XYL_FOLIAGE_IMAGE_MAX_RESOLUTION for LOD 0 (error 0) or beyond it. Pass it as the image
 * desc's resolution to measure a LOD at the size it is drawn. error_px 0 means 0.5, the pick's
 * default. Errors: XYL_ERR_INVALID_ARGUMENT (NULL foliage or resolution, a sector or LOD that
 * does not exist, error_px < 0), XYL_ERR_NON_FINITE. Allocates nothing. */
XYL_API xyl_result xyl_foliage_lod_resolution(const xyl_foliage *f, uint32_t sector, uint32_t lod,
                                              float error_px, uint32_t *resolution, xyl_diag *diag);

/* ---- the GPU record ------------------------------------------------------------------------ */

/* Packs count leaves into out[0 .. count), one 32-byte xyl_foliage_gpu_leaf each (layout and
 * precision in xyl_foliage_shared.h): the centre as is, each half-axis component rounded to the
 * nearest half float (ties to even), each texture coordinate to the nearest unorm16. Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL arrays with a count, a texture coordinate outside [0, 1]),
 * XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED (a half-axis component beyond 65504, the largest
 * half); diag.index names the leaf, and out is untouched. Allocates nothing. */
XYL_API xyl_result xyl_foliage_pack_gpu(const xyl_leaf *leaves, size_t count,
                                        xyl_foliage_gpu_leaf *out, xyl_diag *diag);

/* ---- forest instances (docs/foliage.md, "Forests") ------------------------------------------
 *
 * A forest is many instances of a few species. An instance is 16 bytes (xyl_forest_instance,
 * layout in xyl_foliage_shared.h): its base point, rotation about +Y, scale, species and chosen
 * LOD; the leaves, LOD table, stems and billboard are the species', uploaded once. */
#if !defined(__cplusplus)
_Static_assert(sizeof(xyl_forest_instance) == XYL_FOREST_INSTANCE_SIZE, "an instance in 16 bytes");
_Static_assert(offsetof(xyl_forest_instance, bits) == 12, "the packed word follows the point");
#endif

#define XYL_FOREST_MAX_SPECIES 64   /* the 6 bits of an instance's species */
#define XYL_FOREST_MAX_LEVELS 16    /* leaf levels of a species (LODs 0 .. 15) */
#define XYL_FOREST_MIN_SCALE (1.0f / 64.0f)
#define XYL_FOREST_MAX_SCALE 4.0f

/* An instance unpacked. */
typedef struct xyl_forest_instance_values {
    float position[3]; /* the tree's base point, world units, finite */
    float rotation;    /* radians about +Y, any finite value (wrapped to [0, 2 pi)) */
    float scale;       /* XYL_FOREST_MIN_SCALE .. XYL_FOREST_MAX_SCALE */
    uint32_t species;  /* < XYL_FOREST_MAX_SPECIES */
    uint32_t lod;      /* a leaf level < XYL_FOREST_MAX_LEVELS, or XYL_FOREST_LOD_BILLBOARD */
} xyl_forest_instance_values;

/* Packs v into *out: the rotation rounded to the nearest of 1024 steps (error <= pi / 1024),
 * the scale to the nearest 1/64 (error <= 1/128). Errors: XYL_ERR_INVALID_ARGUMENT (NULL v or
 * out, a scale outside [1/64, 4], species >= 64, a LOD that is neither a level < 16 nor
 * XYL_FOREST_LOD_BILLBOARD), XYL_ERR_NON_FINITE; *out is then untouched. */
XYL_API xyl_result xyl_forest_instance_pack(const xyl_forest_instance_values *v,
                                            xyl_forest_instance *out, xyl_diag *diag);
/* The values of a packed instance (rotation in [0, 2 pi)). NULL arguments: nothing happens. */
XYL_API void xyl_forest_instance_unpack(const xyl_forest_instance *in,
                                        xyl_forest_instance_values *out);

/* N instances on a jittered square grid in the XZ plane (y = 0), centred on the origin. */
typedef struct xyl_forest_grid_desc {
    uint64_t count;        /* instances, >= 1, at most max_instances */
    float spacing;         /* world units between grid points, > 0 */
    float jitter;          /* each point moves by up to jitter * spacing / 2 along x and z,
                              [0, 1]; default 0: none */
    float scale_min, scale_max; /* each scale uniform in [min, max] within [1/64, 4];
                              default (both 0): 1 */
    uint32_t species_count;/* species 0 .. species_count - 1, uniform; default (0): 1 */
    uint64_t seed;         /* the same seed gives the same forest */
    uint64_t max_instances;/* default (0): XYL_FOREST_DEFAULT_MAX_INSTANCES */
} xyl_forest_grid_desc;

#define XYL_FOREST_DEFAULT_MAX_INSTANCES ((uint64_t)1 << 22)
#define XYL_FOREST_LIMIT_MAX_INSTANCES ((uint64_t)1 << 26)

/* Fills out[0 .. count): row-major on a ceil(sqrt(count)) wide grid, rotations uniform, LOD 0.
 * Errors: XYL_ERR_INVALID_ARGUMENT (NULL desc or out, count 0, capacity < count, a spacing
 * <= 0, a jitter outside [0, 1], a scale range outside [1/64, 4] or inverted, species_count
 * over 64), XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED (count over max_instances, or
 * max_instances over XYL_FOREST_LIMIT_MAX_INSTANCES). Allocates nothing. */
XYL_API xyl_result xyl_forest_grid(const xyl_forest_grid_desc *desc, xyl_forest_instance *out,
                                   size_t capacity, xyl_diag *diag);

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
    double origin[3];                 /* default (0): world position of the leaves' (0, 0, 0),
                                         the "leaves" node's translation; finite. Leaves from a
                                         skeleton are relative to its origin: pass
                                         skeleton->origin. The stems node takes the stem mesh's
                                         own origin */
} xyl_foliage_glb_desc;

/* Count-then-fill: *size = the file's bytes (out NULL is fine then); with out and capacity <
 * *size, XYL_ERR_INVALID_ARGUMENT and out untouched. A foliage with no leaves gives a valid file
 * whose "leaves" node has no mesh but still its extras (each sector one LOD of nothing); a
 * texture is then left out, since no material uses it. desc may be NULL (defaults, leaves only).
 * Errors: XYL_ERR_INVALID_ARGUMENT (NULL foliage, out and size both NULL, alpha_cutoff outside
 * [0, 1], texture bytes and size not both given, bytes that are not a PNG, a bad stem mesh),
 * XYL_ERR_NON_FINITE (alpha_cutoff, origin, the stem mesh), XYL_ERR_LIMIT_EXCEEDED (a file over the
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

/* ---- transitions between levels of detail (docs/foliage.md, "Transitions") ---------------- */

/* Where a cross-fade between a near and a far level of detail happens (the whole tree and its
 * billboard, or any two): over a band of camera distances, with hysteresis. */
typedef struct xyl_fade_desc {
    double start, end; /* distances: up to start the near level alone, from end the far one;
                          0 <= start < end, finite */
    double hysteresis; /* how far the camera must move back before the fade follows it, in
                          distance units, >= 0; default (0): none */
} xyl_fade_desc;

/* What one camera keeps between frames (zeroed before the first). */
typedef struct xyl_fade_state {
    float t;     /* the far level's share of the last frame, a multiple of 1/64 */
    bool primed; /* false before the first update */
} xyl_fade_state;

/* One frame's draws: the near level with near_keep, the far one with far_keep (the frames'
 * dither fields of xylem/xyl_foliage_gl.h, _vk.h, xyl_billboard_gl.h; stems: xyl_tess_dither),
 * each only where its flag is set. The two keep ranges split every pixel between the levels:
 * none shows both or neither. */
typedef struct xyl_fade_draws {
    bool near, far;
    float near_keep[2], far_keep[2]; /* (0, 0) for the level drawn alone */
    float t;                         /* the far level's share, a multiple of 1/64 */
} xyl_fade_draws;

/* The draws for a camera at distance from the object: t = (distance - start) / (end - start)
 * clamped to [0, 1], then held while the camera moves less than the hysteresis back (t may
 * lie anywhere between its values at distance - hysteresis and distance + hysteresis, and
 * keeps the last frame's when it can), rounded to the dither's 64 levels (the last frame's
 * level kept until the share is 3/4 of a level from it). A still camera gets the same draws
 * every frame. Errors: XYL_ERR_INVALID_ARGUMENT (NULL desc, state or out, a band
 * out of order, a negative hysteresis or distance), XYL_ERR_NON_FINITE; state and out are then
 * untouched. */
XYL_API xyl_result xyl_fade_update(const xyl_fade_desc *desc, double distance,
                                   xyl_fade_state *state, xyl_fade_draws *out, xyl_diag *diag);

/* ---- billboards: what the GL and Vulkan billboards share (xylem/xyl_billboard_gl.h,
 * xylem/xyl_billboard_vk.h, docs/foliage.md "Billboards") ---- */
#define XYL_BILLBOARD_MAX_PLANES 8
#define XYL_BILLBOARD_MIN_RESOLUTION 8
#define XYL_BILLBOARD_MAX_RESOLUTION 4096 /* and the driver's limit */
#define XYL_BILLBOARD_MIN_GRID 2
#define XYL_BILLBOARD_MAX_GRID 32
#define XYL_BILLBOARD_DEFAULT_GRID 8
#define XYL_BILLBOARD_MAX_ATLAS 16384 /* grid * resolution; and the driver's limit */

typedef enum xyl_billboard_kind {
    XYL_BILLBOARD_SPHERICAL = 0,
    XYL_BILLBOARD_CYLINDRICAL = 1,
    XYL_BILLBOARD_CROSS = 2,
    XYL_BILLBOARD_OCTAHEDRAL = 3
} xyl_billboard_kind;

#ifdef __cplusplus
}
#endif

#endif /* XYL_FOLIAGE_H */
