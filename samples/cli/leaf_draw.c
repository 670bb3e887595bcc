/* The leaves beside the stems in the samples' GL windows (leaf_draw.h). */
#include "leaf_draw.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef XYL_HAVE_GL
#include <epoxy/gl.h>
#include <xylem/xyl_foliage_gl.h>
#endif

#include "leaf_texture.h"

#ifdef XYL_HAVE_GL
xyl_result leaf_draw_create(xyl_foliage_gl **out, xyl_diag *d)
{
    *out = NULL;
    uint32_t w = XYL_LEAF_TEXTURE_WIDTH, h = XYL_LEAF_TEXTURE_HEIGHT;
    uint8_t *tex = malloc((size_t)w * h * 4);
    if (!tex) {
        snprintf(d->message, sizeof d->message, "out of memory for the %ux%u leaf texture", w, h);
        return XYL_ERR_OUT_OF_MEMORY;
    }
    xyl_leaf_texture(tex, w, h);
    xyl_foliage_gl *gl = NULL;
    xyl_result r = xyl_foliage_gl_create(NULL, &gl, d);
    if (r == XYL_OK) r = xyl_foliage_gl_set_texture(gl, tex, w, h, d);
    free(tex);
    if (r != XYL_OK) {
        xyl_foliage_gl_destroy(gl);
        return r;
    }
    *out = gl;
    return XYL_OK;
}

void leaf_draw_target_free(leaf_draw_target *t)
{
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &t->fbo);
    glDeleteFramebuffers(1, &t->resolve_fbo);
    glDeleteRenderbuffers(2, t->rb);
    glDeleteRenderbuffers(1, &t->resolve_rb);
    memset(t, 0, sizeof *t);
}

xyl_result leaf_draw_target_make(leaf_draw_target *t, uint32_t width, uint32_t height,
                                 uint32_t samples, xyl_diag *d)
{
    memset(t, 0, sizeof *t);
    GLint max_samples = 1;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    if (samples > (uint32_t)max_samples) {
        snprintf(d->message, sizeof d->message, "%u samples asked, the driver has %d", samples,
                 max_samples);
        return XYL_ERR_UNSUPPORTED;
    }
    GLsizei n = samples > 1 ? (GLsizei)samples : 0, w = (GLsizei)width, h = (GLsizei)height;
    glCreateRenderbuffers(2, t->rb);
    glNamedRenderbufferStorageMultisample(t->rb[0], n, GL_RGBA8, w, h);
    glNamedRenderbufferStorageMultisample(t->rb[1], n, GL_DEPTH_COMPONENT24, w, h);
    glCreateFramebuffers(1, &t->fbo);
    glNamedFramebufferRenderbuffer(t->fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t->rb[0]);
    glNamedFramebufferRenderbuffer(t->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->rb[1]);
    glCreateRenderbuffers(1, &t->resolve_rb);
    glNamedRenderbufferStorage(t->resolve_rb, GL_RGBA8, w, h);
    glCreateFramebuffers(1, &t->resolve_fbo);
    glNamedFramebufferRenderbuffer(t->resolve_fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                   t->resolve_rb);
    if (glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE ||
        glCheckNamedFramebufferStatus(t->resolve_fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE ||
        glGetError() != GL_NO_ERROR) {
        snprintf(d->message, sizeof d->message, "a %ux%u framebuffer with %u samples is incomplete",
                 width, height, samples);
        leaf_draw_target_free(t);
        return XYL_ERR_UNSUPPORTED;
    }
    t->width = width, t->height = height;
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glViewport(0, 0, w, h);
    return XYL_OK;
}

void leaf_draw_target_read(const leaf_draw_target *t, uint8_t *rgba)
{
    GLint w = (GLint)t->width, h = (GLint)t->height;
    glBlitNamedFramebuffer(t->fbo, t->resolve_fbo, 0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT,
                           GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t->resolve_fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t->fbo);
    size_t row = 4u * (size_t)w; /* GL's rows run bottom to top */
    for (GLint y = 0; y < h / 2; ++y) {
        uint8_t *a = rgba + (size_t)y * row, *b = rgba + (size_t)(h - 1 - y) * row;
        for (size_t i = 0; i < row; ++i) {
            uint8_t c = a[i];
            a[i] = b[i];
            b[i] = c;
        }
    }
}
#endif

xyl_result leaf_draw_pick(const xyl_foliage *f, bool full, const xyl_tess_camera *cam,
                          uint32_t viewport_height, float error_px, uint32_t *lods,
                          size_t lod_cap, leaf_draw_pick_info *info, xyl_diag *d)
{
    if (!f || f->original_count == 0) {
        snprintf(d->message, sizeof d->message, "no leaves to draw");
        return XYL_ERR_INVALID_ARGUMENT;
    }
    if (f->sector_count > lod_cap) {
        snprintf(d->message, sizeof d->message, "%u sectors, room for %zu LODs", f->sector_count,
                 lod_cap);
        return XYL_ERR_INVALID_ARGUMENT;
    }
    xyl_result r = XYL_OK;
    if (full) {
        memset(lods, 0, f->sector_count * sizeof *lods);
    } else {
        xyl_foliage_view v = {0};
        memcpy(v.eye, cam->eye, sizeof v.eye);
        v.fovy = cam->fovy;
        v.viewport_height = viewport_height;
        v.error_px = error_px;
        r = xyl_foliage_pick(f, &v, lods, lod_cap, d);
    }
    size_t drawn = 0;
    if (r == XYL_OK) r = xyl_foliage_gather(f, lods, f->sector_count, NULL, 0, &drawn, d);
    if (r != XYL_OK) return r;
    memset(info, 0, sizeof *info);
    info->drawn = drawn;
    info->original = f->original_count;
    info->lod_lo = UINT32_MAX;
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        info->lod_lo = lods[s] < info->lod_lo ? lods[s] : info->lod_lo;
        info->lod_hi = lods[s] > info->lod_hi ? lods[s] : info->lod_hi;
        info->lod_top = sec->merged_count > info->lod_top ? sec->merged_count : info->lod_top;
        info->error = fmaxf(info->error, sec->lods[lods[s]].error);
    }
    return XYL_OK;
}
