/* foliage/'s tree billboards (xyl_billboard_gl.h) on a headless EGL context (llvmpipe where
 * there is no GPU), with a tree of leaves drawn by xyl_foliage_gl as the bake's callback: the
 * baked views against the tree's own silhouette from the documented bake camera, the billboard
 * seen from its bake direction against the tree, and bad input. Without a usable GL 4.5
 * context every test is skipped, and says why. */
#include <epoxy/gl.h>
#include <math.h>

#include "test_util.h"
#include "foliage_tree.h"
#include <xylem/xyl_billboard_gl.h>
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_tess_gl.h>

#define SIDE 384 /* texels of a baked view and pixels of a test picture */
/* The spherical billboard from its bake side against the tree (compare): measured 0.056 and
 * 0.19 on llvmpipe; the same billboard from +X, where it shows the wrong picture, 0.10 and
 * 0.36. */
#define COLOUR_RMSE 0.08
#define COVERAGE_RMSE 0.27

typedef struct suite {
    xyl_gl_context *ctx;
    xyl_foliage_gl *leaves;
    xyl_foliage *tree;
    uint32_t lods[64];
    float lo[3], hi[3];
    int calls;            /* the bake callback's */
    xyl_result fail_with; /* what the callback returns */
    char why[320];
} suite;

static void expect(xyl_result got, xyl_result want, const xyl_diag *d)
{
    if (got != want)
        fail_msg("expected %s, got %s (%s)", xyl_result_string(want), xyl_result_string(got),
                 d->message);
    if (want != XYL_OK) assert_true(strlen(d->message) > 0);
}

static xyl_foliage *tree_foliage(const char *preset)
{
    return ft_tree_foliage(preset, 1);
}

static int setup(void **state)
{
    suite *s = calloc(1, sizeof *s);
    if (!s) return -1;
    xyl_diag d = {0};
    if (xyl_gl_context_create_headless(NULL, &s->ctx, &d) != XYL_OK ||
        xyl_foliage_gl_create(NULL, &s->leaves, &d) != XYL_OK) {
        snprintf(s->why, sizeof s->why, "no usable GL 4.5 context: %s", d.message);
        xyl_gl_context_destroy(s->ctx);
        s->ctx = NULL;
        *state = s;
        return 0;
    }
    s->tree = tree_foliage("abop-2.8-ternary");
    if (xyl_foliage_gl_set_foliage(s->leaves, s->tree, &d) != XYL_OK) return -1;
    for (int k = 0; k < 3; ++k) s->lo[k] = INFINITY, s->hi[k] = -INFINITY;
    for (size_t i = 0; i < s->tree->leaf_count; ++i) {
        const xyl_leaf *l = &s->tree->leaves[i];
        const float c[3] = {l->center.x, l->center.y, l->center.z};
        const float e[3] = {fabsf(l->side.x) + fabsf(l->axis.x), fabsf(l->side.y) + fabsf(l->axis.y),
                            fabsf(l->side.z) + fabsf(l->axis.z)};
        for (int k = 0; k < 3; ++k) {
            s->lo[k] = fminf(s->lo[k], c[k] - e[k]);
            s->hi[k] = fmaxf(s->hi[k], c[k] + e[k]);
        }
    }
    *state = s;
    return 0;
}

static int teardown(void **state)
{
    suite *s = *state;
    xyl_foliage_gl_destroy(s->leaves);
    xyl_foliage_destroy(s->tree);
    xyl_gl_context_destroy(s->ctx);
    free(s);
    return 0;
}

static suite *need_gl(void **state)
{
    suite *s = *state;
    if (s->why[0]) {
        print_message("skipped: %s\n", s->why);
        skip();
    }
    s->calls = 0;
    s->fail_with = XYL_OK;
    return s;
}

static xyl_result draw_leaves(void *user, const float view_proj[16], const float light[3],
                              xyl_diag *d)
{
    suite *s = user;
    ++s->calls;
    if (s->fail_with != XYL_OK) {
        snprintf(d->message, sizeof d->message, "the test's draw fails");
        return s->fail_with;
    }
    xyl_foliage_gl_frame fr = {0};
    memcpy(fr.view_proj, view_proj, sizeof fr.view_proj);
    memcpy(fr.light_dir, light, sizeof fr.light_dir);
    return xyl_foliage_gl_draw(s->leaves, &fr, s->lods, s->tree->sector_count, d);
}

