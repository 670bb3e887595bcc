/* A procedural leaf texture: an RGBA8 image of one green blade whose alpha is its shape, for the
 * leaf quads of xyl_foliage (docs/foliage.md, "Export"). Shared by the CLI and any renderer that
 * wants the same look. */
#ifndef XYL_SAMPLES_LEAF_TEXTURE_H
#define XYL_SAMPLES_LEAF_TEXTURE_H

#include <stddef.h>
#include <stdint.h>

#define XYL_LEAF_TEXTURE_WIDTH 128
#define XYL_LEAF_TEXTURE_HEIGHT 256

/* Fills rgba (width * height * 4 bytes, rows top to bottom) with the leaf: the stalk end at the
 * bottom row, the tip at the top, the blade filling the width at its widest; alpha 0 outside it,
 * 255 inside, one pixel of smooth edge between. Colour: a green blade, lighter along the midrib
 * and side veins. Deterministic; any size from 8 x 8. */
void xyl_leaf_texture(uint8_t *rgba, uint32_t width, uint32_t height);

#endif
