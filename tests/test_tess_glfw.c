/* tessellate/'s GL backend in a GLFW window (the windowed path; under Xvfb in ctest): what
 * xyl_tess_gl_draw puts into the window's own framebuffer equals what the offscreen renderer
 * makes of the same batches in the same context, for both paths, with and without the wireframe
 * overlay, and the draw leaves the caller's framebuffer binding and viewport alone. The
 * hardware path's overlay covers as many pixels as the instanced one's. */
#include <epoxy/gl.h>
#include <GLFW/glfw3.h>

#include "test_util.h"
#include "tess_util.h"
#include <xylem/xyl_tess_gl.h>

#define SIDE 192

typedef struct suite {
    GLFWwindow *window;
    xyl_tess_patterns *pat;
    xyl_tess_gl *gl;
    xyl_mesh *mesh;
    xyl_tess_patches *patches;
    xyl_tess_batches *batches;
    xyl_tess_frame frame;
    uint8_t *window_rgba, *offscreen_rgba;
} suite;

static void on_error(int code, const char *text)
{
    print_error("GLFW error %d: %s\n", code, text);
}

static GLFWwindow *open_window(void)
{
    glfwSetErrorCallback(on_error);
    if (!glfwInit()) return NULL;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, 0);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    GLFWwindow *w = glfwCreateWindow(SIDE, SIDE, "test_tess_glfw", NULL, NULL);
    if (w) glfwMakeContextCurrent(w);
    return w;
}

/* The default tree framed from the side, adaptive levels for a 192-pixel view. */
static void make_scene(suite *s)
{
    s->mesh = tu_tree_mesh(0, 4, XYL_SUBDIVIDE_NONE);
    assert_int_equal(xyl_tess_patches_create(s->mesh, NULL, &s->patches, NULL), XYL_OK);
    assert_int_equal(xyl_tess_gl_set_patches(s->gl, s->patches, NULL), XYL_OK);
    float lo[3], hi[3];
    xyl_mesh_bounds(s->mesh, lo, hi);
    xyl_tess_camera cam;
    xyl_tess_camera_frame(lo, hi, 0.5f, 0.2f, 0.8f, 1.0f, &cam);
    memset(&s->frame, 0, sizeof s->frame);
    assert_int_equal(xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, s->frame.view_proj, NULL), XYL_OK);
    s->frame.light_dir[1] = 1.0f;
    s->frame.color[0] = 0.5f, s->frame.color[1] = 0.4f, s->frame.color[2] = 0.3f, s->frame.color[3] = 1;
    s->frame.line_color[3] = 1.0f;
    xyl_tess_view view = {0};
    memcpy(view.eye, cam.eye, sizeof view.eye);
    view.fovy = cam.fovy;
    view.viewport_height = SIDE;
    s->batches = tu_batches_create();
    assert_int_equal(xyl_tess_select(s->patches, s->pat, &view, s->batches, NULL), XYL_OK);
    assert_true(s->batches->cmd_count >= 2); /* several levels */
}

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    if (!s) return -1;
    s->window = open_window();
    xyl_diag d = {0};
    if (!s->window || xyl_tess_patterns_create(16, NULL, &s->pat, &d) != XYL_OK ||
        xyl_tess_gl_create(NULL, s->pat, &s->gl, &d) != XYL_OK) {
        print_error("setup failed (a window needs a display: ctest runs this under xvfb-run): %s\n",
                    d.message);
        return -1;
    }
    s->window_rgba = malloc(4u * SIDE * SIDE);
    s->offscreen_rgba = malloc(4u * SIDE * SIDE);
    *state = s;
    make_scene(s);
    return 0;
}

static int teardown(void **state)
{
    suite *s = *state;
    xyl_tess_batches_destroy(s->batches);
    xyl_tess_patches_destroy(s->patches);
    xyl_mesh_destroy(s->mesh);
    xyl_tess_gl_destroy(s->gl);
    xyl_tess_patterns_destroy(s->pat);
    glfwDestroyWindow(s->window);
    glfwTerminate();
    free(s->window_rgba);
    free(s->offscreen_rgba);
    free(s);
    return 0;
}

/* Draws into the window's back buffer and reads it back, top row first. */
static void draw_in_window(suite *s, const xyl_tess_frame *f, xyl_tess_path path)
{
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, SIDE, SIDE);
    glClearColor(0.2f, 0.3f, 0.4f, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    xyl_diag d = {0};
    if (xyl_tess_gl_draw(s->gl, s->batches, f, path, &d) != XYL_OK) fail_msg("draw: %s", d.message);
    GLint fbo = -1, vp[4] = {0};
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fbo);
    glGetIntegerv(GL_VIEWPORT, vp);
    assert_int_equal(fbo, 0);
    assert_int_equal(vp[2], SIDE);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, SIDE, SIDE, GL_RGBA, GL_UNSIGNED_BYTE, s->window_rgba);
    assert_int_equal(glGetError(), GL_NO_ERROR);
    glfwSwapBuffers(s->window);
    size_t row = 4u * SIDE;
    uint8_t tmp[4u * SIDE];
    for (size_t y = 0; y < SIDE / 2; ++y) {
        memcpy(tmp, s->window_rgba + row * y, row);
        memcpy(s->window_rgba + row * y, s->window_rgba + row * (SIDE - 1 - y), row);
        memcpy(s->window_rgba + row * (SIDE - 1 - y), tmp, row);
    }
}

static void window_draw_matches_offscreen_render(void **state)
{
    suite *s = *state;
    xyl_tess_image_desc img = {0};
    img.width = img.height = SIDE;
    img.background[0] = 0.2f, img.background[1] = 0.3f, img.background[2] = 0.4f;
    img.background[3] = 1.0f;
    img.samples = 1;
    size_t instanced_lines = 0;
    for (int path = 0; path < 2; ++path)
        for (int wire = 0; wire < 2; ++wire) {
            xyl_tess_frame f = s->frame;
            if (wire) f.flags |= XYL_TESS_FLAG_WIREFRAME;
            draw_in_window(s, &f, (xyl_tess_path)path);
            img.wireframe = wire != 0;
            xyl_diag d = {0};
            if (xyl_tess_gl_render_rgba(s->gl, s->batches, &s->frame, (xyl_tess_path)path, &img,
                                        s->offscreen_rgba, &d) != XYL_OK)
                fail_msg("render: %s", d.message);
            size_t differ = 0, covered = 0, dark = 0;
            for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) {
                const uint8_t *a = s->window_rgba + 4 * i, *b = s->offscreen_rgba + 4 * i;
                int worst = 0;
                for (int k = 0; k < 3; ++k) worst = abs(a[k] - b[k]) > worst ? abs(a[k] - b[k]) : worst;
                differ += worst > 1;
                covered += a[2] != 102; /* not the background's blue, 0.4 * 255 */
                dark += a[0] == 0 && a[1] == 0 && a[2] == 0;
            }
            print_message("%s%s: %zu pixels covered, %zu line pixels, %zu differ from offscreen\n",
                          path ? "hardware" : "instanced", wire ? " + wireframe" : "", covered,
                          dark, differ);
            assert_true(covered > 500);          /* the tree is in the picture */
            assert_true(wire ? dark > 100 : dark == 0);
            assert_int_equal(differ, 0);
            /* the two paths triangulate differently but cover the same edges: stray lines
             * (llvmpipe's line mode after tessellation) would multiply the count */
            if (wire && !path) instanced_lines = dark;
            if (wire && path) assert_true(dark < instanced_lines * 5 / 4 && dark > instanced_lines * 3 / 4);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(window_draw_matches_offscreen_render),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
