/* `xylem view` with the tuning panel (view_tuner.h). The main thread owns the window, GL and the
 * panel; the worker (view_regrow.c) grows trees. A new tree is adopted at the start of a frame:
 * its patch records and its leaves are uploaded here, never on the worker. */
#define _POSIX_C_SOURCE 200809L

#include "view_tuner.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <epoxy/gl.h> /* before GLFW, which then leaves the GL headers alone */
#include <GLFW/glfw3.h>

#include <xylem/xyl_foliage.h>
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_tess_gl.h>

#include "leaf_draw.h"
#include "leaf_texture.h"
#include "png_write.h"
#include "view_glfw.h"
#include "view_panel.h"
#include "view_regrow.h"

typedef struct tuner {
    const xyl_tune_request *req;
    GLFWwindow *window;
    view_params p;
    view_regrow *worker;
    view_tree *tree;                    /* the tree on screen (NULL before the first good one) */
    const xyl_tess_patches *uploaded;
    xyl_tess_patterns *patterns;
    xyl_tess_batches *batches;
    xyl_tess_gl *gl;
    xyl_foliage_gl *leaf_gl;
    const xyl_foliage *leaf_uploaded;   /* the foliage in leaf_gl: the tree's, or NULL */
    uint32_t lods[LEAF_DRAW_MAX_SECTORS];
    float lo[3], hi[3];                 /* the stems' box */
    float leaf_lo[3], leaf_hi[3];       /* the stems' and the leaves' */
    bool dragging;
    double drag_x, drag_y;
    int tree_x, tree_w, tree_h;         /* the tree's viewport (right of the panel) */
    view_panel_info info;
    char note[640];
    char leaf_note[320];                /* why the leaves are not drawn, when they are not */
    char renderer[256];
} tuner;

static int fail(const char *what, xyl_result r, const xyl_diag *d)
{
    fprintf(stderr, "xylem: view: %s: %s: %s\n", what, xyl_result_string(r), d->message);
    return r == XYL_ERR_OUT_OF_MEMORY ? 71 : (r == XYL_ERR_UNSUPPORTED ? 69 : 65);
}

static void on_glfw_error(int code, const char *text)
{
    fprintf(stderr, "xylem: view: GLFW error %d: %s\n", code, text);
}

static void regrow(tuner *t)
{
    if (!view_regrow_submit(t->worker, &t->p))
        snprintf(t->note, sizeof t->note, "out of memory: the change was not sent to the worker");
}

