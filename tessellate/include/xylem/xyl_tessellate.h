/* xyl_tessellate.h: PN-quad / PN-triangle refinement as instanced tessellation (CPU side).
 *
 * How to use
 *   1. xyl_tess_patches_create(mesh, &desc, &patches): one record per face (quads -> PN-quads,
 *      triangles -> PN-triangles) in the GPU layout of shaders/xyl_tess_shared.h, plus the
 *      mesh's unique edges and per-patch / per-edge error coefficients for the chosen variant.
 *   2. xyl_tess_patterns_create(max_level, ...): the (i, j) lattice and indices of every level,
 *      built once and shared by all meshes.
 *   3. xyl_tess_batches_create(alloc, &batches) once; each frame xyl_tess_select(patches,
 *      patterns, &view, batches): per-edge and per-patch levels from a camera and a pixel
 *      budget (or one fixed level), patches bucketed by (kind, level) into instance records and
 *      indirect draw commands, ready to upload, in batches' read-only arrays.
 *   4. Draw: per command, the level's pattern instanced over its instance records; the vertex
 *      shader evaluates shaders/xyl_tess_eval.glsl. The backends do it for you
 *      (xylem/xyl_tess_gl.h, xylem/xyl_tess_vk.h: into your own framebuffer or command buffer,
 *      or offscreen); xyl_tess_eval_lattice() is the CPU reference of exactly that evaluation,
 *      and xyl_tess_refine() the whole CPU tessellation.
 *
 * Crack-freedom: a shared edge gets one level (computed once per unique edge); each side snaps
 * its lattice points on that edge to it and evaluates the edge in a canonical direction, so both
 * sides produce bit-identical points. This needs the mesh's faces to share vertex indices (one
 * position and normal per vertex) across the edge, as every xyl_mesh from stems/ does.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_TESSELLATE_H
#define XYL_TESSELLATE_H

#include "xylem/xyl_core.h"
#include "xylem/xyl_mesh.h"
#include "xyl_tess_shared.h" /* shaders/ in the source tree, next to this file once installed */

