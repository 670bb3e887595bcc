/* Meshes: xyl_mesh_create / destroy (validation, copies, normals, triangulated view, allocator)
 * and the checks xyl_mesh_check and xyl_mesh_self_intersections (docs/mesh-checks.md). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "xylem/xyl_stems.h"

#define PI 3.14159265358979323846

/* ---- helpers: building meshes --------------------------------------------------------------- */

/* A growing mesh description owned by the test. */
typedef struct builder {
    xyl_vec3 *pos;
    size_t nv, cap_v;
    uint32_t *quads;
    size_t nq, cap_q;
    uint32_t *tris;
    size_t nt, cap_t;
} builder;

static void *grow(void *p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return p;
    size_t c = *cap ? *cap : 16;
    while (c < need) c *= 2;
    p = realloc(p, c * elem);
    assert_non_null(p);
    *cap = c;
    return p;
}

static uint32_t add_vertex(builder *b, double x, double y, double z)
{
    b->pos = grow(b->pos, &b->cap_v, b->nv + 1, sizeof *b->pos);
    b->pos[b->nv] = (xyl_vec3){(float)x, (float)y, (float)z};
    return (uint32_t)b->nv++;
}

static void add_quad(builder *b, uint32_t a, uint32_t c, uint32_t d, uint32_t e)
{
    b->quads = grow(b->quads, &b->cap_q, 4 * (b->nq + 1), sizeof *b->quads);
    uint32_t *q = b->quads + 4 * b->nq++;
    q[0] = a, q[1] = c, q[2] = d, q[3] = e;
}

static void add_tri(builder *b, uint32_t a, uint32_t c, uint32_t d)
{
    b->tris = grow(b->tris, &b->cap_t, 3 * (b->nt + 1), sizeof *b->tris);
    uint32_t *t = b->tris + 3 * b->nt++;
    t[0] = a, t[1] = c, t[2] = d;
}

static void builder_free(builder *b)
{
    free(b->pos);
    free(b->quads);
    free(b->tris);
    memset(b, 0, sizeof *b);
}

/* The 6 faces of a cube from its 8 corners (corner i at bit 0 = x, bit 1 = y, bit 2 = z),
 * counter-clockwise seen from outside. */
static const uint32_t cube_faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                          {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

/* Adds the 8 corners of an axis-aligned cube; returns the index of corner 0. */
static uint32_t add_cube_corners(builder *b, double x, double y, double z, double size)
{
    uint32_t first = (uint32_t)b->nv;
    for (int i = 0; i < 8; ++i)
        add_vertex(b, x + size * (i & 1), y + size * ((i >> 1) & 1), z + size * ((i >> 2) & 1));
    return first;
}

/* Adds the cube's faces over corners c[0..7], leaving out face `skip` (-1 for none). */
static void add_cube_faces(builder *b, const uint32_t c[8], int skip)
{
    for (int f = 0; f < 6; ++f)
        if (f != skip)
            add_quad(b, c[cube_faces[f][0]], c[cube_faces[f][1]], c[cube_faces[f][2]],
                     c[cube_faces[f][3]]);
}

static void add_cube(builder *b, double x, double y, double z, double size)
{
    uint32_t first = add_cube_corners(b, x, y, z, size), c[8];
    for (uint32_t i = 0; i < 8; ++i) c[i] = first + i;
    add_cube_faces(b, c, -1);
}

/* A cube turned by angle about a generic axis and moved, so that no face is parallel to one of
 * an axis-aligned cube (generic configurations for the reference comparisons). */
static void add_turned_cube(builder *b, double ox, double oy, double oz, double angle)
{
    double ax = 1 / sqrt(14.0), ay = 2 / sqrt(14.0), az = 3 / sqrt(14.0);
    double c = cos(angle), s = sin(angle), t = 1 - c;
    double r[3][3] = {{t * ax * ax + c, t * ax * ay - s * az, t * ax * az + s * ay},
                      {t * ax * ay + s * az, t * ay * ay + c, t * ay * az - s * ax},
                      {t * ax * az - s * ay, t * ay * az + s * ax, t * az * az + c}};
    uint32_t first = (uint32_t)b->nv, corners[8];
    for (int i = 0; i < 8; ++i) {
        double p[3] = {i & 1, (i >> 1) & 1, (i >> 2) & 1};
        add_vertex(b, ox + r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2],
                   oy + r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2],
                   oz + r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2]);
        corners[i] = first + (uint32_t)i;
    }
    add_cube_faces(b, corners, -1);
}

/* A torus of n x m quads (wrapping in both directions): Euler characteristic 0. */
static void add_torus(builder *b, int n, int m)
{
    uint32_t first = (uint32_t)b->nv;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            double u = 2 * PI * i / n, v = 2 * PI * j / m;
            add_vertex(b, (2 + 0.5 * cos(v)) * cos(u), (2 + 0.5 * cos(v)) * sin(u), 0.5 * sin(v));
        }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            int i1 = (i + 1) % n, j1 = (j + 1) % m;
            add_quad(b, first + (uint32_t)(i * m + j), first + (uint32_t)(i1 * m + j),
                     first + (uint32_t)(i1 * m + j1), first + (uint32_t)(i * m + j1));
        }
}

/* A deterministic value in [-1, 1) from an index (no rand()). */
static double hash_unit(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return (double)x / 2147483648.0 - 1.0;
}

/* A sphere from a cube whose faces are n x n grids, every vertex pushed out along its ray by a
 * pseudo-random amount: radial moves keep each triangle's central projection, so the mesh stays
 * free of self-intersections while no two faces are alike. 6 n^2 quads. */
static void add_bumpy_sphere(builder *b, int n)
{
    size_t side = (size_t)n + 1;
    uint32_t *id = malloc(side * side * side * sizeof *id);
    assert_non_null(id);
    for (size_t k = 0; k < side * side * side; ++k) {
        int p[3] = {(int)(k % side), (int)(k / side % side), (int)(k / side / side)};
        bool surface = false;
        for (int a = 0; a < 3; ++a) surface |= p[a] == 0 || p[a] == n;
        id[k] = UINT32_MAX;
        if (!surface) continue;
        double x = 2.0 * p[0] / n - 1, y = 2.0 * p[1] / n - 1, z = 2.0 * p[2] / n - 1;
        double r = (1.0 + 0.05 * hash_unit((uint32_t)k)) / sqrt(x * x + y * y + z * z);
        id[k] = add_vertex(b, r * x, r * y, r * z);
    }
    for (int a = 0; a < 3; ++a)
        for (int high = 0; high < 2; ++high)
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    uint32_t v[4];
                    const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
                    for (int c = 0; c < 4; ++c) {
                        int p[3];
                        p[a] = high ? n : 0;
                        p[(a + 1) % 3] = i + di[c];
                        p[(a + 2) % 3] = j + dj[c];
                        v[c] = id[(size_t)p[0] + side * ((size_t)p[1] + side * (size_t)p[2])];
                    }
                    /* (a+1, a+2) turns towards +a, so the low face runs the other way round. */
                    if (high)
                        add_quad(b, v[0], v[1], v[2], v[3]);
                    else
                        add_quad(b, v[0], v[3], v[2], v[1]);
                }
    free(id);
}

static xyl_mesh_desc desc_of(const builder *b)
{
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.positions = b->pos;
    d.vertex_count = b->nv;
    d.quads = b->quads;
    d.quad_count = b->nq;
    d.triangles = b->tris;
    d.triangle_count = b->nt;
    return d;
}

static xyl_mesh *make_mesh(const builder *b)
{
    xyl_mesh_desc d = desc_of(b);
    xyl_mesh *m = NULL;
    xyl_diag diag;
    memset(&diag, 0, sizeof diag);
    xyl_result r = xyl_mesh_create(&d, &m, &diag);
    if (r != XYL_OK) fail_msg("xyl_mesh_create: %s (%s)", xyl_result_string(r), diag.message);
    return m;
}

static xyl_mesh_report check(const builder *b)
{
    xyl_mesh *m = make_mesh(b);
    xyl_mesh_report rep;
    xyl_diag diag;
    memset(&diag, 0, sizeof diag);
    assert_int_equal(xyl_mesh_check(m, NULL, &rep, &diag), XYL_OK);
    assert_int_equal(diag.code, XYL_OK);
    xyl_mesh_destroy(m);
    return rep;
}

