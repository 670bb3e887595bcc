/* xyl_billboard_gl.h: a whole tree (stems and leaves) as a billboard, baked by rendering the
 * tree itself into textures and drawn with OpenGL 4.5 core (docs/foliage.md, "Billboards").
 *
 * How to use
 *     // a current GL 4.5 core context, and a function that draws the whole tree into the bound
 *     // framebuffer with a given world-to-clip matrix and light (stems and leaves, depth-tested)
 *     static xyl_result draw_tree(void *user, const float view_proj[16],
 *                                 const float light_dir[3], xyl_diag *diag);
 *     xyl_billboard_gl_desc bd = {0};
 *     bd.kind = XYL_BILLBOARD_CROSS;
 *     bd.planes = 4;                              // cross only: 2..XYL_BILLBOARD_MAX_PLANES
 *     // or bd.kind = XYL_BILLBOARD_OCTAHEDRAL, bd.grid = 8: 8 x 8 views in one atlas
 *     bd.resolution = 512;                        // texels per side of each baked view
 *     memcpy(bd.lo, lo, sizeof bd.lo);            // the tree's box (stems and leaves)
 *     memcpy(bd.hi, hi, sizeof bd.hi);
 *     xyl_billboard_gl *bb = NULL;
 *     if (xyl_billboard_gl_bake(&bd, draw_tree, tree, &bb, &diag)) puts(diag.message);
 *     // each frame
 *     xyl_billboard_gl_frame fr = {0};            // view_proj, eye, light
 *     xyl_billboard_gl_draw(bb, &fr, &diag);
 *     xyl_billboard_gl_destroy(bb);
 *
 * The billboard's axis is the vertical (+Y) line through the centre of the box; its quads are
 * rectangles as high as the box and as wide as the diagonal of the box's horizontal section
 * (so the tree fits whichever way a quad turns), centred on the box's centre. Kinds:
 *   - spherical: one quad facing the eye (its up vector is world +Y made perpendicular to the
 *     line of sight), showing the one view baked from the side (+Z);
 *   - cylindrical: one quad turning about the axis to face the eye, the same +Z side view;
 *   - cross: planes vertical quads through the axis, plane k at pi * k / planes from the XY
 *     plane about +Y, each showing the orthographic view baked perpendicular to it;
 *   - octahedral (an impostor): grid x grid views from the directions of an octahedral grid
 *     over the whole sphere, baked into the cells of one atlas, drawn as one quad facing the
 *     eye that blends the three grid views around the eye's direction (below).
 * Octahedral grid: view v = column + row * grid has the point o = (2 column / (grid - 1) - 1,
 * 2 row / (grid - 1) - 1) of the square [-1, 1]^2, and the direction normalize(o.x, 1 - |o.x|
 * - |o.y|, o.y); where 1 - |o.x| - |o.y| < 0 (the lower half, folded out to the square's
 * corners) o is first replaced by ((1 - |o.y|) sign o.x, (1 - |o.x|) sign o.y). Its view is
 * an orthographic render looking at the centre of the box along minus that direction d, with
 * right = normalize(Y x d) (+X where d is vertical) and up = d x right, of the square of side
 * 2 R (R: 1.01 times the box's half diagonal) around the centre, depth over [-R, R]; it sits
 * in the atlas's cell (column, row), the atlas being grid * resolution texels wide, row 0 at
 * the bottom. Drawing, the eye's direction from the centre is encoded the same way; the grid
 * triangle around it gives three views and barycentric weights; each view is sampled where
 * the eye's ray, marched through the view's baked heights, first meets what the view saw
 * (parallax correction), relit, and the three are mixed by weight times coverage. The quad
 * is as large as the perspective outline of the sphere of radius R around the centre.
 * Each baked view is an orthographic render of the tree into a resolution x resolution RGBA8
 * colour texture stretched over the rectangle (alpha: covered or not; RGB premultiplied by
 * it, so mipmaps and filtering do not mix in the colour of empty texels) and an RGBA8 normal
 * map: the quad-space normal (x along the quad's right, y up, z towards the bake camera) in
 * RGB as n * 0.5 + 0.5, reconstructed from the bake's depth buffer by central differences,
 * and in alpha the height h towards the bake camera over the plane through the centre as
 * h / R * 0.5 + 0.5 (R: 1.01 times the box's half diagonal, every kind; 0.5 where empty). The bake lights the tree with desc->light_dir
 * (by default each view from its own camera), and the draw relights each texel with the
 * frame's light and the reconstructed normal by the ratio of the stems' shading (Lambert plus
 * a sky term) under the two lights: exactly 1 when the frame's light is the bake's. Leaves
 * (double-sided, translucent) do not shade like that, and the normals of a leaf cloud
 * reconstructed from depth are rough, so the ratio is only an approximation: baking under
 * the scene's own light is what makes a billboard as bright as its tree.
 *
 * The bake binds and clears its own framebuffer and restores the caller's framebuffer and
 * viewport; every call checks its input before its first GL call, and must come from the
 * thread where the context is current.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_BILLBOARD_GL_H
#define XYL_BILLBOARD_GL_H

#include "xylem/xyl_foliage.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The kinds and limits (XYL_BILLBOARD_*, xyl_billboard_kind) are in xylem/xyl_foliage.h,
 * shared with the Vulkan billboard (xylem/xyl_billboard_vk.h). */