/* ---- input: the keys of the plain viewer, when the panel does not take them ------------------ */

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode, (void)mods;
    if ((action != GLFW_PRESS && action != GLFW_REPEAT) || view_panel_wants_keyboard()) return;
    tuner *t = glfwGetWindowUserPointer(w);
    view_params *p = &t->p;
    static const uint32_t levels[] = {0, 1, 2, 3, 4, 6, 8, 12, 16};
    switch (key) {
    case GLFW_KEY_ESCAPE: case GLFW_KEY_Q: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
    case GLFW_KEY_H:
        p->path = p->path == XYL_TESS_PATH_HARDWARE ? XYL_TESS_PATH_INSTANCED : XYL_TESS_PATH_HARDWARE;
        break;
    case GLFW_KEY_V: p->variant = (xyl_tess_variant)((p->variant + 1) % XYL_TESS_VARIANT_COUNT); regrow(t); break;
    case GLFW_KEY_W: p->wireframe = !p->wireframe; break;
    case GLFW_KEY_P: p->panel = !p->panel; break;
    case GLFW_KEY_F: /* the leaf draw: lod, full, none; drawing them builds them */
        p->leaf_draw = (view_leaf_draw)((p->leaf_draw + 1) % 3);
        if (p->leaf_draw != VIEW_LEAVES_NONE && !p->leaves) p->leaves = true, regrow(t);
        break;
    case GLFW_KEY_L: {
        size_t i = 0;
        while (i < sizeof levels / sizeof *levels && levels[i] != p->level) ++i;
        p->level = levels[(i + 1) % (sizeof levels / sizeof *levels)];
        break;
    }
    case GLFW_KEY_EQUAL: case GLFW_KEY_KP_ADD: p->error_px = fmaxf(p->error_px * 0.5f, 1.0f / 64); break;
    case GLFW_KEY_MINUS: case GLFW_KEY_KP_SUBTRACT: p->error_px = fminf(p->error_px * 2.0f, 64.0f); break;
    case GLFW_KEY_LEFT: p->azimuth -= 0.1f; break;
    case GLFW_KEY_RIGHT: p->azimuth += 0.1f; break;
    case GLFW_KEY_UP: p->elevation = fminf(p->elevation + 0.1f, 1.5f); break;
    case GLFW_KEY_DOWN: p->elevation = fmaxf(p->elevation - 0.1f, -1.5f); break;
    default: break;
    }
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    (void)mods;
    tuner *t = glfwGetWindowUserPointer(w);
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    t->dragging = action == GLFW_PRESS && !view_panel_wants_mouse();
    glfwGetCursorPos(w, &t->drag_x, &t->drag_y);
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    tuner *t = glfwGetWindowUserPointer(w);
    if (!t->dragging) return;
    t->p.azimuth += (float)(x - t->drag_x) * 0.01f;
    t->p.elevation = fmaxf(-1.5f, fminf(1.5f, t->p.elevation + (float)(y - t->drag_y) * 0.01f));
    t->drag_x = x, t->drag_y = y;
}

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
    (void)dx;
    tuner *t = glfwGetWindowUserPointer(w);
    if (view_panel_wants_mouse()) return;
    t->p.zoom = fmaxf(0.05f, fminf(4.0f, t->p.zoom * (float)pow(0.9, dy)));
}

/* ---- trees ----------------------------------------------------------------------------------- */

/* The new tree's leaves into leaf_gl when they are new. A failed upload is not fatal: the stems
 * stay on screen and the panel says why the leaves are missing. */
static void upload_leaves(tuner *t)
{
    const xyl_foliage *f = t->tree->foliage;
    /* The old foliage lives until this adoption, so an equal address is the same object. */
    if (f == t->leaf_uploaded) return;
    t->leaf_uploaded = NULL;
    t->leaf_note[0] = '\0';
    if (!f) return;
    if (f->original_count == 0) {
        snprintf(t->leaf_note, sizeof t->leaf_note, "the tree has no leaf attachments");
        return;
    }
    xyl_diag d = {0};
    xyl_result r = xyl_foliage_gl_set_foliage(t->leaf_gl, f, &d);
    if (r != XYL_OK) {
        snprintf(t->leaf_note, sizeof t->leaf_note, "leaf upload: %s: %s", xyl_result_string(r), d.message);
        fprintf(stderr, "xylem: view: %s (the stems are drawn alone)\n", t->leaf_note);
        return;
    }
    t->leaf_uploaded = f;
}

/* Whether this frame draws leaves: built, uploaded, and not switched off. */
static bool leaves_shown(const tuner *t)
{
    return t->tree && t->p.leaves && t->leaf_uploaded && t->tree->foliage == t->leaf_uploaded &&
           t->p.leaf_draw != VIEW_LEAVES_NONE;
}

/* Takes the worker's newest tree, if any, and uploads its patches when they are new. */
static int adopt(tuner *t)
{
    const xyl_tess_patches *before = t->tree ? t->tree->patches : NULL;
    if (!view_regrow_adopt(t->worker, &t->tree)) return 0;
    /* The old patches live until this adoption, so an equal address is the same object. */
    if (t->tree->patches != before) {
        xyl_diag d = {0};
        xyl_result r = xyl_tess_gl_set_patches(t->gl, t->tree->patches, &d);
        if (r != XYL_OK) return fail("patches upload", r, &d);
    }
    t->uploaded = t->tree->patches;
    upload_leaves(t);
    xyl_mesh_bounds(t->tree->mesh, t->lo, t->hi);
    memcpy(t->leaf_lo, t->lo, sizeof t->lo);
    memcpy(t->leaf_hi, t->hi, sizeof t->hi);
    xyl_foliage_bounds(t->leaf_uploaded, t->leaf_lo, t->leaf_hi);
    float c = 0.0f;
    for (size_t i = 0; i < t->tree->patches->count; ++i)
        c = fmaxf(c, xyl_tess_patch_error_coefficient(t->tree->patches, i));
    t->info.error_coefficient = c;
    return 0;
}

