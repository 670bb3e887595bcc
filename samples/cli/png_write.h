/* Writes RGBA8 images as PNG through libpng, atomically (temporary file, then rename), and
 * encodes them in memory. */
#ifndef XYL_SAMPLES_PNG_WRITE_H
#define XYL_SAMPLES_PNG_WRITE_H

#include <stddef.h>
#include <stdint.h>

/* 0 on success; otherwise errno-style failure with a message in msg (size msg_size). */
int xyl_png_write(const char *path, const uint8_t *rgba, uint32_t width, uint32_t height,
                  char *msg, size_t msg_size);

/* The PNG of an RGBA8 image in *png (malloc; the caller frees it), *size bytes. 0 on success;
 * otherwise an errno-style failure with a message in msg. */
int xyl_png_encode(const uint8_t *rgba, uint32_t width, uint32_t height, unsigned char **png,
                   size_t *size, char *msg, size_t msg_size);

/* Any bytes to path the same atomic way: path is the old file or the whole new one. */
int xyl_write_file_atomic(const char *path, const void *data, size_t size, char *msg,
                          size_t msg_size);

#endif
