/* xyl_forest_gl.h: a forest (many instances of a few species) drawn with OpenGL 4.5 core into
 * the caller's framebuffer, each instance at the level of detail its distance allows
 * (docs/foliage.md, "Forests").
 *
 * How to use
 *     // a current GL 4.5 core context; per species a built foliage, optionally its stems' base
 *     // mesh and a billboard baked from the whole tree (xyl_billboard_gl.h)
 *     xyl_forest_gl *forest = NULL;
 *     if (xyl_forest_gl_create(NULL, &forest, &diag)) puts(diag.message);
 *     xyl_forest_gl_species_desc sd = {0};
 *     sd.foliage = foliage; sd.stems = stem_mesh; sd.billboard = bb;   // bb: caller-owned
 *     uint32_t species = 0;
 *     xyl_forest_gl_add_species(forest, &sd, &species, &diag);        // leaves uploaded once
 *     xyl_forest_gl_set_texture(forest, rgba, 128, 256, &diag);        // optional leaf texture
 *
 *     xyl_forest_grid_desc gd = {0};                                  // or your own instances
 *     gd.count = 100000; gd.spacing = 12.0f; gd.jitter = 0.8f; gd.seed = 7;
 *     xyl_forest_instance *inst = malloc(gd.count * sizeof *inst);
 *     xyl_forest_grid(&gd, inst, gd.count, &diag);
 *     xyl_forest_gl_set_instances(forest, inst, gd.count, &diag);     // copied
 *
 *     // each frame, into the bound framebuffer
 *     xyl_forest_gl_frame fr = {0};
 *     memcpy(fr.view_proj, view_proj, sizeof fr.view_proj);
 *     memcpy(fr.eye, eye, sizeof fr.eye);
 *     fr.viewport_height = 1080; fr.error_px = 1.0f;
 *     fr.fade = 0.25f;          // optional: cross-fade levels over 25% past each switch
 *     fr.per_leaf = 16;         // optional: the 16 nearest trees get a per-leaf cut each
 *     xyl_forest_gl_stats st;
 *     xyl_forest_gl_draw(forest, &fr, &st, &diag);
 *     xyl_forest_gl_destroy(forest);
 *
 * A species keeps its leaf array once (32 bytes a leaf) and up to XYL_FOREST_MAX_LEVELS leaf
 * levels: level k is, per sector, LOD min(m, n - ceil(n / 2^k)) of its table (about half the
 * leaves of level k - 1; the last level the coarsest LOD), each drawn as the table's ranges.
 * Past the leaf levels comes the billboard, when the species has one. An instance is 16 bytes
 * (xyl_forest_instance) and stores the level it was last drawn at.
 *
 * The choice is a flat CPU loop over the instances: the distance d from the eye to an
 * instance's sphere (a sphere on its +Y axis around its leaves, stems and box, scaled), in the
 * species' units d / scale, allows level k when level k's error <= per_distance * d, where
 * per_distance = error_px * 2 tan(fovy / 2) / viewport_height (xyl_foliage_pick's rule). The
 * billboard's error is the species desc's billboard_error. Hysteresis: an instance moves to a
 * coarser level only when the distance is (1 + hysteresis) times that level's threshold, and
 * back to a finer one as soon as its own level's threshold is not met, so the budget always
 * holds and a still camera never changes a choice. The loop then counts instances per species
 * and level (those whose sphere reaches into a cone from the eye around the view frustum:
 * conservative, and free of the six planes' cost), sorts them into buckets and uploads them; each
 * bucket is drawn with one instanced draw per range of its level, gl_InstanceID split into the
 * leaf (id % range length) and the instance (id / range length). Stems (the base mesh,
 * per-vertex normals) are drawn for the instances at the levels whose error is under the
 * species' stem_width (where the thickest stem is still wider than the budget), one instanced
 * draw per species; billboards one instanced draw per species (a quad per plane and instance;
 * an octahedral impostor one quad per instance, its three nearest views blended).
 *
 * Cross-fades (frame.fade > 0): the level is then a function of the distance alone, with no
 * hysteresis, and within a band past each threshold (the billboard's included) the instance is
 * drawn at both levels, the coarser one's share t rising from 0 to 1 across the band in the
 * 64 steps of the 8 x 8 dither (shaders/xyl_dither.h): the finer copy keeps the pixels whose
 * threshold is >= t, the coarser one those below, so every pixel shows exactly one of them.
 * A still camera draws the same pixels every frame; a moving one changes 1/64 of an
 * instance's pixels per 1/64 of the band it crosses, never a whole tree at once. The stored
 * instance stays 16 bytes and keeps its level (the coarser one inside a band). The per-frame
 * cost: 3 bytes of scratch per instance (the second bucket and the share), and the sorted
 * copy that is uploaded holds a faded instance twice (16 more bytes each), its LOD byte
 * replaced by the copy's share (the shaders read the keep range from it). Stems follow the
 * leaf level they are drawn with.
 *
 * Per-leaf instances (frame.per_leaf = M > 0): the M visible instances nearest the eye that
 * are at a leaf level leave their buckets and each gets the per-leaf cut of
 * xyl_foliage_gl_draw_adaptive (foliage_cut.comp: per cluster of the collapse forest, the
 * coarsest leaf within the budget), computed on the GPU from the eye turned and scaled into
 * the instance's frame, then one indirect draw of its list and their stems. Per frame: M
 * compute dispatches and M draws; a max-heap picks them in the choice's loop (O(n log M)).
 * They are drawn without a fade: an instance entering or leaving the nearest M switches
 * between its cut and its level, both within the budget.
 *
 * Every call checks its input before its first GL call, and must come from the thread where
 * the context is current.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_FOREST_GL_H
#define XYL_FOREST_GL_H

#include "xylem/xyl_billboard_gl.h"
#include "xylem/xyl_foliage.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct xyl_forest_gl xyl_forest_gl;

typedef struct xyl_forest_gl_desc {
    uint64_t max_instances; /* default (0): XYL_FOREST_DEFAULT_MAX_INSTANCES; at most
                               XYL_FOREST_LIMIT_MAX_INSTANCES */
    float hysteresis;       /* [0, 1]; default (0): 0.1; negative: none */
    uint32_t max_levels;    /* leaf levels per species, 1 .. XYL_FOREST_MAX_LEVELS; default
                               (0): XYL_FOREST_MAX_LEVELS */
    xyl_allocator alloc;    /* every host allocation of the forest, as long as it lives */
} xyl_forest_gl_desc;