/* One line on what a scripted step regrew, or why it failed (stderr). */
static void report_step(tuner *t, const char *what)
{
    view_regrow_status st;
    view_regrow_status_get(t->worker, &st);
    if (st.failed) {
        const xyl_diag *d = &st.diag;
        const char *stays = t->tree ? "the last good tree stays" : "no tree yet";
        if (d->line)
            fprintf(stderr, "xylem: view: %s: %s:%u:%u: %s: %s (%s)\n", what,
                    view_stage_names[st.failed_stage], d->line, d->column, xyl_result_string(st.error),
                    d->message, stays);
        else
            fprintf(stderr, "xylem: view: %s: %s: %s: %s (%s)\n", what, view_stage_names[st.failed_stage],
                    xyl_result_string(st.error), d->message, stays);
        return;
    }
    if (!t->tree || t->tree->generation != st.done) {
        printf("%s: regrew nothing\n", what);
        return;
    }
    printf("%s: regrew", what);
    int ran = 0;
    for (int s = 0; s < VIEW_STAGE_COUNT; ++s)
        if (t->tree->ran[s]) printf("%s %s %.3f ms", ran++ ? "," : "", view_stage_names[s], t->tree->ms[s]);
    printf("%s\n", ran ? "" : " nothing");
}

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot : "";
}

static view_export_kind export_kind_of(const char *path)
{
    const char *e = extension(path);
    if (!strcmp(e, ".lsys")) return VIEW_EXPORT_LSYS;
    if (!strcmp(e, ".skel")) return VIEW_EXPORT_SKEL;
    if (!strcmp(e, ".glb")) return VIEW_EXPORT_GLB;
    if (!strcmp(e, ".png")) return VIEW_EXPORT_PNG;
    return VIEW_EXPORT_NONE;
}

/* Framed on the stems, or on stems and leaves when leaves are drawn, as `xylem render` frames
 * them: the same size and camera then pick the same leaf LODs. */
static void camera_of(const tuner *t, int width, int height, xyl_tess_camera *cam)
{
    bool leaves = leaves_shown(t);
    xyl_tess_camera_frame(leaves ? t->leaf_lo : t->lo, leaves ? t->leaf_hi : t->hi, t->p.azimuth,
                          t->p.elevation, 0.8f, (float)width / (float)(height ? height : 1), cam);
    if (t->p.zoom != 1.0f) xyl_tess_camera_zoom(cam, t->p.zoom); /* else the framed eye, bit for bit */
}

static void fill_frame(const tuner *t, xyl_tess_frame *f)
{
    memset(f, 0, sizeof *f);
    memcpy(f->light_dir, t->p.light, sizeof t->p.light);
    const float bark[4] = {0.47f, 0.35f, 0.24f, 1.0f}, line[4] = {0.08f, 0.08f, 0.08f, 1.0f};
    memcpy(f->color, bark, sizeof bark);
    memcpy(f->line_color, line, sizeof line);
    f->variant = (uint32_t)t->p.variant;
    if (t->p.wireframe) f->flags |= XYL_TESS_FLAG_WIREFRAME;
}

/* The levels for the view in the tree's viewport. */
static xyl_result select_levels(tuner *t, const xyl_tess_camera *cam, int height, xyl_diag *d)
{
    xyl_tess_view view = {0};
    memcpy(view.eye, cam->eye, sizeof view.eye);
    view.fovy = cam->fovy;
    view.viewport_height = (uint32_t)height;
    view.error_px = t->p.error_px;
    view.fixed_level = t->p.level;
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    xyl_result r = xyl_tess_select(t->tree->patches, t->patterns, &view, t->batches, d);
    clock_gettime(CLOCK_MONOTONIC, &b);
    t->info.select_ms = (double)(b.tv_sec - a.tv_sec) * 1e3 + (double)(b.tv_nsec - a.tv_nsec) * 1e-6;
    return r;
}

