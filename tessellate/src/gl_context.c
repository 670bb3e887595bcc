/* The optional headless GL context: EGL on Mesa's surfaceless platform, so tests and tools
 * render without a window system (llvmpipe on machines without a GPU). */
#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <stdio.h>
#include <string.h>

#include "xyl_internal.h"
#include "xylem/xyl_tess_gl.h"

struct xyl_gl_context {
    xyl_allocator alloc;
    EGLDisplay display;
    EGLContext context;
    char renderer[128];
};

static xyl_result no_egl(xyl_diag *diag, const char *what)
{
    return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "headless GL: %s (EGL error 0x%x)", what,
                     (unsigned)eglGetError());
}

/* The surfaceless platform needs no window system or device node beyond the render node (or
 * none at all for llvmpipe), which is what makes it usable in CI containers. */
static xyl_result open_display(EGLDisplay *out, xyl_diag *diag)
{
    if (!epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_base") ||
        !epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless"))
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "headless GL: EGL lacks EGL_MESA_platform_surfaceless");
    EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    if (d == EGL_NO_DISPLAY) return no_egl(diag, "no surfaceless EGL display");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(d, &major, &minor)) return no_egl(diag, "eglInitialize failed");
    if (!epoxy_has_egl_extension(d, "EGL_KHR_no_config_context") ||
        !epoxy_has_egl_extension(d, "EGL_KHR_surfaceless_context")) {
        eglTerminate(d);
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "headless GL: EGL lacks no-config or surfaceless contexts");
    }
    *out = d;
    return XYL_OK;
}

static xyl_result make_context(EGLDisplay d, EGLContext *out, xyl_diag *diag)
{
    if (!eglBindAPI(EGL_OPENGL_API)) return no_egl(diag, "EGL has no desktop OpenGL");
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext c = eglCreateContext(d, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
    if (c == EGL_NO_CONTEXT) return no_egl(diag, "no OpenGL 4.5 core context");
    if (!eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, c)) {
        xyl_result r = no_egl(diag, "eglMakeCurrent failed");
        eglDestroyContext(d, c);
        return r;
    }
    *out = c;
    return XYL_OK;
}

xyl_result xyl_gl_context_create_headless(const xyl_allocator *alloc, xyl_gl_context **out,
                                          xyl_diag *diag)
{
    if (!out) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out is required");
    xyl_allocator a = {0};
    if (alloc) a = *alloc;
    xyl_gl_context *ctx = xyl__calloc(&a, 1, sizeof *ctx);
    if (!ctx) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    ctx->alloc = a;
    xyl_result r = open_display(&ctx->display, diag);
    if (r == XYL_OK) {
        r = make_context(ctx->display, &ctx->context, diag);
        if (r != XYL_OK) eglTerminate(ctx->display);
    }
    if (r != XYL_OK) {
        xyl__free(&a, ctx);
        return r;
    }
    /* Mesa may hand out a lower version than asked for on old drivers: check what we got. */
    if (epoxy_gl_version() < 45) {
        int v = epoxy_gl_version();
        xyl_gl_context_destroy(ctx);
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "headless GL: the driver gives OpenGL %d.%d, 4.5 core is needed", v / 10,
                         v % 10);
    }
    const char *name = (const char *)glGetString(GL_RENDERER);
    snprintf(ctx->renderer, sizeof ctx->renderer, "%s", name ? name : "unknown");
    *out = ctx;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* Terminating the display also ends any other context on it (EGL displays are per process and
 * not reference counted), so use one headless context at a time. */
void xyl_gl_context_destroy(xyl_gl_context *context)
{
    if (!context) return;
    if (eglGetCurrentContext() == context->context)
        eglMakeCurrent(context->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(context->display, context->context);
    eglTerminate(context->display);
    xyl_allocator a = context->alloc;
    xyl__free(&a, context);
}

const char *xyl_gl_context_renderer(const xyl_gl_context *context)
{
    return context ? context->renderer : "";
}