/* Number of self-intersecting pairs; fills up to cap pairs into out (may be NULL). */
static size_t intersections(const builder *b, uint32_t *out, size_t cap)
{
    xyl_mesh *m = make_mesh(b);
    size_t count = 12345;
    assert_int_equal(xyl_mesh_self_intersections(m, NULL, out, cap, &count, NULL), XYL_OK);
    xyl_mesh_destroy(m);
    return count;
}

static xyl_diag fresh_diag(void)
{
    xyl_diag d;
    memset(&d, 0, sizeof d);
    return d;
}

/* A recognisable non-NULL value that a failing create must leave in *out. */
static xyl_mesh untouched_mesh;
#define UNTOUCHED (&untouched_mesh)

/* Counts and optionally fails allocations; remembers live pointers. */
#define MAX_TRACKED 64
typedef struct counter {
    size_t attempts, allocs, frees;
    size_t fail_at; /* 1-based attempt that returns NULL; 0 = never */
    void *live[MAX_TRACKED];
} counter;

static void *count_alloc(size_t size, void *user)
{
    counter *c = user;
    if (++c->attempts == c->fail_at) return NULL;
    void *p = malloc(size);
    if (p && c->allocs < MAX_TRACKED) c->live[c->allocs] = p;
    if (p) c->allocs++;
    return p;
}

static void count_free(void *p, void *user)
{
    counter *c = user;
    c->frees++;
    free(p);
}

static bool tracked(const counter *c, const void *p)
{
    for (size_t i = 0; i < c->allocs && i < MAX_TRACKED; ++i)
        if (c->live[i] == p) return true;
    return false;
}

/* ---- a reference triangle test with its own arithmetic ------------------------------------- */

typedef struct d3 {
    double x, y, z;
} d3;