typedef struct xyl_forest_gl_species_desc {
    const xyl_foliage *foliage;   /* required, with leaves; copied (may be destroyed after) */
    const xyl_mesh *stems;        /* optional: the stems' base mesh, drawn as its triangles
                                     with its per-vertex normals; copied. Its positions are
                                     taken in the species' own coordinates, like the leaves'
                                     (its origin is not used: instances place the tree) */
    xyl_billboard_gl *billboard;  /* optional, borrowed: must outlive the forest; any kind
                                     (an octahedral impostor is relit and parallax-corrected
                                     per instance in the instance's own frame) */
    float billboard_error;        /* world units the billboard may be off the tree; default
                                     (0): the radius of the tree about its axis (flattening the
                                     crown onto planes through the axis moves no point
                                     farther), at least the coarsest leaf level's error */
    float stem_width;             /* the thickest stem's diameter, world units: stems are
                                     left out at levels whose error is at least this (where
                                     the trunk is narrower than the budget); default (0):
                                     stems at every leaf level */
} xyl_forest_gl_species_desc;

typedef enum xyl_forest_mode {
    XYL_FOREST_LOD = 0,         /* leaf levels, then the billboard where a species has one */
    XYL_FOREST_LEAF_LEVELS = 1, /* leaf levels only */
    XYL_FOREST_FULL = 2         /* every instance at level 0 (all its leaves) with stems */
} xyl_forest_mode;