static xyl_billboard_gl_desc desc_of(const suite *s, xyl_billboard_kind kind, uint32_t planes)
{
    xyl_billboard_gl_desc bd = {0};
    bd.kind = kind;
    bd.planes = planes;
    bd.resolution = SIDE;
    memcpy(bd.lo, s->lo, sizeof bd.lo);
    memcpy(bd.hi, s->hi, sizeof bd.hi);
    return bd;
}

/* A SIDE x SIDE picture (top row first) of what draw puts into a cleared target. */
typedef void (*paint_fn)(suite *s, const void *what);
static void picture(suite *s, paint_fn paint, const void *what, uint8_t *rgba)
{
    GLuint rb[2], fbo;
    glCreateRenderbuffers(2, rb);
    glNamedRenderbufferStorage(rb[0], GL_RGBA8, SIDE, SIDE);
    glNamedRenderbufferStorage(rb[1], GL_DEPTH_COMPONENT24, SIDE, SIDE);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    glNamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    assert_int_equal(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER), GL_FRAMEBUFFER_COMPLETE);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, SIDE, SIDE);
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    paint(s, what);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    uint8_t *tmp = malloc(4 * SIDE * SIDE);
    assert_non_null(tmp);
    glReadPixels(0, 0, SIDE, SIDE, GL_RGBA, GL_UNSIGNED_BYTE, tmp);
    for (int y = 0; y < SIDE; ++y) memcpy(rgba + 4 * y * SIDE, tmp + 4 * (SIDE - 1 - y) * SIDE, 4 * SIDE);
    free(tmp);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteRenderbuffers(2, rb);
}

/* The bake camera of cross plane v of n as the header documents it: orthographic, looking at
 * the box's centre along -(sin a, 0, cos a), a = pi v / n, the rectangle as wide as the
 * diagonal of the box's horizontal section and as high as the box. */
typedef struct ortho {
    float m[16];
    float light[3];
} ortho;

static void paint_ortho(suite *s, const void *what)
{
    const ortho *o = what;
    xyl_diag d = {0};
    expect(draw_leaves(s, o->m, o->light, &d), XYL_OK, &d);
}

