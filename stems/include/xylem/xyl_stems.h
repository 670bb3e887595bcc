/* xyl_stems.h: the stem mesher: one closed quad mesh around a whole branch skeleton.
 *
 * How to use
 *     xyl_stems_desc md = {0};                       // zero = k = 4, branch normals, checked
 *     md.subdivision = XYL_SUBDIVIDE_CATMARK;        // optional one level of pre-subdivision
 *     xyl_mesh *mesh = NULL;
 *     if (xyl_stems_build(skeleton, &md, &mesh, NULL, &diag) != XYL_OK) puts(diag.message);
 *     ...
 *     xyl_mesh_destroy(mesh);
 *
 * The skeleton comes from xyl_skeleton.h (your arrays, a .skel file) or from the L-system
 * (xyl_lsystem.h); the mesh is an xyl_mesh (xyl_mesh.h) to check, subdivide, export or
 * tessellate. Output is deterministic: the same skeleton and desc give the same bits.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_STEMS_H
#define XYL_STEMS_H

#include <xylem/xyl_mesh.h>
#include <xylem/xyl_skeleton.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- stems: the mesh of a skeleton ---------------------------------------------------------- */

typedef enum xyl_normal_mode {
    XYL_NORMALS_BRANCH = 0, /* a vertex averages only its own branch's faces (Skjermo 2008) */
    XYL_NORMALS_SMOOTH = 1  /* a vertex averages all its faces */
} xyl_normal_mode;

/* Whether xyl_stems_build checks its mesh at the joints (docs/stems.md, "Checked joints"). */
typedef enum xyl_joint_check {
    XYL_JOINTS_CHECKED = 0,  /* default: the mesh is tested for intersecting triangle pairs; for
                                each pair at a joint (every pair but those where the skeleton
                                overlaps itself) a lateral starts a node later along its own
                                skeleton, then 2, 4, 8 ..., and the mesh is built again (only
                                what changed is tested again), until no pair at a joint is
                                left. A lateral with no node left is not
                                meshed, but what grows from it still is (from its fork): no
                                subtree is left out. The test runs before subdivision, on the
                                mesh at the skeleton's radii; a subdivided mesh makes the same
                                changes */
    XYL_JOINTS_UNCHECKED = 1 /* the construction alone, without the test: faster
                                (docs/BENCHMARKS.md); the presets then have pairs at joints */
} xyl_joint_check;

/* The base of every root's tube (docs/stems.md, "The base"). Either way the root ring lies in
 * the root's plane: through the root node, square to the root's first segment. */
typedef enum xyl_stems_base {
    XYL_STEMS_BASE_CLOSED = 0, /* default: a cap that stays on the plane's upper side (a flat
                                  fan for k < 5, a cone whose apex lies a tenth of the radius
                                  inside for k >= 5). Pre-subdivision still rounds this base off
                                  and lifts it (docs/stems.md, "The base") */
    XYL_STEMS_BASE_OPEN = 1    /* no cap: the mesh is closed but for one k-edge boundary loop
                                  per root (for trees sunk into terrain). Subdivision keeps
                                  boundaries sharp, so the loop stays in the plane; such a mesh
                                  is refined by OpenSubdiv's Far, whose memory does not come
                                  from alloc */
} xyl_stems_base;

/* What a checked build did (all 0 but builds and the ring sides when unchecked). Face counts
 * are of the mesh before subdivision. */