/* Draws the whole tree into the bound framebuffer (its viewport already set) with this
 * column-major world-to-clip matrix (GL clip convention) and light direction (towards the
 * light, unit length). Anything but XYL_OK stops the bake and is returned as is. */
typedef xyl_result (*xyl_billboard_draw_fn)(void *user, const float view_proj[16],
                                            const float light_dir[3], xyl_diag *diag);

typedef struct xyl_billboard_gl_desc {
    xyl_billboard_kind kind;
    uint32_t planes;     /* cross: 2..XYL_BILLBOARD_MAX_PLANES; spherical, cylindrical: 0 or 1 */
    uint32_t resolution; /* texels per side of each baked view, XYL_BILLBOARD_MIN_RESOLUTION..
                            XYL_BILLBOARD_MAX_RESOLUTION (and the driver's limit) */
    uint32_t grid;       /* octahedral: views per side of the grid, XYL_BILLBOARD_MIN_GRID..
                            XYL_BILLBOARD_MAX_GRID, grid * resolution at most
                            XYL_BILLBOARD_MAX_ATLAS (and the driver's limit); 0:
                            XYL_BILLBOARD_DEFAULT_GRID. Other kinds: 0 */
    float lo[3], hi[3];  /* the tree's box, lo < hi on every axis, finite */
    float light_dir[3];  /* towards the light the views are baked under, normalised by the
                            call; default (all 0): each view's own camera direction. Give the
                            scene's light: a draw under the same light then shows the tree's
                            own shading (leaves' translucency included) unchanged */
    xyl_allocator alloc; /* every host allocation, as long as the billboard lives */
} xyl_billboard_gl_desc;

typedef struct xyl_billboard_gl xyl_billboard_gl;

/* The uniforms of a draw. */
typedef struct xyl_billboard_gl_frame {
    float view_proj[16]; /* column-major world-to-clip matrix (GL clip convention); all 0 refused */
    float eye[3];        /* the camera's position: spherical and cylindrical quads face it */
    float light_dir[3];  /* towards the light, normalised by the call; default (all 0): +Y */
    float alpha_cutoff;  /* texels with alpha below it are discarded, (0, 1]; default (0): 0.5.
                            Into a multisampled framebuffer the filtered alpha goes to
                            alpha-to-coverage instead (the share of samples covered) */
    float dither[2];     /* keep range [lo, hi) of the screen-door dither that cross-fades the
                            billboard with the tree (docs/foliage.md, "Transitions";
                            xyl_fade_update gives it); default (0, 0): every fragment; otherwise
                            0 <= lo < hi <= 1 */
} xyl_billboard_gl_frame;

/* Bakes the billboard: one view (spherical, cylindrical), desc->planes views (cross) or grid^2
 * views (octahedral), each a call of draw into an offscreen resolution x resolution target.
 * Errors: XYL_ERR_INVALID_ARGUMENT (NULL desc, draw or out, an unknown kind, planes out of
 * range for the kind, a resolution out of range, a grid out of range or given to another
 * kind, an atlas wider than the limits, an empty or inverted box), XYL_ERR_NON_FINITE (a box
 * coordinate), XYL_ERR_UNSUPPORTED (no current GL 4.5 core context, a shader that does not
 * compile or link, an incomplete framebuffer), XYL_ERR_OUT_OF_MEMORY (host or GL), whatever
 * draw returns. On failure *out is untouched and nothing is left behind. */
XYL_API xyl_result xyl_billboard_gl_bake(const xyl_billboard_gl_desc *desc,
                                         xyl_billboard_draw_fn draw, void *user,
                                         xyl_billboard_gl **out, xyl_diag *diag);
/* NULL is fine. Deletes its GL objects when a context is current (else they died with it). */
XYL_API void xyl_billboard_gl_destroy(xyl_billboard_gl *bb);

/* How many views were baked: 1, the cross's planes, or grid^2. 0 for NULL. */
XYL_API uint32_t xyl_billboard_gl_view_count(const xyl_billboard_gl *bb);

/* A baked view read back: colour (normal false; premultiplied by alpha) or normal map (normal
 * true; height in alpha), resolution * resolution RGBA8 texels, top row first, into rgba
 * (4 * resolution^2 bytes). Errors:
 * XYL_ERR_INVALID_ARGUMENT (NULL bb or rgba, view >= xyl_billboard_gl_view_count). */
XYL_API xyl_result xyl_billboard_gl_read_view(const xyl_billboard_gl *bb, uint32_t view,
                                              bool normal, uint8_t *rgba, xyl_diag *diag);

/* Draws the billboard into the bound framebuffer with the current viewport: depth test
 * (GL_LESS) and writes on, no face culling (restored), no blending, alpha test at the frame's
 * cutoff, or in a multisampled framebuffer (GL_SAMPLE_BUFFERS) alpha-to-coverage and
 * alpha-to-one (restored). Errors: XYL_ERR_INVALID_ARGUMENT (NULL bb or frame, an all-zero
 * matrix, a cutoff outside [0, 1], a dither range other than (0, 0) outside
 * 0 <= lo < hi <= 1), XYL_ERR_NON_FINITE (a matrix, eye, light or dither entry),
 * XYL_ERR_OUT_OF_MEMORY
 * (GL_OUT_OF_MEMORY). */
XYL_API xyl_result xyl_billboard_gl_draw(xyl_billboard_gl *bb,
                                         const xyl_billboard_gl_frame *frame, xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif /* XYL_BILLBOARD_GL_H */