static void bake_camera(const suite *s, uint32_t v, uint32_t n, ortho *o)
{
    float c[3], e[3];
    for (int k = 0; k < 3; ++k) c[k] = 0.5f * (s->lo[k] + s->hi[k]), e[k] = 0.5f * (s->hi[k] - s->lo[k]);
    const float half[2] = {sqrtf(e[0] * e[0] + e[2] * e[2]), e[1]};
    float depth = 2.0f * sqrtf(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    double a = 3.14159265358979323846 * v / n;
    float dir[3] = {(float)sin(a), 0.0f, (float)cos(a)}, right[3] = {dir[2], 0.0f, -dir[0]};
    float up[3] = {0.0f, 1.0f, 0.0f};
    const float *rows[3] = {right, up, dir};
    const float scale[3] = {1.0f / half[0], 1.0f / half[1], -1.0f / depth};
    memset(o->m, 0, sizeof o->m);
    for (int r = 0; r < 3; ++r) {
        float t = 0.0f;
        for (int k = 0; k < 3; ++k) o->m[k * 4 + r] = rows[r][k] * scale[r], t += rows[r][k] * c[k];
        o->m[12 + r] = -t * scale[r];
    }
    o->m[15] = 1.0f;
    memcpy(o->light, dir, sizeof o->light);
}

/* Every baked view of a 4-plane cross is the tree's silhouette from its plane's normal: the
 * baked alpha and the tree's own coverage from the documented camera differ in at most 1% of
 * the texels (edge texels where the two rasterisations round differently), and the tree
 * covers a real share of the view (over 5%), so the views are not empty. */
static void baked_views_are_the_trees_silhouette(void **state)
{
    suite *s = need_gl(state);
    xyl_billboard_gl_desc bd = desc_of(s, XYL_BILLBOARD_CROSS, 4);
    xyl_billboard_gl *bb = NULL;
    xyl_diag d = {0};
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_OK, &d);
    assert_int_equal(s->calls, 4);
    assert_int_equal(xyl_billboard_gl_view_count(bb), 4);
    uint8_t *baked = malloc(4 * SIDE * SIDE), *tree = malloc(4 * SIDE * SIDE);
    uint8_t *normal = malloc(4 * SIDE * SIDE);
    assert_true(baked && tree && normal);
    for (uint32_t v = 0; v < 4; ++v) {
        expect(xyl_billboard_gl_read_view(bb, v, false, baked, &d), XYL_OK, &d);
        expect(xyl_billboard_gl_read_view(bb, v, true, normal, &d), XYL_OK, &d);
        ortho o;
        bake_camera(s, v, 4, &o);
        picture(s, paint_ortho, &o, tree);
        size_t covered = 0, differ = 0, facing = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) {
            bool a = baked[4 * i + 3] > 127, b = tree[4 * i + 3] > 0;
            covered += b;
            differ += a != b;
            if (a) facing += normal[4 * i + 2] > 128; /* z towards the bake camera */
        }
        print_message("view %u: %zu covered, %zu differ, %zu facing\n", v, covered, differ,
                      facing);
        assert_true(covered > SIDE * SIDE / 20);
        assert_true(differ * 100 <= (size_t)SIDE * SIDE);
        size_t baked_covered = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) baked_covered += baked[4 * i + 3] > 127;
        assert_int_equal(facing, baked_covered); /* every reconstructed normal faces the camera */
    }
    free(baked);
    free(tree);
    free(normal);
    xyl_billboard_gl_destroy(bb);
}

typedef struct persp {
    xyl_tess_camera cam;
    float m[16], light[3];
    xyl_billboard_gl *bb; /* NULL: the tree */
} persp;

static void paint_persp(suite *s, const void *what)
{
    const persp *p = what;
    xyl_diag d = {0};
    if (!p->bb) {
        expect(draw_leaves(s, p->m, p->light, &d), XYL_OK, &d);
        return;
    }
    xyl_billboard_gl_frame fr = {0};
    memcpy(fr.view_proj, p->m, sizeof fr.view_proj);
    memcpy(fr.eye, p->cam.eye, sizeof fr.eye);
    memcpy(fr.light_dir, p->light, sizeof fr.light_dir);
    expect(xyl_billboard_gl_draw(p->bb, &fr, &d), XYL_OK, &d);
}

/* The tree and the billboard p->bb from p's camera, compared in 4 x 4 blocks: its leaves are
 * under a pixel wide, and a pixel's coverage is then a matter of where the sample falls, in
 * the tree's picture as in the bake. RMSE of the blocks' mean colour (RGB in [0, 1]) and of
 * their covered share, over the blocks either picture covers a part of. */
static void compare(suite *s, persp *p, double *colour_rmse, double *coverage_rmse,
                    size_t *covered_px)
{
    uint8_t *tree = malloc(4 * SIDE * SIDE), *board = malloc(4 * SIDE * SIDE);
    assert_true(tree && board);
    xyl_billboard_gl *bb = p->bb;
    p->bb = NULL;
    picture(s, paint_persp, p, tree);
    p->bb = bb;
    picture(s, paint_persp, p, board);
    double sc = 0.0, sv = 0.0;
    size_t covered = 0, blocks = 0; /* those either picture covers a part of */
    for (int by = 0; by < SIDE / 4; ++by)
        for (int bx = 0; bx < SIDE / 4; ++bx) {
            double ca[3] = {0}, cb[3] = {0}, va = 0.0, vb = 0.0;
            for (int y = 4 * by; y < 4 * by + 4; ++y)
                for (int x = 4 * bx; x < 4 * bx + 4; ++x) {
                    size_t i = (size_t)y * SIDE + (size_t)x;
                    for (int k = 0; k < 3; ++k) ca[k] += tree[4 * i + k] / 255.0 / 16.0,
                                                cb[k] += board[4 * i + k] / 255.0 / 16.0;
                    va += tree[4 * i + 3] > 0 ? 1.0 / 16.0 : 0.0;
                    vb += board[4 * i + 3] > 0 ? 1.0 / 16.0 : 0.0;
                    covered += tree[4 * i + 3] > 0;
                }
            if (va == 0.0 && vb == 0.0) continue;
            ++blocks;
            for (int k = 0; k < 3; ++k) sc += (ca[k] - cb[k]) * (ca[k] - cb[k]);
            sv += (va - vb) * (va - vb);
        }
    *colour_rmse = sqrt(sc / (3.0 * blocks));
    *coverage_rmse = sqrt(sv / blocks);
    *covered_px = covered;
    free(tree);
    free(board);
}