typedef struct xyl_stems_stats {
    uint32_t builds;           /* meshes built: 1, plus one per round of repairs, plus one to
                                  subdivide */
    uint32_t laterals_started_later; /* meshed laterals that start one or more nodes further
                                  along their own skeleton than the construction starts them */
    uint32_t laterals_hidden;  /* laterals the check hid whole (every node): not meshed, but
                                  their own laterals are, from their fork */
    uint32_t laterals_inside;  /* laterals not meshed because the skeleton puts them wholly
                                  inside another branch's tube (the construction's placement
                                  and sibling merge leave them out, checked or not) */
    double lateral_shift_max;  /* how far (skeleton units, along the lateral's own skeleton) the
                                  check moved the start of the lateral it moved most */
    double lateral_shift_sum;  /* the same, summed over laterals_started_later */
    size_t faces_first;        /* faces of the first mesh built (the unchecked construction's) */
    size_t faces_checked;      /* faces of the mesh that passed, to compare */
    size_t joint_pairs_first;  /* intersecting pairs at joints in the first mesh */
    size_t joint_pairs_left;   /* in the mesh that passed: 0, unless only a root could give way
                                  (a root's own tube, two roots that cross; then diag gets a
                                  warning) */
    size_t skeleton_pairs;     /* intersecting pairs of the mesh that passed that the skeleton's
                                  own overlaps explain */
    /* Ring sides of the written mesh (docs/stems.md, "Ring sides per branch"), filled by every
     * build, checked or not: */
    uint32_t branches_by_sides[33]; /* branch tubes meshed with k sides at [k] (3..32; a branch
                                  the placement meshes in two pieces counts twice) */
    uint32_t sides_clamped;    /* laterals given fewer sides than error_world asks for, because
                                  the branch they grow from has fewer */
    double ring_error_max;     /* the largest radial error of a meshed tube's rings under the
                                  sides_refined model (xyl_stems_ring_error): its widest node's
                                  radius (a root's times 1 + root_flare) times its k's error;
                                  world units, with or without error_world */
} xyl_stems_stats;

#define XYL_STEMS_MAX_ROOT_FLARE 8.0f /* the widest base: 9 times the root's radius */

typedef struct xyl_stems_desc {
    uint32_t sides;               /* ring sides k, 3..32; default (0): 4; with error_world the
                                     most any branch gets. Even k gives quads only; odd k one
                                     triangle per cap and per bridge */
    xyl_normal_mode normals;
    xyl_subdivision subdivision;  /* one level of pre-subdivision; default none */
    bool keep_control_radius;     /* default false: before subdivision, rings are inflated so
                                     the limit surface's MEAN radius is the skeleton's (1.522
                                     for k = 4 with Catmull-Clark; docs/stems.md), and inner
                                     ring centres are moved against the limit's pull towards
                                     the centre of curvature on bends */
    bool keep_control_points;     /* default false: subdivided vertices sit on the limit
                                     surface (see xyl_subdivide_desc) */
    xyl_joint_check joints;
    xyl_stems_base base;          /* default: closed, flat on the root's plane */
    float root_flare;             /* default (0): none. A flared trunk base: each root's first
                                     ring is (1 + root_flare) times the root's radius, easing
                                     back to the skeleton's radius up the trunk as
                                     e^(-d / r) (d the distance from the root, r its radius),
                                     with rings added in the first segment to carry the curve;
                                     0..8 (docs/stems.md, "Root flare") */
    float error_world;            /* default (0): every branch gets `sides` rings sides. Else a
                                     radial error budget in skeleton units (> 0, finite): `sides`
                                     is the most any branch gets, and each branch gets the
                                     fewest k in 3..sides whose radial error (below) at its
                                     widest ring (its widest node, times 1 + root_flare on a
                                     root's branch) is at most error_world, or `sides` if none
                                     is; a lateral gets no more than the branch it grows from
                                     (docs/stems.md, "Ring sides per branch") */
    bool sides_refined;           /* the radial error model of error_world (xyl_stems_ring_error):
                                     false (default): the ring's own sagitta, r (1 - cos(pi / k));
                                     true: the ring as the tessellation's circle and arc rules
                                     refine it (a cubic arc per side) */
    xyl_mesh_limits limits;
    xyl_allocator alloc;
} xyl_stems_desc;

/* One closed quad mesh around the whole skeleton: a tube per branch, children grown out of their
 * parent (docs/stems.md). desc may be NULL (defaults); stats may be NULL, else it is filled
 * when the build succeeds (and left untouched when it fails). The mesh's positions are the
 * skeleton's local coordinates and its origin the skeleton's; where a node's float position is
 * coarser than 1/128 of its radius, diag gets a warning with the figures. Errors:
 * XYL_ERR_INVALID_ARGUMENT, XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY, XYL_ERR_NON_FINITE
 * (rings that leave the float range: positions plus radii above FLT_MAX; diag names the stem
 * mesher and the vertex), and those of xyl_mesh_subdivide. */