static d3 d3_of(xyl_vec3 v)
{
    return (d3){v.x, v.y, v.z};
}
static d3 sub(d3 a, d3 b)
{
    return (d3){a.x - b.x, a.y - b.y, a.z - b.z};
}
static double dot(d3 a, d3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static d3 cross(d3 a, d3 b)
{
    return (d3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/* Whether segment p-q meets triangle (a, b, c), from the point where it meets the plane and that
 * point's barycentric signs. For input that is not coplanar only: *ambiguous is set when the
 * answer hangs on a value too close to 0 to decide. */
static bool ref_segment_triangle(d3 p, d3 q, d3 a, d3 b, d3 c, bool *ambiguous)
{
    const double eps = 1e-9;
    d3 n = cross(sub(b, a), sub(c, a));
    double scale = sqrt(dot(n, n));
    double dp = dot(n, sub(p, a)) / scale, dq = dot(n, sub(q, a)) / scale;
    bool p_on = fabs(dp) < eps, q_on = fabs(dq) < eps;
    if (p_on && q_on) {
        *ambiguous = true;
        return false;
    }
    if (!p_on && !q_on && (dp > 0) == (dq > 0)) return false;
    double t = p_on ? 0.0 : q_on ? 1.0 : dp / (dp - dq);
    d3 x = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z)};
    double bary[3] = {dot(n, cross(sub(c, b), sub(x, b))), dot(n, cross(sub(a, c), sub(x, c))),
                      dot(n, cross(sub(b, a), sub(x, a)))};
    bool inside = true, outside = false;
    for (int k = 0; k < 3; ++k) {
        bary[k] /= scale * scale;
        inside &= bary[k] > eps;
        outside |= bary[k] < -eps;
    }
    if (!inside && !outside) *ambiguous = true;
    return inside;
}

/* Triangles i and j of the view intersect beyond their shared vertices (generic input with at
 * most one shared vertex; pairs sharing an edge are taken as not intersecting). */
static bool ref_pair(const xyl_mesh *m, uint32_t i, uint32_t j, bool *ambiguous)
{
    const uint32_t *a = m->tri_view + 3 * i, *b = m->tri_view + 3 * j;
    int shared = 0, sa = -1, sb = -1;
    for (int x = 0; x < 3; ++x)
        for (int y = 0; y < 3; ++y)
            if (a[x] == b[y]) shared++, sa = x, sb = y;
    if (shared >= 2) return false;
    d3 pa[3], pb[3];
    for (int k = 0; k < 3; ++k)
        pa[k] = d3_of(m->positions[a[k]]), pb[k] = d3_of(m->positions[b[k]]);
    bool hit = false;
    for (int e = 0; e < 3; ++e) {
        /* With a shared vertex only the edges opposite it can meet the other triangle elsewhere. */
        if (shared == 0 || e == (sa + 1) % 3)
            hit |= ref_segment_triangle(pa[e], pa[(e + 1) % 3], pb[0], pb[1], pb[2], ambiguous);
        if (shared == 0 || e == (sb + 1) % 3)
            hit |= ref_segment_triangle(pb[e], pb[(e + 1) % 3], pa[0], pa[1], pa[2], ambiguous);
    }
    return hit;
}

/* The library's pairs equal the brute-force reference over all pairs; returns the count. */
static size_t assert_pairs_match_reference(const builder *b)
{
    xyl_mesh *m = make_mesh(b);
    size_t n = m->tri_view_count, count = 0, expected = 0;
    assert_int_equal(xyl_mesh_self_intersections(m, NULL, NULL, 0, &count, NULL), XYL_OK);
    uint32_t *pairs = malloc(2 * (count + 1) * sizeof *pairs);
    assert_non_null(pairs);
    size_t again = 0;
    assert_int_equal(xyl_mesh_self_intersections(m, NULL, pairs, count, &again, NULL), XYL_OK);
    assert_int_equal(again, count);
    for (uint32_t i = 0; i < n; ++i)
        for (uint32_t j = i + 1; j < n; ++j) {
            bool ambiguous = false, hit = ref_pair(m, i, j, &ambiguous);
            assert_false(ambiguous);
            if (!hit) continue;
            if (expected >= count || pairs[2 * expected] != i || pairs[2 * expected + 1] != j)
                fail_msg("reference pair (%u, %u) is not reported at position %zu", i, j, expected);
            expected++;
        }
    assert_int_equal(expected, count);
    free(pairs);
    xyl_mesh_destroy(m);
    return count;
}

/* ---- xyl_mesh_create ------------------------------------------------------------------------ */

/* A square pyramid: one quad (the base, facing down) and four triangles. */
static void add_pyramid(builder *b)
{
    uint32_t v[5];
    v[0] = add_vertex(b, 0, 0, 0);
    v[1] = add_vertex(b, 1, 0, 0);
    v[2] = add_vertex(b, 1, 1, 0);
    v[3] = add_vertex(b, 0, 1, 0);
    v[4] = add_vertex(b, 0.5, 0.5, 1);
    add_quad(b, v[0], v[3], v[2], v[1]);
    add_tri(b, v[0], v[1], v[4]);
    add_tri(b, v[1], v[2], v[4]);
    add_tri(b, v[2], v[3], v[4]);
    add_tri(b, v[3], v[0], v[4]);
}

static void create_copies_arrays_and_builds_triangulated_view(void **state)
{
    (void)state;
    builder b = {0};
    add_pyramid(&b);
    xyl_mesh *m = make_mesh(&b);
    assert_int_equal(m->vertex_count, 5);
    assert_int_equal(m->quad_count, 1);
    assert_int_equal(m->triangle_count, 4);
    assert_ptr_not_equal(m->positions, b.pos);
    assert_memory_equal(m->positions, b.pos, 5 * sizeof *b.pos);
    assert_memory_equal(m->quads, b.quads, 4 * sizeof *b.quads);
    assert_memory_equal(m->triangles, b.tris, 12 * sizeof *b.tris);
    /* The quad (a, b, c, d) splits into (a, b, c), (a, c, d); the triangles follow as given. */
    const uint32_t view[18] = {0, 3, 2, 0, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    assert_int_equal(m->tri_view_count, 6);
    assert_memory_equal(m->tri_view, view, sizeof view);
    /* The mesh owns copies: changing the input afterwards changes nothing. */
    b.pos[0].x = 42;
    b.quads[0] = 4;
    assert_true(m->positions[0].x == 0.0f);
    assert_int_equal(m->quads[0], 0);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

static void create_fills_absent_optional_arrays_with_zeros(void **state)
{
    (void)state;
    builder b = {0};
    add_pyramid(&b);
    xyl_mesh *m = make_mesh(&b);
    for (size_t v = 0; v < 5; ++v) {
        assert_true(m->uvs[2 * v] == 0.0f && m->uvs[2 * v + 1] == 0.0f);
        assert_int_equal(m->branch_ids[v], 0);
    }
    for (size_t f = 0; f < 5; ++f) assert_int_equal(m->face_branches[f], 0);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

static void create_copies_given_optional_arrays(void **state)
{
    (void)state;
    builder b = {0};
    add_pyramid(&b);
    xyl_vec3 normals[5];
    float uvs[10];
    uint32_t branch_ids[5], face_branches[5] = {7, 8, 9, 10, 11};
    for (int v = 0; v < 5; ++v) {
        normals[v] = (xyl_vec3){0, 0, v % 2 ? 1.0f : -1.0f};
        uvs[2 * v] = 0.25f * (float)v;
        uvs[2 * v + 1] = 1.0f - 0.125f * (float)v;
        branch_ids[v] = (uint32_t)(3 * v + 1);
    }
    xyl_mesh_desc d = desc_of(&b);
    d.normals = normals;
    d.uvs = uvs;
    d.branch_ids = branch_ids;
    d.face_branches = face_branches;
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_mesh_create(&d, &m, NULL), XYL_OK);
    assert_memory_equal(m->normals, normals, sizeof normals);
    assert_memory_equal(m->uvs, uvs, sizeof uvs);
    assert_memory_equal(m->branch_ids, branch_ids, sizeof branch_ids);
    assert_memory_equal(m->face_branches, face_branches, sizeof face_branches);
    assert_ptr_not_equal(m->face_branches, face_branches);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

static void create_computes_unit_outward_normals_on_a_cube(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, -1, 2, 3, 2);
    xyl_mesh *m = make_mesh(&b);
    const double centre[3] = {0, 3, 4}, third = 1 / sqrt(3.0);
    for (size_t v = 0; v < 8; ++v) {
        xyl_vec3 n = m->normals[v], p = m->positions[v];
        double len = sqrt((double)n.x * n.x + (double)n.y * n.y + (double)n.z * n.z);
        assert_true(fabs(len - 1) < 1e-6);
        /* Three equal faces meet at a corner: the normal is the diagonal, pointing outward. */
        const double out[3] = {p.x - centre[0], p.y - centre[1], p.z - centre[2]};
        const float comp[3] = {n.x, n.y, n.z};
        for (int k = 0; k < 3; ++k) assert_true(fabs(comp[k] - copysign(third, out[k])) < 1e-6);
    }
    xyl_mesh_destroy(m);
    builder_free(&b);
}

static void create_gives_an_unused_vertex_the_up_normal(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    add_vertex(&b, 5, 5, 5);
    xyl_mesh *m = make_mesh(&b);
    xyl_vec3 n = m->normals[8];
    assert_true(n.x == 0.0f && n.y == 1.0f && n.z == 0.0f);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

static void create_accepts_an_empty_mesh(void **state)
{
    (void)state;
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    xyl_mesh *m = NULL;
    xyl_diag diag = fresh_diag();
    diag.index = 99;
    assert_int_equal(xyl_mesh_create(&d, &m, &diag), XYL_OK);
    assert_int_equal(diag.code, XYL_OK);
    assert_int_equal(diag.index, -1);
    assert_string_equal(diag.message, "");
    assert_int_equal(m->vertex_count + m->quad_count + m->triangle_count + m->tri_view_count, 0);
    xyl_mesh_destroy(m);
}

/* desc must fail with code and diag.index, leaving *out alone and saying why. */
static void expect_create_error(const xyl_mesh_desc *d, xyl_result code, int64_t index)
{
    xyl_mesh *m = UNTOUCHED;
    xyl_diag diag = fresh_diag();
    xyl_result r = xyl_mesh_create(d, &m, &diag);
    if (r != code || diag.code != code || diag.index != index)
        fail_msg("expected %s at index %lld, got %s at %lld (%s)", xyl_result_string(code),
                 (long long)index, xyl_result_string(r), (long long)diag.index, diag.message);
    assert_ptr_equal(m, UNTOUCHED);
    assert_true(strlen(diag.message) > 0);
}

static void create_rejects_null_desc_and_out(void **state)
{
    (void)state;
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    xyl_mesh *m = UNTOUCHED;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_create(NULL, &m, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.index, -1);
    assert_ptr_equal(m, UNTOUCHED);
    assert_int_equal(xyl_mesh_create(&d, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_create(&d, NULL, NULL), XYL_ERR_INVALID_ARGUMENT);
}

static void create_rejects_null_arrays_with_counts(void **state)
{
    (void)state;
    builder b = {0};
    add_pyramid(&b);
    xyl_mesh_desc d = desc_of(&b);
    d.positions = NULL;
    expect_create_error(&d, XYL_ERR_INVALID_ARGUMENT, -1);
    d = desc_of(&b);
    d.quads = NULL;
    expect_create_error(&d, XYL_ERR_INVALID_ARGUMENT, -1);
    d = desc_of(&b);
    d.triangles = NULL;
    expect_create_error(&d, XYL_ERR_INVALID_ARGUMENT, -1);
    builder_free(&b);
}

static void create_rejects_out_of_range_indices_naming_the_face(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    add_tri(&b, 0, 1, 2);
    add_tri(&b, 0, 1, 3);
    xyl_mesh_desc d = desc_of(&b);
    b.quads[4 * 2 + 3] = 8; /* quad 2 */
    expect_create_error(&d, XYL_ERR_INVALID_ARGUMENT, 2);
    b.quads[4 * 2 + 3] = 4;
    b.tris[3 * 1 + 2] = 100; /* triangle 1: face 6 + 1 */
    expect_create_error(&d, XYL_ERR_INVALID_ARGUMENT, 7);
    builder_free(&b);
}

static void create_rejects_a_face_repeating_a_vertex(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    add_tri(&b, 0, 1, 2);
    xyl_mesh_desc d = desc_of(&b);
    uint32_t keep = b.quads[4 * 5 + 2];
    b.quads[4 * 5 + 2] = b.quads[4 * 5 + 0];
    expect_create_error(&d, XYL_ERR_INVALID_ARGUMENT, 5);
    b.quads[4 * 5 + 2] = keep;
    b.tris[2] = 1;
    expect_create_error(&d, XYL_ERR_INVALID_ARGUMENT, 6);
    builder_free(&b);
}

static void create_rejects_non_finite_numbers_naming_the_vertex(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    xyl_vec3 normals[8];
    float uvs[16] = {0};
    for (int v = 0; v < 8; ++v) normals[v] = (xyl_vec3){0, 1, 0};
    xyl_mesh_desc d = desc_of(&b);
    b.pos[3].y = NAN;
    expect_create_error(&d, XYL_ERR_NON_FINITE, 3);
    b.pos[3].y = 1;
    b.pos[6].z = -INFINITY;
    expect_create_error(&d, XYL_ERR_NON_FINITE, 6);
    b.pos[6].z = 1;
    d.normals = normals;
    normals[5].x = INFINITY;
    expect_create_error(&d, XYL_ERR_NON_FINITE, 5);
    normals[5].x = 0;
    d.uvs = uvs;
    uvs[2 * 7 + 1] = NAN;
    expect_create_error(&d, XYL_ERR_NON_FINITE, 7);
    builder_free(&b);
}

static void create_enforces_limits(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    xyl_mesh_desc d = desc_of(&b);
    d.limits.max_vertices = 7;
    expect_create_error(&d, XYL_ERR_LIMIT_EXCEEDED, -1);
    d.limits.max_vertices = 8;
    d.limits.max_faces = 5;
    expect_create_error(&d, XYL_ERR_LIMIT_EXCEEDED, -1);
    d.limits.max_faces = 6;
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_mesh_create(&d, &m, NULL), XYL_OK);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

static void create_survives_every_allocation_failure(void **state)
{
    (void)state;
    builder b = {0};
    add_pyramid(&b);
    for (size_t k = 1;; ++k) {
        counter c;
        memset(&c, 0, sizeof c);
        c.fail_at = k;
        xyl_mesh_desc d = desc_of(&b);
        d.alloc = (xyl_allocator){count_alloc, count_free, &c};
        xyl_mesh *m = UNTOUCHED;
        xyl_result r = xyl_mesh_create(&d, &m, NULL);
        if (r == XYL_OK) {
            xyl_mesh_destroy(m);
            assert_int_equal(c.allocs, c.frees);
            assert_true(k > 1);
            break;
        }
        assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
        assert_ptr_equal(m, UNTOUCHED);
        assert_int_equal(c.allocs, c.frees);
        assert_true(k < 32);
    }
    builder_free(&b);
}

static void create_takes_every_array_from_the_allocator(void **state)
{
    (void)state;
    builder b = {0};
    add_pyramid(&b);
    counter c;
    memset(&c, 0, sizeof c);
    xyl_mesh_desc d = desc_of(&b);
    d.alloc = (xyl_allocator){count_alloc, count_free, &c};
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_mesh_create(&d, &m, NULL), XYL_OK);
    const void *arrays[] = {m,           m->positions,     m->normals,  m->uvs,
                            m->branch_ids, m->quads,       m->triangles, m->face_branches,
                            m->tri_view, m->uv_wraps};
    for (size_t i = 0; i < sizeof arrays / sizeof *arrays; ++i) assert_true(tracked(&c, arrays[i]));
    /* Scratch (the normal sums) is already back; exactly the mesh's own blocks are live. */
    assert_int_equal(c.allocs - c.frees, sizeof arrays / sizeof *arrays);
    xyl_mesh_destroy(m);
    assert_int_equal(c.allocs, c.frees);
    builder_free(&b);
}

static void destroy_accepts_null(void **state)
{
    (void)state;
    xyl_mesh_destroy(NULL);
}

/* ---- xyl_mesh_check ------------------------------------------------------------------------- */

static void assert_closed(const xyl_mesh_report *r)
{
    assert_int_equal(r->boundary_edges, 0);
    assert_int_equal(r->nonmanifold_edges, 0);
    assert_int_equal(r->misoriented_edges, 0);
    assert_int_equal(r->nonmanifold_vertices, 0);
    assert_int_equal(r->degenerate_faces, 0);
    assert_int_equal(r->duplicate_faces, 0);
    assert_true(r->closed_manifold);
}

static void check_finds_a_cube_closed_with_euler_2(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.vertices, 8);
    assert_int_equal(r.edges, 12); /* quad diagonals are not edges */
    assert_int_equal(r.faces, 6);
    assert_int_equal(r.euler, 2);
    assert_int_equal(r.components, 1);
    assert_int_equal(r.unused_vertices, 0);
    assert_closed(&r);
    builder_free(&b);
}

static void check_accepts_mixed_quads_and_triangles(void **state)
{
    (void)state;
    builder b = {0};
    add_pyramid(&b);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.edges, 8);
    assert_int_equal(r.euler, 2);
    assert_int_equal(r.components, 1);
    assert_closed(&r);
    builder_free(&b);
}

static void check_counts_the_boundary_of_an_open_cube(void **state)
{
    (void)state;
    builder b = {0};
    uint32_t c[8];
    uint32_t first = add_cube_corners(&b, 0, 0, 0, 1);
    for (uint32_t i = 0; i < 8; ++i) c[i] = first + i;
    add_cube_faces(&b, c, 1);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.boundary_edges, 4);
    assert_int_equal(r.nonmanifold_vertices, 0); /* one open fan per rim vertex */
    assert_int_equal(r.euler, 1);
    assert_int_equal(r.components, 1);
    assert_false(r.closed_manifold);
    builder_free(&b);
}

static void check_finds_the_edges_of_a_flipped_face_misoriented(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    uint32_t *q = b.quads + 4 * 3, t = q[1];
    q[1] = q[3];
    q[3] = t;
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.misoriented_edges, 4);
    assert_int_equal(r.boundary_edges, 0);
    assert_int_equal(r.nonmanifold_vertices, 0);
    assert_int_equal(r.euler, 2);
    assert_false(r.closed_manifold);
    builder_free(&b);
}