/* The spherical billboard seen from its bake side (+Z, a far perspective camera: nearly the
 * bake's orthographic view), lit by the bake's own light, against the tree: within COLOUR_RMSE
 * and COVERAGE_RMSE; from +X, where the billboard shows the +Z picture turned, the coverage
 * error is more than 1.5 times as large, so the comparison tells a right picture from a
 * wrong one. */
static void billboard_from_its_bake_side_matches_the_tree(void **state)
{
    suite *s = need_gl(state);
    xyl_billboard_gl_desc bd = desc_of(s, XYL_BILLBOARD_SPHERICAL, 0);
    persp p = {0};
    xyl_diag d = {0};
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &p.bb, &d), XYL_OK, &d);
    assert_int_equal(s->calls, 1);
    xyl_tess_camera_frame(s->lo, s->hi, 0.0f, 0.0f, 0.8f, 1.0f, &p.cam);
    p.cam.fovy = 0.05f; /* nearly orthographic: the eye far away along +Z */
    float c[3];
    for (int k = 0; k < 3; ++k) c[k] = p.cam.target[k];
    float r = 0.5f * sqrtf((s->hi[0] - s->lo[0]) * (s->hi[0] - s->lo[0]) +
                           (s->hi[1] - s->lo[1]) * (s->hi[1] - s->lo[1]) +
                           (s->hi[2] - s->lo[2]) * (s->hi[2] - s->lo[2]));
    float dist = r / tanf(0.025f);
    p.cam.eye[0] = c[0], p.cam.eye[1] = c[1], p.cam.eye[2] = c[2] + dist;
    p.cam.near_plane = dist - 2.0f * r, p.cam.far_plane = dist + 2.0f * r;
    expect(xyl_tess_camera_matrix(&p.cam, XYL_TESS_CLIP_GL, p.m, &d), XYL_OK, &d);
    p.light[2] = 1.0f;
    double colour, coverage, side_colour, side_coverage;
    size_t covered, side_covered;
    compare(s, &p, &colour, &coverage, &covered);
    print_message("from +Z: colour RMSE %.4f, coverage RMSE %.4f, %zu covered\n", colour,
                  coverage, covered);
    assert_true(covered > SIDE * SIDE / 100);
    assert_true(colour < COLOUR_RMSE);
    assert_true(coverage < COVERAGE_RMSE);
    /* from +X the tree is another picture, and the billboard (the +Z view turned) shows it */
    p.cam.eye[0] = c[0] + dist, p.cam.eye[2] = c[2];
    expect(xyl_tess_camera_matrix(&p.cam, XYL_TESS_CLIP_GL, p.m, &d), XYL_OK, &d);
    p.light[0] = 1.0f, p.light[2] = 0.0f;
    compare(s, &p, &side_colour, &side_coverage, &side_covered);
    print_message("from +X: colour RMSE %.4f, coverage RMSE %.4f, %zu covered\n", side_colour,
                  side_coverage, side_covered);
    assert_true(side_coverage > 1.5 * coverage);
    xyl_billboard_gl *bb = p.bb;
    xyl_billboard_gl_destroy(bb);
}

/* ---- the octahedral impostor ------------------------------------------------------------ */

#define GRID 5 /* views (2, 4), (4, 2) and (2, 2) look from +Z, +X and +Y */

