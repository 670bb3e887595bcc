/* `xylem view`: the GL backend in a GLFW window. Levels are chosen for the current camera every
 * frame, as an engine would; the keys switch what the issue compares (path, handle rule, fixed
 * or adaptive levels, budget). See view_glfw.h. */
#include "view_glfw.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <epoxy/gl.h> /* before GLFW, which then leaves the GL headers alone */
#include <GLFW/glfw3.h>

#include <xylem/xyl_tess_gl.h>

#include "png_write.h"

#define PI_F 3.14159265f

typedef struct viewer {
    const xyl_view_request *req;
    GLFWwindow *window;
    xyl_tess_patterns *patterns;
    xyl_tess_patches *patches;
    xyl_tess_batches *batches;
    xyl_tess_gl *gl;
    float lo[3], hi[3];
    /* live settings */
    xyl_tess_variant variant;
    xyl_tess_path path;
    uint32_t fixed_level;
    float error_px, azimuth, elevation, zoom;
    bool wireframe, dirty_patches;
    double drag_x, drag_y;
    bool dragging;
} viewer;

static int fail(const char *what, xyl_result r, const xyl_diag *d)
{
    fprintf(stderr, "xylem: view: %s: %s: %s\n", what, xyl_result_string(r), d->message);
    return r == XYL_ERR_OUT_OF_MEMORY ? 71 : (r == XYL_ERR_UNSUPPORTED ? 69 : 65);
}

static void on_glfw_error(int code, const char *text)
{
    fprintf(stderr, "xylem: view: GLFW error %d: %s\n", code, text);
}

/* ---- input ---------------------------------------------------------------------------------- */

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode, (void)mods;
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    viewer *v = glfwGetWindowUserPointer(w);
    static const uint32_t levels[] = {0, 1, 2, 3, 4, 6, 8, 12, 16};
    switch (key) {
    case GLFW_KEY_ESCAPE: case GLFW_KEY_Q: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
    case GLFW_KEY_H:
        v->path = v->path == XYL_TESS_PATH_HARDWARE ? XYL_TESS_PATH_INSTANCED : XYL_TESS_PATH_HARDWARE;
        break;
    case GLFW_KEY_V: v->variant = (xyl_tess_variant)((v->variant + 1) % XYL_TESS_VARIANT_COUNT); v->dirty_patches = true; break;
    case GLFW_KEY_W: v->wireframe = !v->wireframe; break;
    case GLFW_KEY_L: {
        size_t i = 0;
        while (i < sizeof levels / sizeof *levels && levels[i] != v->fixed_level) ++i;
        v->fixed_level = levels[(i + 1) % (sizeof levels / sizeof *levels)];
        break;
    }
    case GLFW_KEY_EQUAL: case GLFW_KEY_KP_ADD: v->error_px = fmaxf(v->error_px * 0.5f, 1.0f / 64); break;
    case GLFW_KEY_MINUS: case GLFW_KEY_KP_SUBTRACT: v->error_px = fminf(v->error_px * 2.0f, 64.0f); break;
    case GLFW_KEY_LEFT: v->azimuth -= 0.1f; break;
    case GLFW_KEY_RIGHT: v->azimuth += 0.1f; break;
    case GLFW_KEY_UP: v->elevation = fminf(v->elevation + 0.1f, 1.5f); break;
    case GLFW_KEY_DOWN: v->elevation = fmaxf(v->elevation - 0.1f, -1.5f); break;
    default: break;
    }
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    (void)mods;
    viewer *v = glfwGetWindowUserPointer(w);
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    v->dragging = action == GLFW_PRESS;
    glfwGetCursorPos(w, &v->drag_x, &v->drag_y);
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    viewer *v = glfwGetWindowUserPointer(w);
    if (!v->dragging) return;
    v->azimuth += (float)(x - v->drag_x) * 0.01f;
    v->elevation = fmaxf(-1.5f, fminf(1.5f, v->elevation + (float)(y - v->drag_y) * 0.01f));
    v->drag_x = x, v->drag_y = y;
}

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
    (void)dx;
    viewer *v = glfwGetWindowUserPointer(w);
    v->zoom = fmaxf(0.05f, fminf(4.0f, v->zoom * (float)pow(0.9, dy)));
}