static void check_finds_a_bow_tie_vertex_and_two_components(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    /* A second cube whose corner 0 is the first cube's corner 7, (1, 1, 1). */
    uint32_t first = add_cube_corners(&b, 1, 1, 1, 1), c[8];
    for (uint32_t i = 0; i < 8; ++i) c[i] = first + i;
    c[0] = 7;
    add_cube_faces(&b, c, -1);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.nonmanifold_vertices, 1);
    assert_int_equal(r.components, 2);
    assert_int_equal(r.boundary_edges + r.nonmanifold_edges + r.misoriented_edges, 0);
    assert_int_equal(r.unused_vertices, 1); /* the second cube's own corner 0 */
    assert_int_equal(r.euler, 16 - 24 + 12);
    assert_false(r.closed_manifold);
    builder_free(&b);

    /* Two open fans at one vertex: two triangles touching at a corner. */
    builder t = {0};
    add_vertex(&t, 0, 0, 0);
    add_vertex(&t, 1, 0, 0);
    add_vertex(&t, 1, 1, 0);
    add_vertex(&t, -1, 0, 0);
    add_vertex(&t, -1, -1, 0);
    add_tri(&t, 0, 1, 2);
    add_tri(&t, 0, 3, 4);
    r = check(&t);
    assert_int_equal(r.nonmanifold_vertices, 1);
    assert_int_equal(r.boundary_edges, 6);
    assert_int_equal(r.components, 2);
    builder_free(&t);
}

static void check_finds_three_quads_on_one_edge_non_manifold(void **state)
{
    (void)state;
    builder b = {0};
    uint32_t e0 = add_vertex(&b, 0, 0, 0), e1 = add_vertex(&b, 0, 0, 1);
    for (int k = 0; k < 3; ++k) {
        double a = 2 * PI * k / 3;
        uint32_t p = add_vertex(&b, cos(a), sin(a), 0), q = add_vertex(&b, cos(a), sin(a), 1);
        add_quad(&b, e0, p, q, e1);
    }
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.nonmanifold_edges, 1);
    assert_int_equal(r.boundary_edges, 9);
    /* The shared edge joins no fans, so both its ends see three separate fans. */
    assert_int_equal(r.nonmanifold_vertices, 2);
    assert_int_equal(r.components, 1);
    assert_int_equal(r.euler, 8 - 10 + 3);
    assert_false(r.closed_manifold);
    builder_free(&b);
}

static void check_counts_both_faces_of_a_duplicate_pair(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    const uint32_t *q = b.quads + 4 * 2;
    add_quad(&b, q[2], q[1], q[0], q[3]); /* the same vertex set in another order */
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.duplicate_faces, 2);
    assert_false(r.closed_manifold);
    builder_free(&b);

    builder t = {0};
    add_pyramid(&t);
    add_tri(&t, 2, 4, 1); /* (1, 2, 4) again */
    add_tri(&t, 4, 1, 2);
    r = check(&t);
    assert_int_equal(r.duplicate_faces, 3);
    builder_free(&t);
}

static void check_finds_degenerate_faces_relative_to_the_mesh_size(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1000);
    /* Collinear: zero area. */
    uint32_t a = add_vertex(&b, 0, 0, 2000), c = add_vertex(&b, 1, 1, 2001),
             d = add_vertex(&b, 2, 2, 2002);
    add_tri(&b, a, c, d);
    /* Coincident corners of a quad: one triangle of its split has no area. */
    uint32_t q0 = add_vertex(&b, 0, 3000, 0), q1 = add_vertex(&b, 10, 3000, 0);
    uint32_t q2 = add_vertex(&b, 10, 3000, 0), q3 = add_vertex(&b, 0, 3010, 0);
    add_quad(&b, q0, q1, q2, q3);
    /* Area 0.5 against a tolerance of 1e-12 * (bounding box diagonal 5100)^2 = 2.6e-5. */
    uint32_t s0 = add_vertex(&b, 0, 0, -1000), s1 = add_vertex(&b, 1, 0, -1000);
    uint32_t s2 = add_vertex(&b, 0, 1, -1000);
    add_tri(&b, s0, s1, s2);
    /* Area 5e-7, below the tolerance: degenerate although no corners coincide. */
    uint32_t t0 = add_vertex(&b, 0, 0, -2000), t1 = add_vertex(&b, 1000, 0, -2000);
    uint32_t t2 = add_vertex(&b, 0, 1e-9, -2000);
    add_tri(&b, t0, t1, t2);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.degenerate_faces, 3);
    assert_false(r.closed_manifold);
    builder_free(&b);
}