static xyl_billboard_gl_desc octahedral_desc(const suite *s, uint32_t grid)
{
    xyl_billboard_gl_desc bd = desc_of(s, XYL_BILLBOARD_OCTAHEDRAL, 0);
    bd.grid = grid;
    return bd;
}

static float half_diagonal(const suite *s)
{
    float e2 = 0.0f;
    for (int k = 0; k < 3; ++k) e2 += 0.25f * (s->hi[k] - s->lo[k]) * (s->hi[k] - s->lo[k]);
    return sqrtf(e2);
}

/* Grid view v's direction and camera as the header documents them, written out anew. */
static void octahedral_direction(uint32_t grid, uint32_t v, double d[3])
{
    double o[2] = {2.0 * (v % grid) / (grid - 1) - 1.0, 2.0 * (v / grid) / (grid - 1) - 1.0};
    double y = 1.0 - fabs(o[0]) - fabs(o[1]);
    if (y < 0.0) {
        double f0 = (1.0 - fabs(o[1])) * (o[0] >= 0.0 ? 1.0 : -1.0);
        double f1 = (1.0 - fabs(o[0])) * (o[1] >= 0.0 ? 1.0 : -1.0);
        o[0] = f0, o[1] = f1;
    }
    double len = sqrt(o[0] * o[0] + y * y + o[1] * o[1]);
    d[0] = o[0] / len, d[1] = y / len, d[2] = o[1] / len;
}

static void octahedral_camera(const suite *s, uint32_t grid, uint32_t v, ortho *o)
{
    double d[3];
    octahedral_direction(grid, v, d);
    double h = sqrt(d[0] * d[0] + d[2] * d[2]);
    double right[3] = {h > 1e-4 ? d[2] / h : 1.0, 0.0, h > 1e-4 ? -d[0] / h : 0.0};
    double up[3] = {d[1] * right[2] - d[2] * right[1], d[2] * right[0] - d[0] * right[2],
                    d[0] * right[1] - d[1] * right[0]};
    const double *rows[3] = {right, up, d};
    float c[3];
    for (int k = 0; k < 3; ++k) c[k] = 0.5f * (s->lo[k] + s->hi[k]);
    float radius = 1.01f * half_diagonal(s);
    const float scale[3] = {1.0f / radius, 1.0f / radius, -1.0f / radius};
    memset(o->m, 0, sizeof o->m);
    for (int r = 0; r < 3; ++r) {
        float t = 0.0f;
        for (int k = 0; k < 3; ++k)
            o->m[k * 4 + r] = (float)rows[r][k] * scale[r], t += (float)rows[r][k] * c[k];
        o->m[12 + r] = -t * scale[r];
    }
    o->m[15] = 1.0f;
    for (int k = 0; k < 3; ++k) o->light[k] = (float)d[k];
}

/* Every view of a 5 x 5 octahedral grid, read out of the one atlas, is the tree's silhouette
 * from its grid direction: baked alpha and the tree's own coverage from the documented camera
 * differ in at most 1% of the texels (measured on llvmpipe: none), and the tree covers over 1%
 * of every view (the square is the bounding sphere's, 1.5% to 2% on llvmpipe; the views from
 * below, at the square's corners, included), so no view is empty or misplaced. */
static void octahedral_views_are_the_trees_silhouette(void **state)
{
    suite *s = need_gl(state);
    xyl_billboard_gl_desc bd = octahedral_desc(s, GRID);
    xyl_billboard_gl *bb = NULL;
    xyl_diag d = {0};
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_OK, &d);
    assert_int_equal(s->calls, GRID * GRID);
    assert_int_equal(xyl_billboard_gl_view_count(bb), GRID * GRID);
    uint8_t *baked = malloc(4 * SIDE * SIDE), *tree = malloc(4 * SIDE * SIDE);
    assert_true(baked && tree);
    for (uint32_t v = 0; v < GRID * GRID; ++v) {
        expect(xyl_billboard_gl_read_view(bb, v, false, baked, &d), XYL_OK, &d);
        ortho o;
        octahedral_camera(s, GRID, v, &o);
        picture(s, paint_ortho, &o, tree);
        size_t covered = 0, differ = 0;
        for (size_t i = 0; i < (size_t)SIDE * SIDE; ++i) {
            bool a = baked[4 * i + 3] > 127, b = tree[4 * i + 3] > 0;
            covered += b;
            differ += a != b;
        }
        print_message("view %2u: %6zu covered, %4zu differ\n", v, covered, differ);
        assert_true(covered > SIDE * SIDE / 100);
        assert_true(differ * 100 <= (size_t)SIDE * SIDE);
    }
    free(baked);
    free(tree);
    xyl_billboard_gl_destroy(bb);
}