typedef struct xyl_forest_gl_frame {
    float view_proj[16];      /* column-major world-to-clip (GL clip convention); all 0 refused */
    float eye[3];             /* the camera's position, world (the matrix's own eye: the
                                 choice measures distances and culls from it) */
    float fovy;               /* radians, (0, pi); default (0): 0.8 */
    uint32_t viewport_height; /* pixels; default (0): 1080 */
    float error_px;           /* the pixel budget, > 0 (0 and negative are refused) */
    xyl_forest_mode mode;
    bool no_cull;             /* true: draw instances outside the view too; an orthographic
                                 matrix (no view cone) culls nothing either */
    float light_dir[3];       /* towards the light; default (all 0): +Y */
    float leaf_color[4];      /* default (all 0): 0.42, 0.62, 0.25, 1 */
    float stem_color[4];      /* default (all 0): 0.47, 0.35, 0.24, 1 */
    float alpha_cutoff;       /* (0, 1]; default (0): 0.5 */
    uint32_t per_leaf;        /* the per_leaf visible instances nearest the eye (at a leaf
                                 level, not a billboard) get a per-leaf cut of their own
                                 instead of a level (see "Per-leaf instances" above); at
                                 most XYL_FOREST_MAX_PER_LEAF; default (0): none. Not in
                                 XYL_FOREST_FULL */
    float fade;               /* the cross-fade band, a fraction of each switch distance:
                                 an instance between level k's threshold d_k and
                                 (1 + fade) d_k (cut at the next threshold) is drawn at
                                 level k and the finer one before it with complementary
                                 screen-door dither (see "Cross-fades" above); [0,
                                 XYL_FOREST_MAX_FADE]; default (0): hard switches with
                                 the desc's hysteresis. Not in XYL_FOREST_FULL */
} xyl_forest_gl_frame;

#define XYL_FOREST_MAX_FADE 4.0f
#define XYL_FOREST_MAX_PER_LEAF 64

typedef struct xyl_forest_gl_stats {
    uint64_t draws;           /* GL draw calls */
    uint64_t leaves;          /* leaf quads drawn */
    uint64_t triangles;       /* leaves (2 each), stems and billboard quads (2 each) */
    uint64_t instances;       /* all */
    uint64_t visible;         /* past the frustum test */
    uint64_t per_level[XYL_FOREST_MAX_LEVELS + 1]; /* visible instances per leaf level; the
                                                       last entry: billboards. An instance
                                                       in a fade counts at both levels */
    uint64_t faded;           /* visible instances inside a fade band, drawn twice */
    uint64_t per_leaf;        /* visible instances drawn with a cut of their own (not in
                                 per_level); xyl_forest_gl_draw reads their cuts' sizes
                                 back from the GPU into leaves and triangles (a wait for
                                 the GPU; pass stats NULL to avoid it), xyl_forest_gl_choose
                                 does not count their leaves */
    uint64_t with_stems;      /* visible instances drawn with stems */
    uint32_t bytes_per_instance; /* XYL_FOREST_INSTANCE_SIZE */
    double choose_ms;         /* CPU: the LOD choice, frustum test and bucketing */
    double upload_ms;         /* CPU: handing the sorted instances to GL */
} xyl_forest_gl_stats;

/* What a species became: its leaf levels and the thresholds the choice uses. */
typedef struct xyl_forest_gl_species_info {
    uint32_t level_count;
    float level_error[XYL_FOREST_MAX_LEVELS]; /* world units, never decreasing */
    uint32_t level_leaves[XYL_FOREST_MAX_LEVELS];
    uint32_t stem_levels;     /* stems drawn at levels 0 .. stem_levels - 1 */
    bool has_billboard;
    float billboard_error;    /* resolved */
    float center_y, radius;   /* the sphere on the +Y axis, species units */
    uint64_t stem_triangles;
} xyl_forest_gl_species_info;

/* Errors: XYL_ERR_INVALID_ARGUMENT (NULL out, a hysteresis over 1, max_levels over 16),
 * XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED (max_instances over the limit),
 * XYL_ERR_UNSUPPORTED (no GL 4.5 core context, a shader that does not compile: the driver's
 * log in diag.message), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_forest_gl_create(const xyl_forest_gl_desc *desc, xyl_forest_gl **out,
                                        xyl_diag *diag);
/* NULL is fine. Deletes its GL objects when a context is current; billboards are the caller's. */
XYL_API void xyl_forest_gl_destroy(xyl_forest_gl *forest);