static void check_finds_a_quad_torus_closed_with_euler_0(void **state)
{
    (void)state;
    builder b = {0};
    add_torus(&b, 24, 12);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.faces, 288);
    assert_int_equal(r.edges, 576);
    assert_int_equal(r.euler, 0);
    assert_int_equal(r.components, 1);
    assert_closed(&r);
    builder_free(&b);
}

static void check_counts_two_disjoint_cubes_as_two_components(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    add_cube(&b, 5, 0, 0, 1);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.components, 2);
    assert_int_equal(r.euler, 4);
    assert_closed(&r);
    builder_free(&b);
}

static void check_reports_unused_vertices_apart_from_closedness(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    add_vertex(&b, 9, 9, 9);
    add_vertex(&b, -9, 9, 9);
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.unused_vertices, 2);
    assert_int_equal(r.vertices, 10);
    assert_int_equal(r.euler, 4); /* V counts every vertex */
    assert_closed(&r);
    builder_free(&b);
}

static void check_of_an_empty_mesh_is_all_zero(void **state)
{
    (void)state;
    builder b = {0};
    xyl_mesh_report r = check(&b);
    assert_int_equal(r.vertices + r.edges + r.faces + r.components, 0);
    assert_int_equal(r.euler, 0);
    assert_true(r.closed_manifold);
}

static void check_rejects_null_arguments(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    xyl_mesh *m = make_mesh(&b);
    xyl_mesh_report r;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_check(NULL, NULL, &r, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.code, XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_check(m, NULL, NULL, NULL), XYL_ERR_INVALID_ARGUMENT);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

/* A view the caller made must fail with code at index, leaving the report alone. */
static void expect_check_error(const xyl_mesh *view, xyl_result code, int64_t index)
{
    xyl_mesh_report r;
    memset(&r, 0xAB, sizeof r);
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_check(view, NULL, &r, &diag), code);
    assert_int_equal(diag.code, code);
    assert_int_equal(diag.index, index);
    assert_true(strlen(diag.message) > 0);
    unsigned char *p = (unsigned char *)&r;
    for (size_t i = 0; i < sizeof r; ++i) assert_int_equal(p[i], 0xAB);
}

static void check_validates_a_caller_made_view(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    add_tri(&b, 0, 1, 2);
    xyl_mesh view;
    memset(&view, 0, sizeof view);
    view.positions = b.pos;
    view.vertex_count = b.nv;
    view.quads = b.quads;
    view.quad_count = b.nq;
    view.triangles = b.tris;
    view.triangle_count = b.nt;
    xyl_mesh_report r;
    assert_int_equal(xyl_mesh_check(&view, NULL, &r, NULL), XYL_OK);
    b.tris[1] = 8;
    expect_check_error(&view, XYL_ERR_INVALID_ARGUMENT, 6);
    b.tris[1] = 0;
    expect_check_error(&view, XYL_ERR_INVALID_ARGUMENT, 6);
    b.tris[1] = 1;
    b.pos[4].x = NAN;
    expect_check_error(&view, XYL_ERR_NON_FINITE, 4);
    b.pos[4].x = 0;
    view.quads = NULL;
    expect_check_error(&view, XYL_ERR_INVALID_ARGUMENT, -1);
    builder_free(&b);
}

/* A view with normals and UVs (now checked wherever they are given: finite, as in a desc) must
 * be refused by the check, the intersection test and the seam split, naming the vertex. */