/* A far, nearly orthographic camera from direction dir, looking at the box's centre. */
static void far_camera(const suite *s, const double dir[3], persp *p)
{
    xyl_diag d = {0};
    xyl_tess_camera_frame(s->lo, s->hi, 0.0f, 0.0f, 0.8f, 1.0f, &p->cam);
    p->cam.fovy = 0.05f;
    float r = half_diagonal(s), dist = r / tanf(0.025f);
    double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int k = 0; k < 3; ++k) {
        p->cam.target[k] = 0.5f * (s->lo[k] + s->hi[k]);
        p->cam.eye[k] = p->cam.target[k] + dist * (float)(dir[k] / len);
    }
    p->cam.up[0] = 0.0f, p->cam.up[1] = 1.0f, p->cam.up[2] = 0.0f;
    if (fabs(dir[1]) > 0.99 * len) p->cam.up[1] = 0.0f, p->cam.up[2] = -1.0f;
    p->cam.near_plane = dist - 2.0f * r, p->cam.far_plane = dist + 2.0f * r;
    expect(xyl_tess_camera_matrix(&p->cam, XYL_TESS_CLIP_GL, p->m, &d), XYL_OK, &d);
}

/* The impostor seen from grid directions (+Z, +X, straight down from +Y) under the bake's
 * light against the tree, in compare's 4 x 4 blocks: colour RMSE under 0.045 and coverage
 * RMSE under 0.13 (measured on llvmpipe: at most 0.031 and 0.085); the spherical billboard
 * from +X (the wrong picture) is 0.11 and 0.36 by the same measure. */
static void impostor_from_a_grid_direction_matches_the_tree(void **state)
{
    suite *s = need_gl(state);
    xyl_billboard_gl_desc bd = octahedral_desc(s, GRID);
    const float light[3] = {0.42f, 0.78f, 0.46f};
    memcpy(bd.light_dir, light, sizeof light);
    persp p = {0};
    xyl_diag d = {0};
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &p.bb, &d), XYL_OK, &d);
    const double dirs[3][3] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
    for (int i = 0; i < 3; ++i) {
        far_camera(s, dirs[i], &p);
        float len = sqrtf(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
        for (int k = 0; k < 3; ++k) p.light[k] = light[k] / len;
        double colour, coverage;
        size_t covered;
        compare(s, &p, &colour, &coverage, &covered);
        print_message("from (%g, %g, %g): colour RMSE %.4f, coverage RMSE %.4f, %zu covered\n",
                      dirs[i][0], dirs[i][1], dirs[i][2], colour, coverage, covered);
        assert_true(covered > SIDE * SIDE / 100);
        assert_true(colour < 0.045);
        assert_true(coverage < 0.13);
    }
    xyl_billboard_gl_destroy(p.bb);
}

/* Mean absolute difference of two pictures' RGBA, in [0, 1]. */
static double picture_change(const uint8_t *a, const uint8_t *b)
{
    double sum = 0.0;
    for (size_t i = 0; i < 4u * SIDE * SIDE; ++i) sum += abs(a[i] - b[i]);
    return sum / (4.0 * SIDE * SIDE * 255.0);
}