/* Stems, then leaves, into an offscreen target of the CLI's own, read back into rgba. */
static xyl_result render_leafy(tuner *t, const xyl_tess_image_desc *im, const xyl_tess_camera *cam,
                               const xyl_tess_frame *f, uint8_t *rgba, xyl_diag *d)
{
    const xyl_foliage *fo = t->tree->foliage;
    leaf_draw_pick_info pick;
    uint32_t *lods = t->lods;
    xyl_result r = leaf_draw_pick(fo, t->p.leaf_draw == VIEW_LEAVES_FULL, cam, im->height, t->p.error_px,
                                  lods, LEAF_DRAW_MAX_SECTORS, &pick, d);
    leaf_draw_target target;
    if (r == XYL_OK) r = leaf_draw_target_make(&target, im->width, im->height, im->samples, d);
    if (r != XYL_OK) return r;
    glClearColor(im->background[0], im->background[1], im->background[2], im->background[3]);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    r = xyl_tess_gl_draw(t->gl, t->batches, f, t->p.path, d);
    if (r == XYL_OK) {
        xyl_foliage_gl_frame lf = {0};
        memcpy(lf.view_proj, f->view_proj, sizeof lf.view_proj);
        memcpy(lf.light_dir, f->light_dir, sizeof lf.light_dir);
        lf.color[0] = lf.color[1] = lf.color[2] = lf.color[3] = 1.0f;
        r = xyl_foliage_gl_draw(t->leaf_gl, &lf, lods, fo->sector_count, d);
    }
    if (r == XYL_OK) leaf_draw_target_read(&target, rgba);
    leaf_draw_target_free(&target);
    return r;
}

/* The tree alone (no panel) at the size of its viewport, offscreen, with the leaves the window
 * draws. */
static int export_png(tuner *t, const char *path, char *msg, size_t cap)
{
    xyl_tess_image_desc im = {0};
    im.width = (uint32_t)(t->tree_w > 0 ? t->tree_w : 512);
    im.height = (uint32_t)(t->tree_h > 0 ? t->tree_h : 512);
    memcpy(im.background, t->p.background, sizeof im.background);
    im.wireframe = t->p.wireframe;
    im.samples = t->req->samples > 1 ? t->req->samples : 1;
    xyl_tess_camera cam;
    camera_of(t, (int)im.width, (int)im.height, &cam);
    xyl_tess_frame f;
    fill_frame(t, &f);
    bool leaves = leaves_shown(t);
    if (!leaves) f.flags &= ~(uint32_t)XYL_TESS_FLAG_WIREFRAME; /* the image desc draws the edges */
    xyl_diag d = {0};
    uint8_t *rgba = malloc((size_t)im.width * im.height * 4);
    xyl_result r = rgba ? xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, f.view_proj, &d) : XYL_ERR_OUT_OF_MEMORY;
    if (r == XYL_OK) r = select_levels(t, &cam, (int)im.height, &d);
    if (r == XYL_OK && leaves) r = render_leafy(t, &im, &cam, &f, rgba, &d);
    else if (r == XYL_OK) r = xyl_tess_gl_render_rgba(t->gl, t->batches, &f, t->p.path, &im, rgba, &d);
    int rc = 0;
    if (r != XYL_OK) {
        snprintf(msg, cap, "%s: %s: %s", path, xyl_result_string(r), rgba ? d.message : "out of memory");
        rc = r == XYL_ERR_OUT_OF_MEMORY ? 71 : 65;
    } else if (xyl_png_write(path, rgba, im.width, im.height, msg, cap) != 0) {
        rc = 73;
    }
    free(rgba);
    return rc;
}

