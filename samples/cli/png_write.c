#define _POSIX_C_SOURCE 200809L
#include "png_write.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
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

int xyl_png_write(const char *path, const uint8_t *rgba, uint32_t width, uint32_t height,
                  char *msg, size_t msg_size)
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
    int bad = !f || encode(f, rgba, width, height) != 0;
    int e = bad ? (errno ? errno : EIO) : 0;
    if (f && fflush(f) != 0 && !bad) bad = 1, e = errno;
    if (f && !bad) { /* mkstemp makes 0600 files; give the image the usual permissions */
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