/* Between grid directions the impostor blends: a camera going round the tree in 1 degree
 * steps at 20 degrees up, across several grid cells (a 5-grid's horizontal views are 90
 * degrees apart), changes the impostor's picture by at most STEP_FACTOR times the tree's own
 * largest change over the same steps (measured on llvmpipe: 0.0023 against the tree's 0.0024).
 * The orbit crosses grid lines (o.y = 0.5 near 30 degrees, o.x = 0.5 near 60); a switch to
 * the nearest view instead of a blend would jump there by a picture as different as two
 * views 45 degrees apart. */
#define STEP_FACTOR 1.5
static void impostor_blend_is_continuous(void **state)
{
    suite *s = need_gl(state);
    xyl_billboard_gl_desc bd = octahedral_desc(s, GRID);
    persp p = {0};
    xyl_diag d = {0};
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &p.bb, &d), XYL_OK, &d);
    xyl_billboard_gl *bb = p.bb;
    uint8_t *pic[2][2]; /* [tree, impostor][previous, this] */
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) assert_non_null(pic[i][j] = malloc(4 * SIDE * SIDE));
    double tree_max = 0.0, imp_max = 0.0;
    const double el = 20.0 * 3.14159265358979323846 / 180.0;
    for (int step = 0; step <= 40; ++step) {
        double az = (25.0 + 1.0 * step) * 3.14159265358979323846 / 180.0;
        const double dir[3] = {sin(az) * cos(el), sin(el), cos(az) * cos(el)};
        far_camera(s, dir, &p);
        p.light[1] = 1.0f;
        int now = step & 1;
        p.bb = NULL;
        picture(s, paint_persp, &p, pic[0][now]);
        p.bb = bb;
        picture(s, paint_persp, &p, pic[1][now]);
        if (step == 0) continue;
        double t = picture_change(pic[0][now], pic[0][!now]);
        double m = picture_change(pic[1][now], pic[1][!now]);
        tree_max = fmax(tree_max, t), imp_max = fmax(imp_max, m);
    }
    print_message("largest step change: tree %.5f, impostor %.5f\n", tree_max, imp_max);
    assert_true(tree_max > 0.0);
    assert_true(imp_max <= STEP_FACTOR * tree_max);
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) free(pic[i][j]);
    xyl_billboard_gl_destroy(bb);
}