/* The .glb of the stems, with the leaves and the procedural leaf texture when leaves are on. */
static xyl_result export_glb(const view_tree *tree, const char *path, xyl_diag *d)
{
    if (!tree->foliage) return xyl_mesh_write_file(tree->mesh, path, XYL_MESH_FORMAT_GLB, NULL, d);
    xyl_foliage_glb_desc gd = {0};
    gd.stems = tree->mesh;
    unsigned char *png = NULL;
    size_t size = 0;
    if (tree->foliage->leaf_count) {
        uint32_t w = XYL_LEAF_TEXTURE_WIDTH, h = XYL_LEAF_TEXTURE_HEIGHT;
        uint8_t *rgba = malloc((size_t)w * h * 4);
        int e = rgba ? 0 : 1;
        if (rgba) xyl_leaf_texture(rgba, w, h);
        if (!e) e = xyl_png_encode(rgba, w, h, &png, &size, d->message, sizeof d->message);
        free(rgba);
        if (e) return XYL_ERR_OUT_OF_MEMORY;
    }
    gd.texture_png = png;
    gd.texture_png_size = size;
    xyl_result r = xyl_foliage_write_glb_file(tree->foliage, &gd, path, d);
    free(png);
    return r;
}

/* Writes the tree on screen; 0 or an exit code, with the outcome in t->note either way. */
static int export_tree(tuner *t, view_export_kind kind, const char *path)
{
    char msg[512] = "";
    int rc = 0;
    xyl_result r = XYL_OK;
    xyl_diag d = {0};
    if (!t->tree) {
        snprintf(msg, sizeof msg, "no tree to export yet");
        rc = 65;
    } else if (kind == VIEW_EXPORT_LSYS) {
        if (xyl_write_file_atomic(path, t->tree->lsys, strlen(t->tree->lsys), msg, sizeof msg)) rc = 73;
    } else if (kind == VIEW_EXPORT_SKEL) {
        r = xyl_skeleton_write_file(t->tree->skeleton, path, XYL_SKEL_FORMAT_SKEL, NULL, &d);
    } else if (kind == VIEW_EXPORT_GLB) {
        r = export_glb(t->tree, path, &d);
    } else {
        rc = export_png(t, path, msg, sizeof msg);
    }
    if (r != XYL_OK) {
        snprintf(msg, sizeof msg, "%s: %s", path, d.message);
        rc = r == XYL_ERR_IO ? 73 : (r == XYL_ERR_OUT_OF_MEMORY ? 71 : 65);
    }
    if (rc) snprintf(t->note, sizeof t->note, "export failed: %s", msg);
    else snprintf(t->note, sizeof t->note, "wrote %s", path);
    return rc;
}

/* ---- frames ---------------------------------------------------------------------------------- */

/* The leaves' LODs for this camera and budget (the panel shows them with leaves on, drawn or
 * not), then, when they are shown, the draw with the stems' matrix and light. */
static int draw_leaves(tuner *t, const xyl_tess_camera *cam, const xyl_tess_frame *stems)
{
    const xyl_foliage *f = t->tree->foliage;
    t->info.has_leaf_pick = t->info.leaves_drawn = false;
    if (!t->p.leaves || !f || f->original_count == 0) return 0;
    leaf_draw_pick_info pick;
    xyl_diag d = {0};
    xyl_result r = leaf_draw_pick(f, t->p.leaf_draw == VIEW_LEAVES_FULL, cam, (uint32_t)t->tree_h,
                                  t->p.error_px, t->lods, LEAF_DRAW_MAX_SECTORS, &pick, &d);
    if (r != XYL_OK) return fail("leaf LODs", r, &d);
    t->info.has_leaf_pick = true;
    t->info.leaves_picked = pick.drawn;
    t->info.leaf_error = pick.error;
    t->info.leaf_lod_lo = pick.lod_lo, t->info.leaf_lod_hi = pick.lod_hi;
    t->info.leaf_lod_top = pick.lod_top;
    if (!leaves_shown(t)) return 0;
    xyl_foliage_gl_frame lf = {0};
    memcpy(lf.view_proj, stems->view_proj, sizeof lf.view_proj);
    memcpy(lf.light_dir, stems->light_dir, sizeof lf.light_dir);
    lf.color[0] = lf.color[1] = lf.color[2] = lf.color[3] = 1.0f; /* the texture's own */
    r = xyl_foliage_gl_draw(t->leaf_gl, &lf, t->lods, f->sector_count, &d);
    if (r != XYL_OK) return fail("leaf draw", r, &d);
    t->info.leaves_drawn = true;
    return 0;
}

