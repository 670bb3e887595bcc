/* Internal to foliage/ and its tests: the leaf renderer's vertices read back, so tests compare
 * the clip-space corners the GPU computes with a CPU reference. Not installed, not API. */
#ifndef XYL_FOLIAGE_GL_DEBUG_H
#define XYL_FOLIAGE_GL_DEBUG_H

#include "xylem/xyl_foliage_gl.h"

/* One vertex of a drawn triangle as transform feedback wrote it: gl_Position, the corner
 * (s, t) in {-1, 1}^2 it belongs to, and the record (index into the whole leaf array). */
typedef struct xyl__foliage_captured {
    float clip[4];
    float st[2];
    uint32_t leaf;
} xyl__foliage_captured;

/* Runs the draw of xyl_foliage_gl_draw with the rasterizer off and transform feedback on:
 * every triangle of every leaf strip (two a leaf, three vertices each, in draw order), the
 * first `capacity` vertices into out, the total into *count, and the primitives the GL counted
 * (GL_PRIMITIVES_GENERATED) into *generated. Errors as xyl_foliage_gl_draw, and
 * XYL_ERR_LIMIT_EXCEEDED (a read-back over 2 GiB), XYL_ERR_UNSUPPORTED (feedback wrote fewer
 * triangles than were generated). */
xyl_result xyl__foliage_gl_capture(xyl_foliage_gl *gl, const xyl_foliage_gl_frame *frame,
                                   const uint32_t *lods, size_t lod_count,
                                   xyl__foliage_captured *out, size_t capacity, size_t *count,
                                   uint64_t *generated, xyl_diag *diag);

#endif /* XYL_FOLIAGE_GL_DEBUG_H */
