#define _POSIX_C_SOURCE 200809L
#include "png_write.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int encode(FILE *f, const uint8_t *rgba, uint32_t w, uint32_t h)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, w, h, 8, PNG_COLOR_TYPE_RGB_ALPHA, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (uint32_t y = 0; y < h; ++y) png_write_row(png, rgba + (size_t)y * w * 4);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return 0;
}

typedef int (*fill_fn)(FILE *f, const void *ctx);

/* Writes through fill into a temporary file next to path, then renames it over path. */
static int write_atomic(const char *path, fill_fn fill, const void *ctx, char *msg,
                        size_t msg_size)
{
    size_t n = strlen(path) + 16;
    char *tmp = malloc(n);
    if (!tmp) return snprintf(msg, msg_size, "out of memory"), ENOMEM;
    snprintf(tmp, n, "%s.tmp-XXXXXX", path);
    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        snprintf(msg, msg_size, "cannot create a file next to %s: %s", path, strerror(e));
        free(tmp);
        return e;
    }
    FILE *f = fdopen(fd, "wb");
    errno = 0;
    int bad = !f || fill(f, ctx) != 0;
    int e = bad ? (errno ? errno : EIO) : 0;
    if (f && fflush(f) != 0 && !bad) bad = 1, e = errno;
    if (f && !bad) { /* mkstemp makes 0600 files; give the file the usual permissions */
        mode_t mask = umask(0);
        umask(mask);
        if (fchmod(fileno(f), 0666 & ~mask) != 0) bad = 1, e = errno;
    }
    if (f && !bad && fsync(fileno(f)) != 0) bad = 1, e = errno;
    if (f) fclose(f); else close(fd);
    if (!bad && rename(tmp, path) != 0) bad = 1, e = errno;
    if (bad) {
        unlink(tmp);
        snprintf(msg, msg_size, "cannot write %s: %s", path, strerror(e));
    }
    free(tmp);
    return bad ? e : 0;
}

typedef struct image {
    const uint8_t *rgba;
    uint32_t width, height;
} image;

static int fill_png(FILE *f, const void *ctx)
{
    const image *im = ctx;
    return encode(f, im->rgba, im->width, im->height);
}

int xyl_png_write(const char *path, const uint8_t *rgba, uint32_t width, uint32_t height,
                  char *msg, size_t msg_size)
{
    image im = {rgba, width, height};
    return write_atomic(path, fill_png, &im, msg, msg_size);
}

typedef struct bytes {
    const void *data;
    size_t size;
} bytes;

static int fill_bytes(FILE *f, const void *ctx)
{
    const bytes *b = ctx;
    return b->size && fwrite(b->data, 1, b->size, f) != b->size ? -1 : 0;
}

int xyl_write_file_atomic(const char *path, const void *data, size_t size, char *msg,
                          size_t msg_size)
{
    bytes b = {data, size};
    return write_atomic(path, fill_bytes, &b, msg, msg_size);
}

int xyl_png_encode(const uint8_t *rgba, uint32_t width, uint32_t height, unsigned char **png,
                   size_t *size, char *msg, size_t msg_size)
{
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = width;
    im.height = height;
    im.format = PNG_FORMAT_RGBA;
    png_alloc_size_t n = 0;
    *png = NULL;
    bool sized = png_image_write_get_memory_size(im, n, 0, rgba, 0, NULL);
    if (sized) *png = malloc(n);
    if (!*png || !png_image_write_to_memory(&im, *png, &n, 0, rgba, 0, NULL)) {
        bool oom = sized && !*png;
        snprintf(msg, msg_size, "cannot encode a %ux%u PNG: %s", (unsigned)width,
                 (unsigned)height, oom ? "out of memory" : im.message);
        free(*png);
        *png = NULL;
        png_image_free(&im);
        return oom ? ENOMEM : EINVAL;
    }
    *size = (size_t)n;
    return 0;
}