static int draw_tree(tuner *t)
{
    t->info.triangles = t->info.vertices = 0;
    t->info.level_lo = t->info.level_hi = 0;
    if (!t->tree || t->tree_w <= 0 || t->tree_h <= 0) return 0;
    xyl_tess_camera cam;
    camera_of(t, t->tree_w, t->tree_h, &cam);
    xyl_tess_frame f;
    fill_frame(t, &f);
    xyl_diag d = {0};
    xyl_result r = xyl_tess_camera_matrix(&cam, XYL_TESS_CLIP_GL, f.view_proj, &d);
    if (r == XYL_OK) r = select_levels(t, &cam, t->tree_h, &d);
    if (r != XYL_OK) return fail("level selection", r, &d);
    glViewport(t->tree_x, 0, t->tree_w, t->tree_h);
    r = xyl_tess_gl_draw(t->gl, t->batches, &f, t->p.path, &d);
    if (r != XYL_OK) return fail("draw", r, &d);
    uint32_t lo = XYL_TESS_MAX_LEVEL, hi = 0;
    for (size_t c = 0; c < t->batches->cmd_count; ++c) {
        uint32_t l = t->batches->batches[c].level;
        lo = l < lo ? l : lo;
        hi = l > hi ? l : hi;
    }
    t->info.level_lo = t->batches->cmd_count ? lo : 0, t->info.level_hi = hi;
    t->info.triangles = t->batches->triangles, t->info.vertices = t->batches->vertices;
    t->info.gpu_ms = xyl_tess_gl_last_gpu_ms(t->gl);
    return draw_leaves(t, &cam, &f);
}

static int frame(tuner *t, int width, int height)
{
    int rc = adopt(t);
    if (rc) return rc;
    float panel = t->p.panel ? fminf(400.0f, (float)width * 0.5f) : 0.0f;
    t->tree_x = (int)panel, t->tree_w = width - (int)panel, t->tree_h = height;
    const float *bg = t->p.background;
    glViewport(0, 0, width, height);
    glClearColor(bg[0], bg[1], bg[2], 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    rc = draw_tree(t);
    if (rc) return rc;
    glViewport(0, 0, width, height);
    t->info.tree = t->tree;
    view_regrow_status_get(t->worker, &t->info.status);
    t->info.note = t->note[0] ? t->note : NULL;
    t->info.width = panel;
    t->info.renderer = t->renderer;
    t->info.leaf_note = t->leaf_note[0] ? t->leaf_note : NULL;
    view_panel_result out;
    view_panel_frame(&t->p, &t->info, &out);
    if (out.regrow) regrow(t);
    if (out.export_kind != VIEW_EXPORT_NONE) export_tree(t, out.export_kind, out.export_path);
    return 0;
}

static int loop(tuner *t)
{
    const xyl_tune_request *req = t->req;
    for (uint32_t n = 0; !glfwWindowShouldClose(t->window); ++n) {
        bool last = req->frames && n + 1 >= req->frames;
        if (last) view_regrow_wait(t->worker); /* the last frame shows a finished tree */
        int width = 0, height = 0;
        glfwGetFramebufferSize(t->window, &width, &height);
        int rc = width > 0 && height > 0 ? frame(t, width, height) : 0;
        if (rc) return rc;
        if (last && req->screenshot) {
            rc = xyl_view_write_screenshot(req->screenshot, width, height);
            if (rc) return rc;
        }
        glfwSwapBuffers(t->window);
        if (last) break;
        if (req->frames) {
            glfwPollEvents();
        } else {
            /* Idle windows sleep; while the worker runs, frames follow its progress line. */
            view_regrow_status st;
            view_regrow_status_get(t->worker, &st);
            glfwWaitEventsTimeout(st.busy ? 0.02 : 0.25);
        }
    }
    return 0;
}

/* ---- setup ----------------------------------------------------------------------------------- */

static int open_window(tuner *t)
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
    glfwWindowHint(GLFW_SAMPLES, t->req->samples > 1 ? (int)t->req->samples : 0);
    glfwWindowHint(GLFW_RESIZABLE, t->req->frames ? GLFW_FALSE : GLFW_TRUE);
    t->window = glfwCreateWindow((int)t->req->width, (int)t->req->height, "xylem view: tuning", NULL, NULL);
    if (!t->window) {
        fprintf(stderr, "xylem: view: no OpenGL 4.5 core window\n");
        return 69;
    }
    glfwMakeContextCurrent(t->window);
    glfwSwapInterval(t->req->frames ? 0 : 1);
    glfwSetWindowUserPointer(t->window, t);
    glfwSetKeyCallback(t->window, on_key);
    glfwSetMouseButtonCallback(t->window, on_button);
    glfwSetCursorPosCallback(t->window, on_cursor);
    glfwSetScrollCallback(t->window, on_scroll);
    glEnable(GL_MULTISAMPLE);
    if (!view_panel_init(t->window)) {
        fprintf(stderr, "xylem: view: the Dear ImGui panel could not start\n");
        return 69;
    }
    return 0;
}

