/* xyl_dither.h: the screen-door dither that cross-fades two levels of detail without blending
 * (docs/foliage.md, "Transitions"), read by C and GLSL like the other shared headers.
 *
 * A draw keeps the fragments whose threshold lies in its keep range [lo, hi): the threshold of
 * pixel (x, y) is (B(x mod 8, y mod 8) + 0.5) / 64, B the 8 x 8 Bayer matrix (every value 0..63
 * once in each 8 x 8 block, spread so that any run of consecutive values is spread evenly over
 * the block). Two draws with the ranges [0, t) and [t, 1) cover every pixel exactly once between
 * them: no pixel shows both or neither, and each shows a share t and 1 - t of the screen. The
 * range (0, 0) keeps every fragment (the default of a zeroed frame).
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_DITHER_H
#define XYL_DITHER_H

#define XYL_DITHER_SIDE 8u

#ifdef XYL_GLSL

/* B(x, y) of the 8 x 8 Bayer matrix: per bit level i the 2 x 2 pattern (0 2 / 3 1) of bit i of
 * x and y, weighted 4^(2 - i). */
float xyl_dither_threshold(vec2 frag)
{
    uvec2 p = uvec2(frag) & 7u;
    uint b = 0u;
    for (uint i = 0u; i < 3u; ++i) {
        uint bx = (p.x >> i) & 1u, by = (p.y >> i) & 1u;
        b += (2u * (bx ^ by) + by) << (2u * (2u - i));
    }
    return (float(b) + 0.5) / 64.0;
}

bool xyl_dither_keeps(vec2 frag, vec2 keep)
{
    if (keep.x == 0.0 && keep.y == 0.0) return true;
    float t = xyl_dither_threshold(frag);
    return t >= keep.x && t < keep.y;
}

#else /* C */

#include <stdint.h>

/* The same threshold on the CPU, for tests and references. */
static inline float xyl_dither_threshold(uint32_t x, uint32_t y)
{
    uint32_t b = 0;
    for (uint32_t i = 0; i < 3; ++i) {
        uint32_t bx = (x >> i) & 1u, by = (y >> i) & 1u;
        b += (2u * (bx ^ by) + by) << (2u * (2u - i));
    }
    return ((float)b + 0.5f) / 64.0f;
}

#endif

#endif /* XYL_DITHER_H */
