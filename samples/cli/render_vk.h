/* xylem render --backend vulkan with leaves: stems (xyl_tess_vk) and leaves (xyl_foliage_vk)
 * recorded into one command buffer on the CLI's own Vulkan device, as an engine records them
 * into its own frame. */
#ifndef XYL_SAMPLES_RENDER_VK_H
#define XYL_SAMPLES_RENDER_VK_H

#include <xylem/xyl_foliage.h>
#include <xylem/xyl_tessellate.h>

/* The tree's billboard (xyl_billboard_vk.h), baked from its stems and leaves. */
typedef struct xyl_cli_vk_billboard {
    int kind;                  /* an xyl_billboard_kind */
    uint32_t planes, grid;     /* the cross's planes, the octahedral grid (0: default) */
    uint32_t resolution;       /* texels per baked view */
    float lo[3], hi[3];        /* the tree's box */
    float eye[3];              /* the camera's position */
    double bake_ms;            /* out: the bake's wall time */
    uint32_t views;            /* out: the views baked */
} xyl_cli_vk_billboard;

typedef struct xyl_cli_vk_tree {
    const xyl_tess_patterns *patterns;
    const xyl_tess_patches *patches;
    const xyl_tess_batches *batches;
    xyl_tess_frame frame;        /* view_proj: Vulkan's clip convention */
    const xyl_tess_image_desc *image;
    const xyl_foliage *foliage;
    const uint32_t *lods;        /* one per sector, or NULL: the per-leaf cut for cut_view */
    const xyl_foliage_view *cut_view;
    size_t *cut_leaves;          /* with the cut: the leaves the GPU's cut drew */
    const uint8_t *leaf_texture; /* RGBA8, top row first */
    uint32_t texture_width, texture_height;
    xyl_cli_vk_billboard *billboard; /* non-NULL: the billboard drawn in the tree's place */
} xyl_cli_vk_tree;

/* Draws the stems, then the leaves (the two-range LODs, or the per-leaf cut recorded before
 * the render pass and drawn inside it), or with tree->billboard the billboard baked from them
 * (by renderers made for the bake's single-sample pass) in their place, into a colour (R8G8B8A8, image->samples) and depth target
 * cleared to image->background, resolves it, and writes width * height RGBA8 pixels, top row
 * first. device_name (at least 256 bytes) gets the device's name, *gpu_ms the render pass's GPU
 * time from timestamp queries (negative where the queue has none). Errors: the libraries' codes;
 * XYL_ERR_UNSUPPORTED for a machine without a fitting Vulkan 1.2 device (diag says why). */
xyl_result xyl_cli_render_vk_tree(const xyl_cli_vk_tree *tree, uint8_t *rgba, char *device_name,
                                  double *gpu_ms, xyl_diag *diag);

#endif