static int start_gl(tuner *t)
{
    xyl_diag d = {0};
    xyl_result r = xyl_tess_patterns_create(0, NULL, &t->patterns, &d);
    if (r == XYL_OK) r = xyl_tess_batches_create(NULL, &t->batches, &d);
    if (r == XYL_OK) r = xyl_tess_gl_create(NULL, t->patterns, &t->gl, &d);
    if (r == XYL_OK) r = leaf_draw_create(&t->leaf_gl, &d);
    if (r != XYL_OK) return fail("GL backend", r, &d);
    GLint samples = 0;
    glGetIntegerv(GL_SAMPLES, &samples);
    snprintf(t->renderer, sizeof t->renderer, "%s", (const char *)glGetString(GL_RENDERER));
    printf("device: %s (OpenGL, GLFW window, %d samples per pixel, tuning panel)\n", t->renderer,
           samples > 1 ? samples : 1);
    return 0;
}

int xyl_view_check_sets(const view_params *start, const char *const *sets, uint32_t count)
{
    view_params p;
    view_params_init(&p);
    if (!view_params_copy(&p, start)) {
        fprintf(stderr, "xylem: out of memory\n");
        return 71;
    }
    int rc = 0;
    for (uint32_t i = 0; !rc && i < count; ++i) {
        const char *eq = strchr(sets[i], '=');
        char name[64], err[512];
        size_t n = eq ? (size_t)(eq - sets[i]) : 0;
        if (!eq || n == 0 || n >= sizeof name) {
            fprintf(stderr, "xylem: --set takes NAME=VALUE, not '%s'\n", sets[i]);
            rc = 64;
            break;
        }
        memcpy(name, sets[i], n);
        name[n] = '\0';
        if (!strcmp(name, "export")) {
            if (export_kind_of(eq + 1) == VIEW_EXPORT_NONE) {
                fprintf(stderr, "xylem: --set export takes FILE.lsys, .skel, .glb or .png, not '%s'\n", eq + 1);
                rc = 64;
            }
        } else if ((rc = view_params_set(&p, name, eq + 1, err, sizeof err)) != 0) {
            fprintf(stderr, "xylem: %s\n", err);
        }
    }
    view_params_free(&p);
    return rc;
}