/* Adds a species; *index receives its number (0, 1, ...). Errors: XYL_ERR_INVALID_ARGUMENT
 * (NULL forest, desc, foliage or index; a foliage with no leaves, a malformed table, a stem
 * mesh without triangles or normals, a negative billboard_error or stem_width, 64 species
 * already), XYL_ERR_NON_FINITE, those of
 * xyl_foliage_pack_gpu, XYL_ERR_LIMIT_EXCEEDED (a leaf
 * array over the driver's storage block), XYL_ERR_OUT_OF_MEMORY. On failure nothing changes. */
XYL_API xyl_result xyl_forest_gl_add_species(xyl_forest_gl *forest,
                                             const xyl_forest_gl_species_desc *desc,
                                             uint32_t *index, xyl_diag *diag);

/* The leaf texture of every species, as xyl_foliage_gl_set_texture takes it. */
XYL_API xyl_result xyl_forest_gl_set_texture(xyl_forest_gl *forest, const uint8_t *rgba,
                                             uint32_t width, uint32_t height, xyl_diag *diag);

/* Copies count instances (replacing the previous ones). Errors: XYL_ERR_INVALID_ARGUMENT (NULL
 * forest, NULL instances with a count, 0 instances, a species not added, a LOD beyond the
 * species' levels or a billboard LOD for a species without one: diag.index = the instance),
 * XYL_ERR_NON_FINITE (a position), XYL_ERR_LIMIT_EXCEEDED (count over max_instances),
 * XYL_ERR_OUT_OF_MEMORY. On failure the previous instances stay. */
XYL_API xyl_result xyl_forest_gl_set_instances(xyl_forest_gl *forest,
                                               const xyl_forest_instance *instances,
                                               size_t count, xyl_diag *diag);

/* The forest's instances with the LODs last chosen (NULL forest: NULL, *count 0). */
XYL_API const xyl_forest_instance *xyl_forest_gl_instances(const xyl_forest_gl *forest,
                                                           size_t *count);

/* The LOD choice alone (no GL call): every instance's level for this frame, written into the
 * instances, and the stats' counts and choose_ms. Errors: those of the frame as
 * xyl_forest_gl_draw checks it. */
XYL_API xyl_result xyl_forest_gl_choose(xyl_forest_gl *forest, const xyl_forest_gl_frame *frame,
                                        xyl_forest_gl_stats *stats, xyl_diag *diag);

/* Chooses (as xyl_forest_gl_choose) and draws the forest into the bound framebuffer with the
 * current viewport: depth test (GL_LESS) and writes on, no face culling (restored), no
 * blending. stats may be NULL. Errors: XYL_ERR_INVALID_ARGUMENT (NULL forest or frame, no
 * instances, an all-zero matrix, a budget <= 0, fovy outside (0, pi) when given, an unknown
 * mode, a cutoff outside [0, 1], a fade outside [0, XYL_FOREST_MAX_FADE], per_leaf over
 * XYL_FOREST_MAX_PER_LEAF), XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED (more visible
 * instances, or per-leaf lists, than the driver's storage block holds), XYL_ERR_OUT_OF_MEMORY
 * (GL). Uses storage buffer bindings 0 and 4 (with per_leaf also 1 to 3; the draw-indirect
 * buffer binding is restored) and texture units 0 and 1. */
XYL_API xyl_result xyl_forest_gl_draw(xyl_forest_gl *forest, const xyl_forest_gl_frame *frame,
                                      xyl_forest_gl_stats *stats, xyl_diag *diag);

/* Errors: XYL_ERR_INVALID_ARGUMENT (NULL forest or info, a species not added). */
XYL_API xyl_result xyl_forest_gl_species(const xyl_forest_gl *forest, uint32_t species,
                                         xyl_forest_gl_species_info *info, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_FOREST_GL_H */
