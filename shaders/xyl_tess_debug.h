/* xyl_tess_debug.h: debug views of the fragment shader, read by C (tessellate/src/tess_debug.h)
 * and GLSL like xyl_tess_shared.h, but not installed: they use xyl_tess_frame.flags bits the
 * public header leaves reserved, and only the library's tests set them.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_TESS_DEBUG_H
#define XYL_TESS_DEBUG_H

/* Back-facing fragments are pure red and nothing is culled (GL: back faces in a second pass
 * behind the front ones): on a closed surface a back face shows only through a crack. */
#define XYL__TESS_FLAG_BACKFACES 4u

#endif /* XYL_TESS_DEBUG_H */