#ifdef __cplusplus
extern "C" {
#endif

/* The C view of the shared layouts; std430 in GLSL. */
#if !defined(__cplusplus)
_Static_assert(sizeof(xyl_tess_patch) == 128, "xyl_tess_patch is 8 vec4 in std430");
_Static_assert(offsetof(xyl_tess_patch, n) == 64, "normals follow the 4 positions");
_Static_assert(sizeof(xyl_tess_instance) == 16, "instance record is one uvec4");
_Static_assert(sizeof(xyl_tess_draw_cmd) == 20, "indirect indexed draw command is 5 words");
_Static_assert(offsetof(xyl_tess_draw_cmd, base_instance) == 16, "GL / Vulkan command layout");
_Static_assert(sizeof(xyl_tess_frame) == 128, "xyl_tess_frame is 128 bytes in std140");
_Static_assert(offsetof(xyl_tess_frame, variant) == 112, "scalars follow mat4 + 3 vec4");
#endif

typedef enum xyl_tess_variant {
    XYL_TESS_PN = XYL_TESS_VARIANT_PN,           /* handles 1/3: Vlachos' PN rule (default) */
    XYL_TESS_ROUNDED = XYL_TESS_VARIANT_ROUNDED, /* handles 1/2: Skjermo's rounded rule */
    XYL_TESS_CIRCLE = XYL_TESS_VARIANT_CIRCLE,   /* (4/3) tan(phi/4) r: exact on circular arcs */
    XYL_TESS_ARC = XYL_TESS_VARIANT_ARC          /* circle, with handles along each regular
                                                    vertex's branch curve: exact on bent tubes
                                                    (docs/tessellation.md, "The arc rule") */
} xyl_tess_variant;

/* ---- CPU reference evaluator (the shader's formulas, in float, same operation order) ------- */

/* PN-quad at (u, v) in [0,1]^2, corners at (0,0), (1,0), (1,1), (0,1); PN-triangle
 * (patch kind 3) at corner weights (1 - u - v, u, v). Interior formula only: points on an edge
 * of a tessellation are produced by xyl_tess_eval_edge (see xyl_tess_eval_lattice). */
XYL_API void xyl_tess_eval(const xyl_tess_patch *patch, xyl_tess_variant variant, float u,
                           float v, float pos[3], float normal[3]);

/* Point k of le (0 <= k <= le, 1 <= le <= 64) along the patch's edge e (from corner e to corner
 * e + 1), evaluated in the edge's canonical direction: bit-identical from both patches. */
XYL_API void xyl_tess_eval_edge(const xyl_tess_patch *patch, xyl_tess_variant variant,
                                uint32_t e, uint32_t k, uint32_t le, float pos[3],
                                float normal[3]);

/* Lattice point (i, j) of a level-`level` pattern, with the instance's packed edge levels:
 * exactly what the instanced vertex shader computes. */
XYL_API void xyl_tess_eval_lattice(const xyl_tess_patch *patch, xyl_tess_variant variant,
                                   uint32_t level, uint32_t edge_levels, uint32_t i, uint32_t j,
                                   float pos[3], float normal[3]);

/* Kind (3 or 4) of a patch record. */
XYL_API uint32_t xyl_tess_patch_kind(const xyl_tess_patch *patch);

/* ---- patches ------------------------------------------------------------------------------- */

typedef struct xyl_tess_patches_desc {
    xyl_tess_variant variant; /* default (0): XYL_TESS_PN */
    xyl_allocator alloc;
} xyl_tess_patches_desc;

typedef struct xyl_tess_patches {
    const xyl_tess_patch *records; /* one per face: the mesh's quads, then its triangles */
    size_t count;
    size_t quad_count;             /* records [0, quad_count) are quads */
    const uint32_t *patch_edges;   /* 4 unique-edge ids per patch (triangles: the 4th is ~0u) */
    size_t edge_count;             /* unique edges */
    xyl_tess_variant variant;
    float size;                    /* largest extent of the mesh's bounding box */
} xyl_tess_patches;

/* The mesh may be one the caller built: it needs normals, and is checked as xyl_mesh_create
 * checks a desc. Errors: XYL_ERR_INVALID_ARGUMENT (NULL, bad variant, a NULL array with a count,
 * a face with a vertex out of range, repeated or with a zero normal: diag.index is the face),
 * XYL_ERR_NON_FINITE (a position or normal: diag.index is the vertex; control points that
 * overflow: the face), XYL_ERR_LIMIT_EXCEEDED, XYL_ERR_OUT_OF_MEMORY. On failure *out is
 * untouched. */
XYL_API xyl_result xyl_tess_patches_create(const xyl_mesh *mesh, const xyl_tess_patches_desc *desc,
                                           xyl_tess_patches **out, xyl_diag *diag);
XYL_API void xyl_tess_patches_destroy(xyl_tess_patches *patches);

/* World-space bound of the distance between a patch (or edge) tessellated at level L and its
 * PN surface: coefficient / L^2 (see docs/tessellation.md). */
XYL_API float xyl_tess_patch_error_coefficient(const xyl_tess_patches *patches, size_t patch);
XYL_API float xyl_tess_edge_error_coefficient(const xyl_tess_patches *patches, size_t edge);

/* ---- patterns ------------------------------------------------------------------------------ */

typedef struct xyl_tess_pattern_range {
    uint32_t first_vertex, vertex_count; /* in vertices[] */
    uint32_t first_index, index_count;   /* in indices[]; indices are local to the pattern */
} xyl_tess_pattern_range;

typedef struct xyl_tess_patterns {
    const uint32_t *vertices; /* packed: i | j << XYL_TESS_PATTERN_SHIFT_J
                                 | local index << XYL_TESS_PATTERN_SHIFT_LOCAL */
    size_t vertex_count;
    const uint32_t *indices;  /* counter-clockwise triangles, like the faces they refine */
    size_t index_count;
    uint32_t max_level;
    /* ranges[0][L] quads, ranges[1][L] triangles, L = 1..max_level (index 0 unused) */
    xyl_tess_pattern_range ranges[2][XYL_TESS_MAX_LEVEL + 1];
} xyl_tess_patterns;

/* All patterns of levels 1..max_level (1..64; 0 means 64) for both kinds. Errors:
 * XYL_ERR_INVALID_ARGUMENT (max_level > 64), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_tess_patterns_create(uint32_t max_level, const xyl_allocator *alloc,
                                            xyl_tess_patterns **out, xyl_diag *diag);
XYL_API void xyl_tess_patterns_destroy(xyl_tess_patterns *patterns);

/* ---- level selection and batches ------------------------------------------------------------ */

typedef struct xyl_tess_view {
    float eye[3];             /* camera position, world space */
    float fovy;               /* vertical field of view, radians; default (0): 0.8 (45.8 deg) */
    uint32_t viewport_height; /* pixels; default (0): 1080 */
    float error_px;           /* screen-space budget; default (0): 0.5 px */
    float near_distance;      /* distances are clamped up to this; default (0): 1e-3 * size */
    uint32_t fixed_level;     /* 1..64 draws every patch at this level; default (0): adaptive */
    uint32_t max_level;       /* adaptive levels are clamped to this; default (0): patterns' max */
} xyl_tess_view;

typedef struct xyl_tess_batch {
    uint32_t kind, level; /* pattern drawn */
} xyl_tess_batch;

/* What xyl_tess_select chose for one frame, read only: instance records and indirect draw
 * commands ready to upload. A xyl_tess_batches made by xyl_tess_batches_create owns these arrays
 * and refills them at each select (they stay valid until the next select or destroy; storage
 * grows, never shrinks). The backends take any xyl_tess_batches, so a caller may also fill one
 * on the stack with arrays of its own (after culling, say): they check every record. */
typedef struct xyl_tess_batches {
    const xyl_tess_instance *instances; /* sorted by (kind, level); a per-instance buffer */
    size_t instance_count;
    const xyl_tess_draw_cmd *cmds;      /* one per non-empty (kind, level) */
    const xyl_tess_batch *batches;      /* what each command draws */
    size_t cmd_count;
    const uint8_t *edge_levels;         /* level of each unique edge (select only) */
    uint64_t triangles;                 /* triangles the commands draw */
    uint64_t vertices;                  /* pattern vertices they evaluate */
} xyl_tess_batches;

/* An empty batches object whose storage comes from alloc (NULL or zero-filled: malloc / free).
 * Errors: XYL_ERR_INVALID_ARGUMENT (out NULL), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_tess_batches_create(const xyl_allocator *alloc, xyl_tess_batches **out,
                                           xyl_diag *diag);
/* Only for objects from xyl_tess_batches_create (NULL is a no-op). */
XYL_API void xyl_tess_batches_destroy(xyl_tess_batches *batches);

/* Chooses the levels for the view and refills batches (from xyl_tess_batches_create). Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL, levels out of range, patterns with a smaller max level than
 * asked), XYL_ERR_NON_FINITE (eye), XYL_ERR_OUT_OF_MEMORY (batches keep their previous
 * content). */
XYL_API xyl_result xyl_tess_select(const xyl_tess_patches *patches,
                                   const xyl_tess_patterns *patterns, const xyl_tess_view *view,
                                   xyl_tess_batches *batches, xyl_diag *diag);

/* The world size of view->error_px pixels (0: 0.5) at the nearest point of a bounding sphere
 * (center, radius >= 0; world units) seen from view->eye: error_px d 2 tan(fovy / 2) /
 * viewport_height, with d the distance from the eye to the sphere's near side clamped up to
 * view->near_distance (0: 1e-3 of the sphere's diameter, as xyl_tess_select clamps to 1e-3 of
 * the patches' size). The same pixel -> world conversion as the level selection and the foliage
 * LOD pick, so a world error of at most *world shows as at most error_px pixels at every point
 * of the sphere (farther points: fewer). Turns one screen budget into the mesher's and the
 * pruning's world budgets (docs/tessellation.md, "One budget for the whole tree"). Errors:
 * XYL_ERR_INVALID_ARGUMENT (view, center or world NULL; fovy outside [0, pi), error_px,
 * near_distance or radius negative), XYL_ERR_NON_FINITE (eye, center or radius). */
XYL_API xyl_result xyl_tess_view_world_error(const xyl_tess_view *view, const float center[3],
                                             float radius, float *world, xyl_diag *diag);

/* ---- CPU tessellation ---------------------------------------------------------------------- */

/* Evaluates every instance of the batches with the reference evaluator into a triangle mesh:
 * each instance's pattern vertices in instance order (not welded across patches: the shared
 * edges' points are bit-identical, so xyl_mesh_check-style welding by position is exact), the
 * patterns' triangles. Drawing it as plain triangles is the "cpu" path of `xylem render`.
 * limits may be NULL (defaults); alloc may be NULL (the default allocator), else the mesh and
 * the call's scratch come from it. Errors: XYL_ERR_INVALID_ARGUMENT (instances that do not
 * match the patches or patterns), XYL_ERR_LIMIT_EXCEEDED (limits: default 2^26 vertices and
 * faces), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_tess_refine(const xyl_tess_patches *patches,
                                   const xyl_tess_patterns *patterns,
                                   const xyl_tess_batches *batches, const xyl_mesh_limits *limits,
                                   const xyl_allocator *alloc, xyl_mesh **out, xyl_diag *diag);

/* ---- cameras and offscreen images (shared by the GL and Vulkan backends) ------------------- */

typedef enum xyl_tess_clip {
    XYL_TESS_CLIP_GL = 0,    /* y up, depth -1..1 */
    XYL_TESS_CLIP_VULKAN = 1 /* y down, depth 0..1 */
} xyl_tess_clip;

typedef struct xyl_tess_camera {
    float eye[3], target[3], up[3]; /* up default (all 0): +Y */
    float fovy;                     /* radians; default (0): 0.8 */
    float aspect;                   /* width / height; default (0): 1 */
    float near_plane, far_plane;    /* default (0): from the distance to target (1e-3 d, 1e3 d) */
} xyl_tess_camera;

/* Column-major world-to-clip matrix for the API's clip convention. Errors:
 * XYL_ERR_INVALID_ARGUMENT (eye == target, up parallel to the view direction, planes out of
 * order), XYL_ERR_NON_FINITE. */
XYL_API xyl_result xyl_tess_camera_matrix(const xyl_tess_camera *camera, xyl_tess_clip clip,
                                          float view_proj[16], xyl_diag *diag);

/* A camera that frames a bounding box from a direction (azimuth around +Y and elevation, radians)
 * with the whole box in view. */
XYL_API void xyl_tess_camera_frame(const float lo[3], const float hi[3], float azimuth,
                                   float elevation, float fovy, float aspect,
                                   xyl_tess_camera *camera);

/* Moves the eye along its line to the target to factor times its distance (> 1 away, < 1
 * closer) and scales the near plane with it; the far plane moves by the eye's change in
 * distance, so what was between the planes stays between them. A factor that is not finite or
 * not > 0 leaves the camera as it is. */
XYL_API void xyl_tess_camera_zoom(xyl_tess_camera *camera, float factor);

/* xyl_tess_frame.dither for the keep range [lo, hi) of the screen-door dither (a cross-fade
 * between levels of detail: xyl_fade_update in xylem/xyl_foliage.h gives the ranges, and
 * shaders/xyl_dither.h says which pixels each keeps): both clamped to [0, 1] and rounded to
 * 16 bits, NaN taken as 0. (0, 0), the default, keeps every fragment; so does any range that
 * rounds to it, so skip a draw whose range is empty rather than packing it. */
XYL_API uint32_t xyl_tess_dither(float lo, float hi);

typedef enum xyl_tess_path {
    XYL_TESS_PATH_INSTANCED = 0, /* one pattern per level, drawn once per patch */
    XYL_TESS_PATH_HARDWARE = 1   /* TCS/TES: GL only */
} xyl_tess_path;

typedef struct xyl_tess_image_desc {
    uint32_t width, height;  /* default (0): 512 x 512; at most 8192 each */
    float background[4];     /* RGBA 0..1; default all 0 (transparent black) */
    bool wireframe;          /* overlay the triangle edges in frame->line_color */
    uint32_t samples;        /* MSAA samples; default (0): 1 */
} xyl_tess_image_desc;

#ifdef __cplusplus
}
#endif

#endif /* XYL_TESSELLATE_H */