/* ---- frames --------------------------------------------------------------------------------- */

static void camera_of(const viewer *v, int width, int height, xyl_tess_camera *cam)
{
    xyl_tess_camera_frame(v->lo, v->hi, v->azimuth, v->elevation, 0.8f,
                          (float)width / (float)(height ? height : 1), cam);
    if (v->zoom != 1.0f) xyl_tess_camera_zoom(cam, v->zoom);
}

static int draw_frame(viewer *v, int width, int height)
{
    xyl_diag d = {0};
    xyl_result r = XYL_OK;
    if (v->dirty_patches) {
        xyl_tess_patches *p = NULL;
        xyl_tess_patches_desc pd = {0};
        pd.variant = v->variant;
        r = xyl_tess_patches_create(v->req->mesh, &pd, &p, &d);
        if (r == XYL_OK) r = xyl_tess_gl_set_patches(v->gl, p, &d);
        if (r != XYL_OK) return fail("patches", r, &d);
        xyl_tess_patches_destroy(v->patches);
        v->patches = p;
        v->dirty_patches = false;
    }
    xyl_tess_camera cam;
    camera_of(v, width, height, &cam);
    xyl_tess_view view = {0};
    memcpy(view.eye, cam.eye, sizeof view.eye);
    view.fovy = cam.fovy;
    view.viewport_height = (uint32_t)height;
    view.error_px = v->error_px;
    view.fixed_level = v->fixed_level;
    xyl_tess_frame f = *v->req->look;
    f.variant = (uint32_t)v->variant;
    if (v->wireframe) f.flags |= XYL_TESS_FLAG_WIREFRAME;
    r = xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, f.view_proj, &d);
    if (r == XYL_OK) r = xyl_tess_select(v->patches, v->patterns, &view, v->batches, &d);
    if (r != XYL_OK) return fail("level selection", r, &d);
    const float *bg = v->req->background;
    glViewport(0, 0, width, height);
    glClearColor(bg[0], bg[1], bg[2], bg[3]);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    r = xyl_tess_gl_draw(v->gl, v->batches, &f, v->path, &d);
    return r == XYL_OK ? 0 : fail("draw", r, &d);
}

static void show_status(viewer *v)
{
    uint32_t lo = XYL_TESS_MAX_LEVEL, hi = 0;
    for (size_t c = 0; c < v->batches->cmd_count; ++c) {
        uint32_t l = v->batches->batches[c].level;
        lo = l < lo ? l : lo;
        hi = l > hi ? l : hi;
    }
    static const char *variants[] = {"pn", "rounded", "circle", "arc"};
    char level[48], title[256];
    if (v->fixed_level) snprintf(level, sizeof level, "level %u", v->fixed_level);
    else snprintf(level, sizeof level, "%.3g px budget, levels %u..%u", v->error_px, lo, hi);
    snprintf(title, sizeof title, "xylem view - %s, %s, %s, %llu triangles, GPU %.2f ms",
             v->path == XYL_TESS_PATH_HARDWARE ? "hardware" : "instanced", variants[v->variant],
             level, (unsigned long long)v->batches->triangles, xyl_tess_gl_last_gpu_ms(v->gl));
    glfwSetWindowTitle(v->window, title);
}

int xyl_view_write_screenshot(const char *path, int width, int height)
{
    size_t row = (size_t)width * 4;
    uint8_t *rgba = malloc(row * (size_t)height), *tmp = malloc(row);
    if (!rgba || !tmp) {
        free(rgba), free(tmp);
        fprintf(stderr, "xylem: view: out of memory for the screenshot\n");
        return 71;
    }
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    for (int y = 0; y < height / 2; ++y) {
        memcpy(tmp, rgba + row * (size_t)y, row);
        memcpy(rgba + row * (size_t)y, rgba + row * (size_t)(height - 1 - y), row);
        memcpy(rgba + row * (size_t)(height - 1 - y), tmp, row);
    }
    char msg[512];
    int rc = xyl_png_write(path, rgba, (uint32_t)width, (uint32_t)height, msg, sizeof msg);
    if (rc) fprintf(stderr, "xylem: view: %s\n", msg);
    free(rgba), free(tmp);
    return rc ? 73 : 0;
}