static void calls_refuse_a_view_with_a_non_finite_normal_or_uv(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    xyl_mesh *m = make_mesh(&b);
    xyl_vec3 normals[8];
    float uvs[16];
    memcpy(normals, m->normals, sizeof normals);
    memcpy(uvs, m->uvs, sizeof uvs);
    xyl_mesh view = *m;
    view.normals = normals;
    view.uvs = uvs;
    for (int bad = 0; bad < 3; ++bad) {
        normals[3].y = bad == 0 ? NAN : m->normals[3].y;
        uvs[2 * 5 + 1] = bad == 1 ? INFINITY : m->uvs[2 * 5 + 1];
        int64_t vertex = bad == 0 ? 3 : 5;
        xyl_result want = bad < 2 ? XYL_ERR_NON_FINITE : XYL_OK;
        xyl_mesh_report r;
        size_t count = 77;
        xyl_mesh *split = UNTOUCHED;
        xyl_diag diag = fresh_diag();
        assert_int_equal(xyl_mesh_check(&view, NULL, &r, &diag), want);
        if (want) assert_int_equal(diag.index, vertex);
        diag = fresh_diag();
        assert_int_equal(xyl_mesh_self_intersections(&view, NULL, NULL, 0, &count, &diag), want);
        if (want) assert_int_equal(diag.index, vertex);
        if (want) assert_int_equal(count, 77);
        diag = fresh_diag();
        assert_int_equal(xyl_mesh_split_seams(&view, NULL, &split, &diag), want);
        if (want) assert_int_equal(diag.index, vertex);
        if (want) assert_ptr_equal(split, UNTOUCHED);
        else xyl_mesh_destroy(split);
    }
    /* the seam split reads every array, so it is refused a non-finite position too */
    xyl_vec3 pos[8];
    memcpy(pos, m->positions, sizeof pos);
    pos[6].z = -INFINITY;
    view.positions = pos;
    xyl_mesh *split = UNTOUCHED;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_split_seams(&view, NULL, &split, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(diag.index, 6);
    assert_ptr_equal(split, UNTOUCHED);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

/* ---- xyl_mesh_self_intersections ------------------------------------------------------------ */

static void self_intersections_of_a_cube_are_none(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    assert_int_equal(intersections(&b, NULL, 0), 0);
    builder_free(&b);
}

static void self_intersections_of_a_torus_are_none(void **state)
{
    (void)state;
    builder b = {0};
    add_torus(&b, 48, 16);
    assert_int_equal(intersections(&b, NULL, 0), 0);
    builder_free(&b);
}

static void self_intersections_of_interpenetrating_cubes_are_genuine(void **state)
{
    (void)state;
    builder b = {0};
    add_turned_cube(&b, 0, 0, 0, 0.1);
    add_turned_cube(&b, 0.45, 0.35, 0.3, 0.7);
    size_t n = assert_pairs_match_reference(&b);
    assert_true(n > 0);
    builder_free(&b);
}

static void self_intersections_of_separate_cubes_are_none(void **state)
{
    (void)state;
    builder b = {0};
    add_turned_cube(&b, 0, 0, 0, 0.1);
    add_turned_cube(&b, 1.8, 0.2, 0.1, 0.7);
    assert_int_equal(assert_pairs_match_reference(&b), 0);
    builder_free(&b);
}

static void self_intersections_find_a_fold_between_triangles_that_share_a_vertex(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    b.pos[7] = (xyl_vec3){0.35f, 0.45f, -0.5f}; /* corner (1, 1, 1) pushed through the bottom */
    size_t n = assert_pairs_match_reference(&b);
    assert_true(n > 0);
    /* Some of the pairs found share exactly one vertex. */
    xyl_mesh *m = make_mesh(&b);
    uint32_t *pairs = malloc(2 * n * sizeof *pairs);
    assert_non_null(pairs);
    size_t count = 0, one_shared = 0;
    assert_int_equal(xyl_mesh_self_intersections(m, NULL, pairs, n, &count, NULL), XYL_OK);
    for (size_t k = 0; k < count; ++k) {
        const uint32_t *a = m->tri_view + 3 * pairs[2 * k], *c = m->tri_view + 3 * pairs[2 * k + 1];
        int shared = 0;
        for (int x = 0; x < 3; ++x)
            for (int y = 0; y < 3; ++y) shared += a[x] == c[y];
        one_shared += shared == 1;
    }
    assert_true(one_shared > 0);
    free(pairs);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

/* Two triangles sharing vertex s = (0, 0, 0): a = (s, (2,0,0), (0,2,0)) and (s, p, q). */
static size_t shared_vertex_pair(xyl_vec3 p, xyl_vec3 q)
{
    builder b = {0};
    uint32_t s = add_vertex(&b, 0, 0, 0), a1 = add_vertex(&b, 2, 0, 0),
             a2 = add_vertex(&b, 0, 2, 0);
    uint32_t b1 = add_vertex(&b, p.x, p.y, p.z), b2 = add_vertex(&b, q.x, q.y, q.z);
    add_tri(&b, s, a1, a2);
    add_tri(&b, s, b1, b2);
    size_t n = intersections(&b, NULL, 0);
    builder_free(&b);
    return n;
}

static void self_intersections_with_one_shared_vertex_look_beyond_it(void **state)
{
    (void)state;
    /* Through the other triangle's interior. */
    assert_int_equal(shared_vertex_pair((xyl_vec3){0.5f, 0.5f, 1}, (xyl_vec3){0.6f, 0.4f, -1}), 1);
    /* Both far corners above the plane: they meet only at s. */
    assert_int_equal(shared_vertex_pair((xyl_vec3){0.5f, 0.5f, 1}, (xyl_vec3){0.6f, 0.4f, 0.5f}),
                     0);
    /* Coplanar, inside the other's corner: overlap. */
    assert_int_equal(shared_vertex_pair((xyl_vec3){1, 0.2f, 0}, (xyl_vec3){1, 0.5f, 0}), 1);
    /* Coplanar, in the opposite corner: only s in common. */
    assert_int_equal(shared_vertex_pair((xyl_vec3){-1, -0.2f, 0}, (xyl_vec3){-1, -0.5f, 0}), 0);
    /* Coplanar, sharing the direction of an edge: they overlap along it. */
    assert_int_equal(shared_vertex_pair((xyl_vec3){1, 0, 0}, (xyl_vec3){1, -1, 0}), 1);
    /* Out of the plane, the edge to a far corner on the other's far edge lies in the other. */
    assert_int_equal(shared_vertex_pair((xyl_vec3){1, 1, 0}, (xyl_vec3){0.2f, 0.2f, 1}), 1);
}

/* Two triangles of one flat side of a straight prism, after one Catmull-Clark level (xylem's
 * own stem_up hard case at k = 4): they share one corner and lie in one plane but for 1e-18 in
 * x. A far corner of one then falls within the error bound of the other's plane while its
 * partner does not, and the line through them was tested for piercing the other triangle with
 * volumes all within their bounds too, so "on every side" read as a hit: 27 such pairs on that
 * stem. The corner on the plane is now tested for lying in the triangle, as coplanar points are. */
static void self_intersections_of_nearly_coplanar_neighbours_are_none(void **state)
{
    (void)state;
    builder b = {0};
    uint32_t v40 = add_vertex(&b, 0x1.1db9ap-4f, 0x1p-1f, -0x1.1db9ap-4f);
    uint32_t v5 = add_vertex(&b, 0x1.90b6c6p-59f, 0x1p-1f, -0x1.9f99a2p-4f);
    uint32_t v50 = add_vertex(&b, 0x1.c71c72p-60f, 0x1.8p-1f, -0x1.9f99a2p-4f);
    uint32_t v24 = add_vertex(&b, 0x1.1db9ap-4f, 0x1.8p-1f, -0x1.1db9ap-4f);
    uint32_t v9 = add_vertex(&b, 0x1.90b6c6p-59f, 0x1p+0f, -0x1.9f99a2p-4f);
    add_tri(&b, v40, v5, v50);
    add_tri(&b, v24, v50, v9);
    assert_int_equal(intersections(&b, NULL, 0), 0);
    builder_free(&b);
}

/* Two triangles sharing the edge (0,0,0)-(1,0,0), with third corners c and d. */
static size_t shared_edge_pair(xyl_vec3 c, xyl_vec3 d)
{
    builder b = {0};
    uint32_t e0 = add_vertex(&b, 0, 0, 0), e1 = add_vertex(&b, 1, 0, 0);
    uint32_t v0 = add_vertex(&b, c.x, c.y, c.z), v1 = add_vertex(&b, d.x, d.y, d.z);
    add_tri(&b, e0, e1, v0);
    add_tri(&b, e1, e0, v1);
    size_t n = intersections(&b, NULL, 0);
    builder_free(&b);
    return n;
}

static void self_intersections_with_a_shared_edge_count_only_a_flat_fold(void **state)
{
    (void)state;
    assert_int_equal(shared_edge_pair((xyl_vec3){0.5f, 1, 0}, (xyl_vec3){0.5f, -1, 0}), 0);
    assert_int_equal(shared_edge_pair((xyl_vec3){0.5f, 1, 0}, (xyl_vec3){0.5f, 1, 1}), 0);
    assert_int_equal(shared_edge_pair((xyl_vec3){0.5f, 1, 0}, (xyl_vec3){0.7f, 0.5f, 0}), 1);
    /* The two halves of a flat, convex quad: none. */
    builder b = {0};
    add_vertex(&b, 0, 0, 0);
    add_vertex(&b, 1, 0, 0);
    add_vertex(&b, 1, 1, 0);
    add_vertex(&b, 0, 1, 0);
    add_quad(&b, 0, 1, 2, 3);
    assert_int_equal(intersections(&b, NULL, 0), 0);
    builder_free(&b);
}

/* Triangle t[0..2] and a second one, p q r, with its own three vertices. */
static size_t separate_pair_at(const xyl_vec3 t[3], xyl_vec3 p, xyl_vec3 q, xyl_vec3 r)
{
    builder b = {0};
    for (int i = 0; i < 3; ++i) add_vertex(&b, t[i].x, t[i].y, t[i].z);
    add_vertex(&b, p.x, p.y, p.z);
    add_vertex(&b, q.x, q.y, q.z);
    add_vertex(&b, r.x, r.y, r.z);
    add_tri(&b, 0, 1, 2);
    add_tri(&b, 3, 4, 5);
    size_t n = intersections(&b, NULL, 0);
    builder_free(&b);
    return n;
}

/* Triangle (0,0,0), (1,0,0), (0,1,0) and a second one with its own three vertices. */
static size_t separate_pair(xyl_vec3 p, xyl_vec3 q, xyl_vec3 r)
{
    static const xyl_vec3 unit[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    return separate_pair_at(unit, p, q, r);
}

static void self_intersections_count_distinct_triangles_that_touch(void **state)
{
    (void)state;
    /* At a corner: the same position, different vertices. */
    assert_int_equal(separate_pair((xyl_vec3){1, 0, 0}, (xyl_vec3){2, 0, 1}, (xyl_vec3){2, 1, -1}),
                     1);
    /* A corner on the other's interior. */
    assert_int_equal(
        separate_pair((xyl_vec3){0.25f, 0.25f, 0}, (xyl_vec3){1, 1, 1}, (xyl_vec3){0, 1, 1}), 1);
    /* Along an edge, coplanar, outside each other. */
    assert_int_equal(separate_pair((xyl_vec3){1, 0, 0}, (xyl_vec3){0, 1, 0}, (xyl_vec3){1, 1, 0}),
                     1);
}

static void self_intersections_count_coplanar_overlap(void **state)
{
    (void)state;
    assert_int_equal(separate_pair((xyl_vec3){0.2f, 0.2f, 0}, (xyl_vec3){1.2f, 0.2f, 0},
                                   (xyl_vec3){0.2f, 1.2f, 0}),
                     1);
    /* Wholly inside: no edges cross. */
    assert_int_equal(separate_pair((xyl_vec3){0.1f, 0.1f, 0}, (xyl_vec3){0.3f, 0.1f, 0},
                                   (xyl_vec3){0.1f, 0.3f, 0}),
                     1);
    /* Coplanar and apart. */
    assert_int_equal(separate_pair((xyl_vec3){0.6f, 0.6f, 0}, (xyl_vec3){1.6f, 0.6f, 0},
                                   (xyl_vec3){0.6f, 1.6f, 0}),
                     0);
}

/* Near misses whose boxes overlap, so that the exact test decides, not the broad phase; with
 * gap 0 each of them touches. */
static void near_misses(float e, size_t expect)
{
    /* Coplanar, a corner just beyond the hypotenuse. */
    assert_int_equal(separate_pair((xyl_vec3){0.5f + e, 0.5f + e, 0}, (xyl_vec3){1.2f, 0.4f, 0},
                                   (xyl_vec3){0.4f, 1.2f, 0}),
                     expect);
    /* Upright in the plane x = y, its edge just beyond the hypotenuse. */
    assert_int_equal(separate_pair((xyl_vec3){0.5f + e, 0.5f + e, -1},
                                   (xyl_vec3){0.5f + e, 0.5f + e, 1}, (xyl_vec3){2, 2, 0}),
                     expect);
    /* Tilted, in the plane z = e + 1 - x - y: above the triangle, by e at the hypotenuse, and
     * below its plane only beyond it (binary fractions, so that gap 0 touches exactly). */
    assert_int_equal(separate_pair((xyl_vec3){0.25f, 0.625f, e + 0.125f},
                                   (xyl_vec3){1.25f, 1.25f, e - 1.5f},
                                   (xyl_vec3){0.625f, 0.25f, e + 0.125f}),
                     expect);
}

static void self_intersections_ignore_a_near_miss(void **state)
{
    (void)state;
    const float e = 1e-6f;
    near_misses(e, 0);
    near_misses(0, 1);
    /* Parallel, one above the other (apart already by their boxes). */
    assert_int_equal(separate_pair((xyl_vec3){0, 0, e}, (xyl_vec3){1, 0, e}, (xyl_vec3){0, 1, e}),
                     0);
    /* Edges crossing with a gap. */
    assert_int_equal(separate_pair((xyl_vec3){0.5f, -0.5f, e}, (xyl_vec3){0.5f, 0.5f, e},
                                   (xyl_vec3){0.5f, 0, 1}),
                     0);
}

/* A point of the plane z = x / 8 + y / 32 on a grid of 2^-20: exact in float, while the
 * products in an orientation determinant of such points need more bits than a double has. */
static xyl_vec3 on_tilted_plane(uint32_t seed)
{
    double x = floor((hash_unit(seed) + 1) * 524288) / 1048576;
    double y = floor((hash_unit(seed + 1) + 1) * 524288) / 1048576;
    return (xyl_vec3){(float)x, (float)y, (float)(x / 8 + y / 32)};
}

static double cross2(xyl_vec3 a, xyl_vec3 b, xyl_vec3 c)
{
    return ((double)b.x - a.x) * ((double)c.y - a.y) - ((double)b.y - a.y) * ((double)c.x - a.x);
}

static void self_intersections_find_exact_contact_despite_rounding(void **state)
{
    (void)state;
    size_t tried = 0;
    for (uint32_t k = 0; tried < 300 && k < 100000; ++k) {
        xyl_vec3 t[4];
        for (uint32_t i = 0; i < 4; ++i) t[i] = on_tilted_plane(8 * k + 2 * i);
        /* t[3] strictly inside t[0..2], seen from above (the plane is a graph over xy). */
        double s0 = cross2(t[0], t[1], t[3]), s1 = cross2(t[1], t[2], t[3]),
               s2 = cross2(t[2], t[0], t[3]);
        double area = cross2(t[0], t[1], t[2]);
        if (fabs(area) < 1e-2 || !((s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0)))
            continue;
        tried++;
        /* A triangle standing on that point, otherwise above the plane, touches exactly there. */
        xyl_vec3 p = t[3];
        size_t got = separate_pair_at(t, p, (xyl_vec3){p.x + 0.25f, p.y + 0.125f, p.z + 1},
                                      (xyl_vec3){p.x - 0.125f, p.y + 0.25f, p.z + 1});
        if (got != 1) fail_msg("case %u: contact at (%a, %a, %a) not found", k, p.x, p.y, p.z);
    }
    assert_int_equal(tried, 300);
}

static void self_intersections_skip_degenerate_triangles(void **state)
{
    (void)state;
    /* A zero-area triangle through the middle of another: skipped (xyl_mesh_check reports it). */
    assert_int_equal(separate_pair((xyl_vec3){0.2f, 0.2f, -1}, (xyl_vec3){0.2f, 0.2f, 0},
                                   (xyl_vec3){0.2f, 0.2f, 1}),
                     0);
}

static void self_intersections_agree_with_the_reference_on_random_pairs(void **state)
{
    (void)state;
    size_t hits = 0, decided = 0;
    for (uint32_t k = 0; k < 3000; ++k) {
        builder b = {0};
        for (uint32_t v = 0; v < 6; ++v)
            add_vertex(&b, hash_unit(60 * k + 3 * v), hash_unit(60 * k + 3 * v + 1),
                       hash_unit(60 * k + 3 * v + 2));
        add_tri(&b, 0, 1, 2);
        if (k % 2)
            add_tri(&b, 3, 4, 5);
        else
            add_tri(&b, 0, 4, 5); /* half of them share a vertex */
        xyl_mesh *m = make_mesh(&b);
        bool ambiguous = false, expect = ref_pair(m, 0, 1, &ambiguous);
        xyl_mesh_destroy(m);
        if (!ambiguous) {
            size_t got = intersections(&b, NULL, 0);
            if (got != (size_t)expect)
                fail_msg("random pair %u: got %zu, expected %d", k, got, expect);
            hits += expect;
            decided++;
        }
        builder_free(&b);
    }
    assert_true(decided > 2900);
    assert_true(hits > 100 && hits < decided - 100);
}

static void self_intersections_write_sorted_pairs_up_to_the_capacity(void **state)
{
    (void)state;
    builder b = {0};
    add_turned_cube(&b, 0, 0, 0, 0.1);
    add_turned_cube(&b, 0.45, 0.35, 0.3, 0.7);
    size_t total = intersections(&b, NULL, 0);
    assert_true(total >= 4);
    uint32_t all[256], some[256];
    assert_true(total <= 128);
    assert_int_equal(intersections(&b, all, total), total);
    for (size_t k = 0; k < total; ++k) {
        assert_true(all[2 * k] < all[2 * k + 1]);
        if (k)
            assert_true(all[2 * k - 2] < all[2 * k] ||
                        (all[2 * k - 2] == all[2 * k] && all[2 * k - 1] < all[2 * k + 1]));
    }
    /* Any capacity gets the first pairs of the full list, and nothing past them is written. */
    for (size_t cap = 0; cap <= total; ++cap) {
        memset(some, 0xEE, sizeof some);
        assert_int_equal(intersections(&b, some, cap), total);
        if (cap) assert_memory_equal(some, all, 2 * cap * sizeof *some);
        for (size_t k = 2 * cap; k < 256; ++k) assert_int_equal(some[k], 0xEEEEEEEEu);
    }
    builder_free(&b);
}

static void self_intersections_count_every_pair_of_a_stack_of_overlapping_triangles(void **state)
{
    (void)state;
    /* 60 copies of a triangle, each turned a little about a vertical axis through its middle:
     * every pair crosses, 1770 pairs; only the first 5 are kept. */
    builder b = {0};
    for (int k = 0; k < 60; ++k) {
        double a = 0.05 * k, c = cos(a), s = sin(a);
        uint32_t v0 = add_vertex(&b, -c, -s, -1), v1 = add_vertex(&b, c, s, -1);
        uint32_t v2 = add_vertex(&b, 0, 0, 1 + 0.01 * k);
        add_tri(&b, v0, v1, v2);
    }
    uint32_t first[10];
    assert_int_equal(intersections(&b, first, 5), 60 * 59 / 2);
    const uint32_t expect[10] = {0, 1, 0, 2, 0, 3, 0, 4, 0, 5};
    assert_memory_equal(first, expect, sizeof expect);
    builder_free(&b);
}

static void self_intersections_reject_bad_arguments(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    xyl_mesh *m = make_mesh(&b);
    size_t count = 77;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_self_intersections(NULL, NULL, NULL, 0, &count, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.code, XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_self_intersections(m, NULL, NULL, 0, NULL, NULL),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_mesh_self_intersections(m, NULL, NULL, 4, &count, NULL),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(count, 77);
    /* A caller-made view with a bad index or position. */
    xyl_mesh view = *m;
    uint32_t tv[3] = {0, 1, 9};
    view.tri_view = tv;
    view.tri_view_count = 1;
    diag = fresh_diag();
    assert_int_equal(xyl_mesh_self_intersections(&view, NULL, NULL, 0, &count, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.index, 0);
    tv[2] = 2;
    xyl_vec3 pos[8];
    memcpy(pos, m->positions, sizeof pos);
    pos[1].y = NAN;
    view.positions = pos;
    assert_int_equal(xyl_mesh_self_intersections(&view, NULL, NULL, 0, &count, &diag),
                     XYL_ERR_NON_FINITE);
    assert_int_equal(diag.index, 1);
    assert_int_equal(count, 77);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

static void a_bumpy_sphere_of_100k_triangles_is_closed_and_free_of_intersections(void **state)
{
    (void)state;
    builder b = {0};
    add_bumpy_sphere(&b, 92);
    xyl_mesh *m = make_mesh(&b);
    assert_true(m->tri_view_count > 100000);
    xyl_mesh_report r;
    assert_int_equal(xyl_mesh_check(m, NULL, &r, NULL), XYL_OK);
    assert_int_equal(r.euler, 2);
    assert_int_equal(r.components, 1);
    assert_closed(&r);
    size_t count = 1;
    assert_int_equal(xyl_mesh_self_intersections(m, NULL, NULL, 0, &count, NULL), XYL_OK);
    assert_int_equal(count, 0);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

/* Bounds cover every position (a vertex no face uses too); NULL and empty meshes are zeros. */
static void bounds_cover_every_position(void **state)
{
    (void)state;
    builder b;
    memset(&b, 0, sizeof b);
    add_cube(&b, -1.5, 2.0, 0.25, 3.0);
    add_vertex(&b, 0.0, -7.0, 1.0); /* used by no face */
    xyl_mesh *m = make_mesh(&b);
    float lo[3], hi[3];
    xyl_mesh_bounds(m, lo, hi);
    const float want_lo[3] = {-1.5f, -7.0f, 0.25f}, want_hi[3] = {1.5f, 5.0f, 3.25f};
    for (int k = 0; k < 3; ++k) {
        assert_true(lo[k] == want_lo[k]);
        assert_true(hi[k] == want_hi[k]);
    }
    xyl_mesh_bounds(NULL, lo, hi);
    for (int k = 0; k < 3; ++k) assert_true(lo[k] == 0.0f && hi[k] == 0.0f);
    xyl_mesh_destroy(m);
    builder_free(&b);
}

#ifndef XYL_HAVE_OPENSUBDIV
/* A build without OpenSubdiv (XYL_WITH_OPENSUBDIV=OFF) says so instead of subdividing, both in
 * xyl_mesh_subdivide and in a stem build that asks for pre-subdivision. */
static void subdivision_says_it_is_not_built(void **state)
{
    (void)state;
    builder b = {0};
    add_cube(&b, 0, 0, 0, 1);
    xyl_mesh *m = make_mesh(&b), *out = NULL;
    xyl_subdivide_desc sd = {0};
    sd.scheme = XYL_SUBDIVIDE_CATMARK;
    xyl_diag diag = {0};
    assert_int_equal(xyl_mesh_subdivide(m, &sd, &out, &diag), XYL_ERR_UNSUPPORTED);
    assert_null(out);
    assert_non_null(strstr(diag.message, "XYL_WITH_OPENSUBDIV=OFF"));
    xyl_skel_node nodes[2] = {{{0, 0, 0}, 0.1f, -1, 0, 0}, {{0, 1, 0}, 0.1f, 0, 0, 0}};
    xyl_skeleton_desc skd = {0};
    skd.nodes = nodes;
    skd.node_count = 2;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_create(&skd, &sk, NULL), XYL_OK);
    xyl_stems_desc md = {0};
    md.subdivision = XYL_SUBDIVIDE_LOOP;
    memset(&diag, 0, sizeof diag);
    assert_int_equal(xyl_stems_build(sk, &md, &out, NULL, &diag), XYL_ERR_UNSUPPORTED);
    assert_null(out);
    assert_non_null(strstr(diag.message, "XYL_WITH_OPENSUBDIV=OFF"));
    md.subdivision = XYL_SUBDIVIDE_NONE;
    assert_int_equal(xyl_stems_build(sk, &md, &out, NULL, &diag), XYL_OK);
    xyl_mesh_destroy(out);
    xyl_skeleton_destroy(sk);
    xyl_mesh_destroy(m);
    builder_free(&b);
}
#endif

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(create_copies_arrays_and_builds_triangulated_view),
        cmocka_unit_test(bounds_cover_every_position),
        cmocka_unit_test(create_fills_absent_optional_arrays_with_zeros),
        cmocka_unit_test(create_copies_given_optional_arrays),
        cmocka_unit_test(create_computes_unit_outward_normals_on_a_cube),
        cmocka_unit_test(create_gives_an_unused_vertex_the_up_normal),
        cmocka_unit_test(create_accepts_an_empty_mesh),
        cmocka_unit_test(create_rejects_null_desc_and_out),
        cmocka_unit_test(create_rejects_null_arrays_with_counts),
        cmocka_unit_test(create_rejects_out_of_range_indices_naming_the_face),
        cmocka_unit_test(create_rejects_a_face_repeating_a_vertex),
        cmocka_unit_test(create_rejects_non_finite_numbers_naming_the_vertex),
        cmocka_unit_test(create_enforces_limits),
        cmocka_unit_test(create_survives_every_allocation_failure),
        cmocka_unit_test(create_takes_every_array_from_the_allocator),
        cmocka_unit_test(destroy_accepts_null),
        cmocka_unit_test(check_finds_a_cube_closed_with_euler_2),
        cmocka_unit_test(check_accepts_mixed_quads_and_triangles),
        cmocka_unit_test(check_counts_the_boundary_of_an_open_cube),
        cmocka_unit_test(check_finds_the_edges_of_a_flipped_face_misoriented),
        cmocka_unit_test(check_finds_a_bow_tie_vertex_and_two_components),
        cmocka_unit_test(check_finds_three_quads_on_one_edge_non_manifold),
        cmocka_unit_test(check_counts_both_faces_of_a_duplicate_pair),
        cmocka_unit_test(check_finds_degenerate_faces_relative_to_the_mesh_size),
        cmocka_unit_test(check_finds_a_quad_torus_closed_with_euler_0),
        cmocka_unit_test(check_counts_two_disjoint_cubes_as_two_components),
        cmocka_unit_test(check_reports_unused_vertices_apart_from_closedness),
        cmocka_unit_test(check_of_an_empty_mesh_is_all_zero),
        cmocka_unit_test(check_rejects_null_arguments),
        cmocka_unit_test(check_validates_a_caller_made_view),
        cmocka_unit_test(calls_refuse_a_view_with_a_non_finite_normal_or_uv),
        cmocka_unit_test(self_intersections_of_a_cube_are_none),
        cmocka_unit_test(self_intersections_of_a_torus_are_none),
        cmocka_unit_test(self_intersections_of_interpenetrating_cubes_are_genuine),
        cmocka_unit_test(self_intersections_of_separate_cubes_are_none),
        cmocka_unit_test(self_intersections_find_a_fold_between_triangles_that_share_a_vertex),
        cmocka_unit_test(self_intersections_with_one_shared_vertex_look_beyond_it),
        cmocka_unit_test(self_intersections_of_nearly_coplanar_neighbours_are_none),
        cmocka_unit_test(self_intersections_with_a_shared_edge_count_only_a_flat_fold),
        cmocka_unit_test(self_intersections_count_distinct_triangles_that_touch),
        cmocka_unit_test(self_intersections_count_coplanar_overlap),
        cmocka_unit_test(self_intersections_ignore_a_near_miss),
        cmocka_unit_test(self_intersections_find_exact_contact_despite_rounding),
        cmocka_unit_test(self_intersections_skip_degenerate_triangles),
        cmocka_unit_test(self_intersections_agree_with_the_reference_on_random_pairs),
        cmocka_unit_test(self_intersections_write_sorted_pairs_up_to_the_capacity),
        cmocka_unit_test(self_intersections_count_every_pair_of_a_stack_of_overlapping_triangles),
        cmocka_unit_test(self_intersections_reject_bad_arguments),
        cmocka_unit_test(a_bumpy_sphere_of_100k_triangles_is_closed_and_free_of_intersections),
#ifndef XYL_HAVE_OPENSUBDIV
        cmocka_unit_test(subdivision_says_it_is_not_built),
#endif
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
