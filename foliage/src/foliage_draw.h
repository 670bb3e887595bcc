/* What foliage/'s GPU leaf renderers (GL and Vulkan) share: the checked copy of a species' LOD
 * tables they draw from, and the checks and defaults of a draw's values, so both accept and
 * refuse the same input with the same codes and messages. Not installed. */
#ifndef XYL_FOLIAGE_DRAW_H
#define XYL_FOLIAGE_DRAW_H

#include "xyl_internal.h"
#include "xylem/xyl_foliage.h"

typedef struct xyl__foliage_sector_ref {
    uint32_t base, first_lod, lod_count;
} xyl__foliage_sector_ref;

typedef struct xyl__foliage_range {
    uint32_t a, b, c; /* a LOD's ranges [base, base + a) and [base + b, base + b + c) */
} xyl__foliage_range;

/* A species' tables as a renderer keeps them; leaf_count 0: nothing uploaded. */
typedef struct xyl__foliage_tables {
    xyl__foliage_sector_ref *sectors;
    xyl__foliage_range *ranges; /* at sectors[s].first_lod + lod */
    uint32_t sector_count;
    size_t leaf_count;
} xyl__foliage_tables;

/* A draw's values with their defaults filled in (light normalised). */
typedef struct xyl__foliage_frame {
    float view_proj[16], light[3], color[4], cutoff, translucency, dither[2];
} xyl__foliage_frame;

/* The fields both renderers' public frames have, as the checks take them. */
typedef struct xyl__foliage_frame_in {
    const float *view_proj, *light_dir, *color, *dither;
    float alpha_cutoff, translucency;
} xyl__foliage_frame_in;

/* A public frame's fields (xyl_foliage_gl_frame, xyl_foliage_vk_frame: the same names). */
#define XYL__FOLIAGE_FRAME_IN(f)                                                               \
    ((xyl__foliage_frame_in){(f)->view_proj, (f)->light_dir, (f)->color, (f)->dither,         \
                             (f)->alpha_cutoff, (f)->translucency})

/* The tables of a non-NULL foliage, checked (a foliage without leaves, missing arrays, a range
 * outside the leaf array: XYL_ERR_INVALID_ARGUMENT) and copied from alloc
 * (XYL_ERR_OUT_OF_MEMORY). On failure *out is untouched. */
xyl_result xyl__foliage_tables_make(const xyl_foliage *foliage, const xyl_allocator *alloc,
                                    xyl__foliage_tables *out, xyl_diag *diag);
void xyl__foliage_tables_free(xyl__foliage_tables *t, const xyl_allocator *alloc);

/* Leaves a draw of these LODs draws. */
uint64_t xyl__foliage_tables_leaves(const xyl__foliage_tables *t, const uint32_t *lods);

/* The checks of a draw after its NULL arguments: an upload, one LOD per sector within its
 * table, then the frame's values (the fields both renderers' public frames have). */
xyl_result xyl__foliage_draw_check(const xyl__foliage_tables *t, const uint32_t *lods,
                                   size_t lod_count, const xyl__foliage_frame_in *in,
                                   xyl__foliage_frame *out, xyl_diag *diag);

/* The same without LODs, for a draw that chooses its leaves itself (the per-leaf cut): an
 * upload, then the frame's values. */
xyl_result xyl__foliage_frame_check(const xyl__foliage_tables *t,
                                    const xyl__foliage_frame_in *in, xyl__foliage_frame *out,
                                    xyl_diag *diag);

/* The frame checks alone, for a renderer without a leaf table of its own (the forest). */
xyl_result xyl__foliage_frame_resolve(const xyl__foliage_frame_in *in, xyl__foliage_frame *out,
                                      xyl_diag *diag);

/* The checks of a dither keep range: (0, 0), or finite with 0 <= lo < hi <= 1. */
xyl_result xyl__foliage_dither_check(const float dither[2], xyl_diag *diag);

/* A node of the collapse forest as foliage_cut.comp reads it (std430), for the per-leaf cut. */
typedef struct xyl__foliage_cut_node {
    float sphere[4]; /* centre, radius (xyl_foliage_cut's: the half diagonal grown by the error) */
    float error;
    int32_t parent;
    uint32_t pad[2];
} xyl__foliage_cut_node;

/* The cut's nodes of every leaf of foliage into nodes (leaf_count of them). A parent outside
 * the array or a negative or non-finite error (a foliage assembled by hand) is refused with
 * XYL_ERR_INVALID_ARGUMENT: the shader follows the parents unchecked. So is a foliage without
 * links. */
xyl_result xyl__foliage_cut_nodes(const xyl_foliage *foliage, xyl__foliage_cut_node *nodes,
                                  xyl_diag *diag);

#endif /* XYL_FOLIAGE_DRAW_H */