/* One --set step: a parameter (then the tree regrows and the step is reported) or an export. */
static int apply_set(tuner *t, const char *arg)
{
    const char *eq = strchr(arg, '=');
    char name[64];
    size_t n = (size_t)(eq - arg) < sizeof name ? (size_t)(eq - arg) : sizeof name - 1;
    memcpy(name, arg, n);
    name[n] = '\0';
    const char *value = eq + 1;
    if (!strcmp(name, "export")) {
        int rc = export_tree(t, export_kind_of(value), value);
        fprintf(rc ? stderr : stdout, "%s%s\n", rc ? "xylem: view: " : "", t->note);
        return rc;
    }
    char err[512];
    int rc = view_params_set(&t->p, name, value, err, sizeof err);
    if (rc) {
        fprintf(stderr, "xylem: %s\n", err);
        return rc;
    }
    regrow(t);
    view_regrow_wait(t->worker);
    rc = adopt(t);
    /* A grammar text names itself by its name only: it spans lines. */
    if (!rc) report_step(t, strpbrk(value, "\r\n") || strlen(value) > 60 ? name : arg);
    return rc;
}

/* The last frame's leaves, in the words of `xylem render`'s leaves line. */
static void print_leaves(const tuner *t)
{
    static const char *const modes[] = {"lod", "full", "none"};
    const view_panel_info *i = &t->info;
    char which[64];
    if (i->leaf_lod_lo == i->leaf_lod_hi) snprintf(which, sizeof which, "LOD %u", i->leaf_lod_lo);
    else snprintf(which, sizeof which, "LODs %u..%u", i->leaf_lod_lo, i->leaf_lod_hi);
    if (i->leaves_drawn)
        printf("leaves: foliage=%s: %s of 0..%u, %llu of %zu leaves drawn in the last frame\n",
               modes[t->p.leaf_draw], which, i->leaf_lod_top, (unsigned long long)i->leaves_picked,
               t->tree->foliage->original_count);
    else
        printf("leaves: not drawn (%s); the budget picks %s of 0..%u, %llu of %zu leaves\n",
               t->leaf_note[0] ? t->leaf_note : "foliage=none", which, i->leaf_lod_top,
               (unsigned long long)i->leaves_picked, t->tree->foliage->original_count);
}

static int run(tuner *t)
{
    int rc = open_window(t);
    if (!rc) rc = start_gl(t);
    char err[256];
    if (!rc && !(t->worker = view_regrow_start(err, sizeof err))) {
        fprintf(stderr, "xylem: view: %s\n", err);
        rc = 71;
    }
    if (rc) return rc;
    regrow(t);
    view_regrow_wait(t->worker);
    rc = adopt(t);
    if (!rc) report_step(t, t->p.source);
    for (uint32_t i = 0; !rc && i < t->req->set_count; ++i) rc = apply_set(t, t->req->sets[i]);
    if (!rc) rc = loop(t);
    if (!rc && t->tree) printf("%llu triangles in the last frame\n", (unsigned long long)t->info.triangles);
    if (!rc && t->info.has_leaf_pick) print_leaves(t);
    if (!rc) {
        view_regrow_status st;
        view_regrow_status_get(t->worker, &st);
        if (st.failed) rc = 65;
    }
    return rc;
}

int xyl_view_tune(const xyl_tune_request *req)
{
    tuner *t = calloc(1, sizeof *t);
    if (!t) {
        fprintf(stderr, "xylem: view: out of memory\n");
        return 71;
    }
    t->req = req;
    view_params_init(&t->p);
    int rc = view_params_copy(&t->p, req->start) ? run(t) : 71;
    view_regrow_stop(t->worker, &t->tree);
    view_panel_shutdown();
    xyl_foliage_gl_destroy(t->leaf_gl);
    xyl_tess_gl_destroy(t->gl);
    xyl_tess_batches_destroy(t->batches);
    xyl_tess_patterns_destroy(t->patterns);
    if (t->window) glfwDestroyWindow(t->window);
    glfwTerminate();
    view_params_free(&t->p);
    free(t);
    return rc;
}