static void octahedral_bad_input_gets_result_codes(void **state)
{
    suite *s = need_gl(state);
    xyl_diag d = {0};
    xyl_billboard_gl *bb = NULL;
    const uint32_t bad_grid[] = {1, XYL_BILLBOARD_MAX_GRID + 1, UINT32_MAX};
    for (size_t i = 0; i < sizeof bad_grid / sizeof *bad_grid; ++i) {
        xyl_billboard_gl_desc bd = octahedral_desc(s, bad_grid[i]);
        expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
        assert_non_null(strstr(d.message, "grid"));
    }
    xyl_billboard_gl_desc bd = desc_of(s, XYL_BILLBOARD_CROSS, 4);
    bd.grid = 4; /* a grid on another kind */
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_non_null(strstr(d.message, "grid"));
    bd = octahedral_desc(s, XYL_BILLBOARD_MAX_GRID);
    bd.resolution = 1024; /* 32768 texels wide */
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_non_null(strstr(d.message, "atlas"));
    bd = octahedral_desc(s, 4);
    bd.light_dir[2] = INFINITY;
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_NON_FINITE, &d);
    assert_int_equal(s->calls, 0);
    assert_null(bb);
    /* grid 0 is the default, 8 x 8 views */
    bd = octahedral_desc(s, 0);
    bd.resolution = XYL_BILLBOARD_MIN_RESOLUTION;
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_OK, &d);
    assert_int_equal(xyl_billboard_gl_view_count(bb), XYL_BILLBOARD_DEFAULT_GRID * XYL_BILLBOARD_DEFAULT_GRID);
    uint8_t px[4 * XYL_BILLBOARD_MIN_RESOLUTION * XYL_BILLBOARD_MIN_RESOLUTION];
    expect(xyl_billboard_gl_read_view(bb, 63, true, px, &d), XYL_OK, &d);
    expect(xyl_billboard_gl_read_view(bb, 64, false, px, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    xyl_billboard_gl_destroy(bb);
}

static void bad_input_gets_result_codes(void **state)
{
    suite *s = need_gl(state);
    xyl_diag d = {0};
    xyl_billboard_gl *bb = NULL;
    xyl_billboard_gl_desc bd = desc_of(s, XYL_BILLBOARD_CROSS, 4);
    expect(xyl_billboard_gl_bake(NULL, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_gl_bake(&bd, NULL, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    const uint32_t bad_planes[] = {0, 1, 9, 1000};
    for (size_t i = 0; i < sizeof bad_planes / sizeof *bad_planes; ++i) {
        bd.planes = bad_planes[i];
        expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
        assert_non_null(strstr(d.message, "planes"));
    }
    bd = desc_of(s, XYL_BILLBOARD_SPHERICAL, 2);
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd = desc_of(s, (xyl_billboard_kind)7, 0);
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    const uint32_t bad_res[] = {0, 7, XYL_BILLBOARD_MAX_RESOLUTION + 1, UINT32_MAX};
    for (size_t i = 0; i < sizeof bad_res / sizeof *bad_res; ++i) {
        bd = desc_of(s, XYL_BILLBOARD_CYLINDRICAL, 0);
        bd.resolution = bad_res[i];
        expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
        assert_non_null(strstr(d.message, "resolution"));
    }
    bd = desc_of(s, XYL_BILLBOARD_CYLINDRICAL, 0);
    bd.hi[1] = bd.lo[1];
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    bd.hi[1] = NAN;
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_NON_FINITE, &d);
    assert_int_equal(s->calls, 0); /* nothing drawn for bad input */
    assert_null(bb);
    /* the callback's failure stops the bake and comes back as is */
    bd = desc_of(s, XYL_BILLBOARD_CROSS, 3);
    s->fail_with = XYL_ERR_LIMIT_EXCEEDED;
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_ERR_LIMIT_EXCEEDED, &d);
    assert_string_equal(d.message, "the test's draw fails");
    assert_int_equal(s->calls, 1);
    assert_null(bb);
    s->fail_with = XYL_OK;
    /* draws and reads */
    expect(xyl_billboard_gl_bake(&bd, draw_leaves, s, &bb, &d), XYL_OK, &d);
    xyl_billboard_gl_frame fr = {0};
    expect(xyl_billboard_gl_draw(NULL, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_gl_draw(bb, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_gl_draw(bb, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d); /* all-zero matrix */
    fr.view_proj[0] = fr.view_proj[5] = fr.view_proj[10] = fr.view_proj[15] = 1.0f;
    fr.eye[1] = NAN;
    expect(xyl_billboard_gl_draw(bb, &fr, &d), XYL_ERR_NON_FINITE, &d);
    fr.eye[1] = 0.0f;
    fr.alpha_cutoff = 2.0f;
    expect(xyl_billboard_gl_draw(bb, &fr, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    fr.alpha_cutoff = 0.0f;
    persp p = {0}; /* a good draw, into a complete framebuffer */
    memcpy(p.m, fr.view_proj, sizeof p.m);
    p.bb = bb;
    uint8_t *px = malloc(4 * SIDE * SIDE);
    assert_non_null(px);
    picture(s, paint_persp, &p, px);
    expect(xyl_billboard_gl_read_view(bb, 3, false, px, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_gl_read_view(bb, 0, false, NULL, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    expect(xyl_billboard_gl_read_view(NULL, 0, false, px, &d), XYL_ERR_INVALID_ARGUMENT, &d);
    assert_int_equal(xyl_billboard_gl_view_count(NULL), 0);
    free(px);
    xyl_billboard_gl_destroy(bb);
    xyl_billboard_gl_destroy(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(baked_views_are_the_trees_silhouette),
        cmocka_unit_test(billboard_from_its_bake_side_matches_the_tree),
        cmocka_unit_test(bad_input_gets_result_codes),
        cmocka_unit_test(octahedral_views_are_the_trees_silhouette),
        cmocka_unit_test(impostor_from_a_grid_direction_matches_the_tree),
        cmocka_unit_test(impostor_blend_is_continuous),
        cmocka_unit_test(octahedral_bad_input_gets_result_codes),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