XYL_API xyl_result xyl_stems_build(const xyl_skeleton *skeleton, const xyl_stems_desc *desc,
                                   xyl_mesh **out, xyl_stems_stats *stats, xyl_diag *diag);

/* The worst radial error of a ring of `sides` sides (3..32) around a circle of radius 1, as a
 * fraction of the radius (scale it by the ring's radius): unrefined, the sagitta
 * 1 - cos(pi / sides), the inward error at mid-side; refined, the worst outward error of the
 * cubic arc that the tessellation's circle and arc rules draw over one side (handles
 * 4/3 tan(pi / (2 sides)) long; docs/stems.md, "Ring sides per branch"). This is the model
 * error_world is held to. Errors: XYL_ERR_INVALID_ARGUMENT (sides out of range, error NULL). */
XYL_API xyl_result xyl_stems_ring_error(uint32_t sides, bool refined, double *error);

/* ---- stem LODs: a chain of meshes for growing world errors --------------------------------
 *
 * From one skeleton, a sequence of closed stem meshes that drop ever thicker twigs
 * (xyl_skeleton_prune): LOD 0 pruned at a first budget E0 (0: nothing pruned), each next LOD at
 * the budget times a factor, until max_lods LODs are made or the trunk alone is left. A LOD
 * that would prune nothing more than the one before it, or would have no fewer faces, is
 * skipped (the budget grows on). An instance draws the coarsest LOD whose world error stays
 * under its pixel budget (xyl_stems_lods_pick; docs/stems.md, "Stem LODs").
 *
 *     xyl_stems_lod_desc ld = {0};                   // zero = 8 LODs, E0 = 0, factor 2
 *     xyl_stems_lods *chain = NULL;
 *     xyl_stems_lods_build(skeleton, &ld, &chain, &diag);
 *     uint32_t lod;
 *     xyl_stems_lods_pick(chain, xyl_stems_pixel_world(d, fovy, height), 0.5f, &lod, NULL);
 *     draw(chain->lods[lod].mesh);
 *     xyl_stems_lods_destroy(chain);
 */

#define XYL_STEMS_LOD_MAX 12 /* LODs in one chain at most */

typedef struct xyl_stems_lod_desc {
    xyl_stems_desc stems;  /* how every LOD is meshed (xyl_stems_build); its alloc is the
                              chain's too */
    uint32_t max_lods;     /* 1..XYL_STEMS_LOD_MAX; default (0): 8 */
    float first_budget;    /* E0, LOD 0's prune width, world units, finite, >= 0; default (0):
                              nothing pruned */
    float factor;          /* each LOD's budget over the one before, finite, > 1; default (0):
                              2. From a budget of 0 the next is factor times the thinnest
                              node's diameter 2 r */
    bool fixed_sides;      /* default false: each LOD's ring sides follow its budget too
                              (stems.error_world raised to the budget, so a branch gets the
                              fewest sides, up to stems.sides, whose ring error under
                              stems.sides_refined's model is within it); true: every LOD is
                              meshed with stems as given */
} xyl_stems_lod_desc;

typedef struct xyl_stems_lod {
    xyl_mesh *mesh;          /* closed, owned by the chain (xyl_stems_build's guarantees) */
    float budget;            /* the prune width: every subtree thinner than this was removed,
                                world units */
    float error;             /* the measured world error of the pruning: the widest removed
                                node's diameter 2 r (< budget; 0 when nothing was removed),
                                world units */
    float ring_error;        /* the rings' largest radial error (stats.ring_error_max, under
                                stems.sides_refined's model), world units; the LOD's error is
                                the larger of the two (xyl_stems_lod_error) */
    size_t node_count;       /* of the pruned skeleton */
    uint32_t branch_count;   /* of the pruned skeleton */
    size_t face_count;       /* quads + triangles of the mesh */
    size_t nodes_removed, subtrees_removed; /* xyl_skeleton_prune_stats */
    xyl_stems_stats stats;   /* what xyl_stems_build did for this LOD */
} xyl_stems_lod;

