/* Writes RGBA8 images as PNG through libpng, atomically (temporary file, then rename). */
#ifndef XYL_SAMPLES_PNG_WRITE_H
#define XYL_SAMPLES_PNG_WRITE_H

#include <stddef.h>
#include <stdint.h>

/* 0 on success; otherwise errno-style failure with a message in msg (size msg_size). */
int xyl_png_write(const char *path, const uint8_t *rgba, uint32_t width, uint32_t height,
                  char *msg, size_t msg_size);

#endif