static int loop(viewer *v)
{
    for (uint32_t n = 0; !glfwWindowShouldClose(v->window); ++n) {
        int width = 0, height = 0;
        glfwGetFramebufferSize(v->window, &width, &height);
        int rc = width > 0 && height > 0 ? draw_frame(v, width, height) : 0;
        if (rc) return rc;
        bool last = v->req->frames && n + 1 >= v->req->frames;
        if (last && v->req->screenshot) {
            rc = xyl_view_write_screenshot(v->req->screenshot, width, height);
            if (rc) return rc;
        }
        glfwSwapBuffers(v->window);
        show_status(v);
        if (last) break;
        glfwPollEvents();
    }
    return 0;
}

/* ---- setup ---------------------------------------------------------------------------------- */

static int open_window(viewer *v)
{
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
        fprintf(stderr, "xylem: view: no window system (GLFW could not start; DISPLAY unset?)\n");
        return 69;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, v->req->samples > 1 ? (int)v->req->samples : 0);
    glfwWindowHint(GLFW_RESIZABLE, v->req->frames ? GLFW_FALSE : GLFW_TRUE);
    v->window = glfwCreateWindow((int)v->req->width, (int)v->req->height, "xylem view", NULL, NULL);
    if (!v->window) {
        fprintf(stderr, "xylem: view: no OpenGL 4.5 core window\n");
        return 69;
    }
    glfwMakeContextCurrent(v->window);
    glfwSwapInterval(v->req->frames ? 0 : 1);
    glfwSetWindowUserPointer(v->window, v);
    glfwSetKeyCallback(v->window, on_key);
    glfwSetMouseButtonCallback(v->window, on_button);
    glfwSetCursorPosCallback(v->window, on_cursor);
    glfwSetScrollCallback(v->window, on_scroll);
    glEnable(GL_MULTISAMPLE);
    return 0;
}

int xyl_view_run(const xyl_view_request *req)
{
    viewer v;
    memset(&v, 0, sizeof v);
    v.req = req;
    v.variant = req->variant;
    v.path = req->path;
    v.fixed_level = req->fixed_level;
    v.error_px = req->error_px > 0 ? req->error_px : 0.5f;
    v.azimuth = req->azimuth, v.elevation = req->elevation, v.zoom = 1.0f;
    v.wireframe = req->wireframe;
    v.dirty_patches = true;
    xyl_mesh_bounds(req->mesh, v.lo, v.hi);
    xyl_diag d = {0};
    int rc = open_window(&v);
    if (!rc) {
        xyl_result r = xyl_tess_patterns_create(0, NULL, &v.patterns, &d);
        if (r == XYL_OK) r = xyl_tess_batches_create(NULL, &v.batches, &d);
        if (r == XYL_OK) r = xyl_tess_gl_create(NULL, v.patterns, &v.gl, &d);
        if (r != XYL_OK) rc = fail("GL backend", r, &d);
        else {
            GLint samples = 0;
            glGetIntegerv(GL_SAMPLES, &samples);
            printf("device: %s (OpenGL, GLFW window, %d samples per pixel)\n",
                   (const char *)glGetString(GL_RENDERER), samples > 1 ? samples : 1);
        }
    }
    if (!rc) rc = loop(&v);
    if (!rc) printf("%llu triangles in the last frame\n", (unsigned long long)v.batches->triangles);
    xyl_tess_gl_destroy(v.gl);
    xyl_tess_batches_destroy(v.batches);
    xyl_tess_patches_destroy(v.patches);
    xyl_tess_patterns_destroy(v.patterns);
    if (v.window) glfwDestroyWindow(v.window);
    glfwTerminate();
    return rc;
}