typedef struct xyl_stems_lods {
    const xyl_stems_lod *lods; /* finest first: budgets, errors grow and face counts fall
                                  strictly along the chain */
    uint32_t lod_count;        /* >= 1 */
    bool trunk_only;           /* the last LOD has no lateral left: the chain ends there */
    float center[3];           /* a sphere around every LOD's vertices, in the skeleton's
                                  local coordinates: d for xyl_stems_pixel_world is the eye's
                                  distance to it */
    float radius;
} xyl_stems_lods;

/* Builds the chain. desc may be NULL (defaults). Deterministic. Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL skeleton or out; max_lods over XYL_STEMS_LOD_MAX; first_budget or factor NaN, infinite,
 * negative, or a factor in (0, 1]), those of xyl_skeleton_prune and xyl_stems_build (diag says
 * which LOD), XYL_ERR_OUT_OF_MEMORY. On failure *out is untouched and nothing is left
 * allocated. diag keeps the first warning of any LOD's build. */
XYL_API xyl_result xyl_stems_lods_build(const xyl_skeleton *skeleton,
                                        const xyl_stems_lod_desc *desc, xyl_stems_lods **out,
                                        xyl_diag *diag);
/* NULL is fine. */
XYL_API void xyl_stems_lods_destroy(xyl_stems_lods *lods);

/* The world size of one pixel at distance d from the eye: 2 d tan(fovy / 2) / viewport_height,
 * the formula xyl_foliage_pick uses, with its defaults (fovy 0: 0.8 rad, viewport_height 0:
 * 1080 px), so that stems and leaves picked for the same eye match. d is the distance from the
 * eye to the chain's sphere (|eye - center| - radius), clamped at 0 inside it. */
XYL_API double xyl_stems_pixel_world(double d, float fovy, uint32_t viewport_height);

/* A LOD's world error: the larger of its pruning's and its rings' (xyl_stems_lod). */
XYL_API float xyl_stems_lod_error(const xyl_stems_lod *lod);

/* The coarsest LOD whose error is at most error_px pixels of pixel_world world units each:
 * xyl_stems_lod_error(&lods[i]) <= error_px * pixel_world (error_px 0: 0.5 px, foliage's default); LOD 0 when
 * none is. Never coarser for a smaller pixel_world: 0 (the eye inside the sphere) gives LOD 0,
 * +inf the coarsest. Allocates nothing.
 * Errors: XYL_ERR_INVALID_ARGUMENT (NULL chain or lod, an empty chain, pixel_world or error_px
 * negative), XYL_ERR_NON_FINITE (a NaN, an infinite error_px); *lod is then untouched. */
XYL_API xyl_result xyl_stems_lods_pick(const xyl_stems_lods *lods, double pixel_world,
                                       float error_px, uint32_t *lod, xyl_diag *diag);

/* The chain as one glTF 2.0 binary: a mesh per LOD (each as xyl_mesh_write_file writes one, with
 * extras {"lod": i, "error_world": e}) on a node of its own, LOD 0's node naming the coarser
 * ones' in the MSFT_lod extension (docs/stems.md, "Stem LODs"), the scene showing LOD 0.
 * Count-then-fill as xyl_mesh_write_memory (buffer NULL: *needed = the size), or to path as
 * xyl_mesh_write_file (atomically; alloc NULL: the default allocator). Errors: those of the
 * mesh writers, XYL_ERR_INVALID_ARGUMENT (NULL chain, lod_count 0 or over XYL_STEMS_LOD_MAX). */
XYL_API xyl_result xyl_stems_lods_write_glb_memory(const xyl_stems_lods *lods,
                                                   const xyl_allocator *alloc, void *buffer,
                                                   size_t capacity, size_t *needed,
                                                   xyl_diag *diag);
XYL_API xyl_result xyl_stems_lods_write_glb_file(const xyl_stems_lods *lods, const char *path,
                                                 const xyl_allocator *alloc, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_STEMS_H */
