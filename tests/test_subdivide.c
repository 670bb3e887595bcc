/* One level of subdivision through OpenSubdiv (xyl_mesh_subdivide, xyl__subdivide) and the ring
 * inflation factor the mesher relies on. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "subdivide.h"
#include "test_util.h"
#include "xylem/xyl_mesh.h"

#define PI 3.14159265358979323846

/* ---- helpers ------------------------------------------------------------------------------- */

/* cmocka's assert_float_equal compares floats; these checks need doubles. */
#define assert_near(a, b, tol) near_or_fail((a), (b), (tol), #a, __LINE__)

static void near_or_fail(double a, double b, double tol, const char *what, int line)
{
    if (!(fabs(a - b) <= tol))
        fail_msg("line %d: %s = %.17g, expected %.17g (tolerance %g)", line, what, a, b, tol);
}

static xyl_diag fresh_diag(void)
{
    xyl_diag d;
    memset(&d, 0, sizeof d);
    return d;
}

static xyl_mesh *make_mesh(const xyl_vec3 *p, size_t nv, const uint32_t *quads, size_t nq,
                           const uint32_t *tris, size_t nt)
{
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.positions = p;
    d.vertex_count = nv;
    d.quads = quads;
    d.quad_count = nq;
    d.triangles = tris;
    d.triangle_count = nt;
    xyl_mesh *m = NULL;
    xyl_diag diag = fresh_diag();
    if (xyl_mesh_create(&d, &m, &diag) != XYL_OK) fail_msg("mesh_create: %s", diag.message);
    return m;
}

/* The refinement rules themselves: control points, not their limits. */
static xyl_mesh *subdivide(const xyl_mesh *m, xyl_subdivision scheme)
{
    xyl_subdivide_desc sd;
    memset(&sd, 0, sizeof sd);
    sd.scheme = scheme;
    sd.keep_control_points = true;
    xyl_mesh *out = NULL;
    xyl_diag diag = fresh_diag();
    xyl_result r = xyl_mesh_subdivide(m, &sd, &out, &diag);
    if (r != XYL_OK) fail_msg("subdivide: %s: %s", xyl_result_string(r), diag.message);
    return out;
}

/* The cube [-1, 1]^3: vertex i has x from bit 0, y from bit 1, z from bit 2. */
static const uint32_t cube_quads[6 * 4] = {
    0, 2, 3, 1, /* -z */
    4, 5, 7, 6, /* +z */
    0, 1, 5, 4, /* -y */
    2, 6, 7, 3, /* +y */
    0, 4, 6, 2, /* -x */
    1, 3, 7, 5, /* +x */
};

static void cube_positions(xyl_vec3 p[8])
{
    for (int i = 0; i < 8; ++i) {
        p[i].x = (i & 1) ? 1.0f : -1.0f;
        p[i].y = (i & 2) ? 1.0f : -1.0f;
        p[i].z = (i & 4) ? 1.0f : -1.0f;
    }
}

static xyl_mesh *cube(void)
{
    xyl_vec3 p[8];
    cube_positions(p);
    return make_mesh(p, 8, cube_quads, 6, NULL, 0);
}

static double dot3(xyl_vec3 a, xyl_vec3 b)
{
    return (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z;
}

static xyl_vec3 sub3(xyl_vec3 a, xyl_vec3 b)
{
    xyl_vec3 r = {a.x - b.x, a.y - b.y, a.z - b.z};
    return r;
}

static xyl_vec3 cross3(xyl_vec3 a, xyl_vec3 b)
{
    xyl_vec3 r = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    return r;
}

/* Face f of m (quads first): its indices and corner count. */
static const uint32_t *face_of(const xyl_mesh *m, size_t f, int *n)
{
    if (f < m->quad_count) {
        *n = 4;
        return m->quads + 4 * f;
    }
    *n = 3;
    return m->triangles + 3 * (f - m->quad_count);
}

static xyl_vec3 face_centroid(const xyl_mesh *m, size_t f)
{
    int n = 0;
    const uint32_t *idx = face_of(m, f, &n);
    xyl_vec3 c = {0, 0, 0};
    for (int k = 0; k < n; ++k) {
        c.x += m->positions[idx[k]].x / (float)n;
        c.y += m->positions[idx[k]].y / (float)n;
        c.z += m->positions[idx[k]].z / (float)n;
    }
    return c;
}

/* Twice the area-weighted normal (Newell's method works for triangles and quads alike). */
static xyl_vec3 face_normal(const xyl_mesh *m, size_t f)
{
    int n = 0;
    const uint32_t *idx = face_of(m, f, &n);
    xyl_vec3 s = {0, 0, 0};
    for (int k = 0; k < n; ++k) {
        xyl_vec3 c = cross3(m->positions[idx[k]], m->positions[idx[(k + 1) % n]]);
        s.x += c.x;
        s.y += c.y;
        s.z += c.z;
    }
    return s;
}

static xyl_vec3 mesh_centroid(const xyl_mesh *m)
{
    xyl_vec3 c = {0, 0, 0};
    for (size_t v = 0; v < m->vertex_count; ++v) {
        c.x += m->positions[v].x / (float)m->vertex_count;
        c.y += m->positions[v].y / (float)m->vertex_count;
        c.z += m->positions[v].z / (float)m->vertex_count;
    }
    return c;
}

/* Every face of a mesh of a convex shape faces away from the centroid. */
static void assert_faces_point_outward(const xyl_mesh *m)
{
    xyl_vec3 c = mesh_centroid(m);
    for (size_t f = 0; f < m->quad_count + m->triangle_count; ++f) {
        double d = dot3(face_normal(m, f), sub3(face_centroid(m, f), c));
        if (!(d > 0)) fail_msg("face %zu faces inwards (%g)", f, d);
    }
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Asserts that every directed edge occurs once and its reverse once (a closed, consistently
 * oriented surface) and returns the number of undirected edges. */
static size_t closed_oriented_edges(const xyl_mesh *m)
{
    size_t faces = m->quad_count + m->triangle_count, n = 4 * m->quad_count + 3 * m->triangle_count;
    uint64_t *e = malloc((n ? n : 1) * sizeof *e);
    assert_non_null(e);
    size_t w = 0;
    for (size_t f = 0; f < faces; ++f) {
        int k = 0;
        const uint32_t *idx = face_of(m, f, &k);
        for (int i = 0; i < k; ++i) e[w++] = ((uint64_t)idx[i] << 32) | idx[(i + 1) % k];
    }
    qsort(e, n, sizeof *e, cmp_u64);
    for (size_t i = 0; i < n; ++i) {
        if (i && e[i] == e[i - 1]) fail_msg("directed edge used twice");
        uint64_t rev = (e[i] << 32) | (e[i] >> 32);
        if (!bsearch(&rev, e, n, sizeof *e, cmp_u64)) fail_msg("edge without its opposite");
    }
    free(e);
    return n / 2;
}

static int64_t euler(const xyl_mesh *m)
{
    size_t edges = closed_oriented_edges(m);
    return (int64_t)m->vertex_count - (int64_t)edges + (int64_t)(m->quad_count + m->triangle_count);
}

/* Index of the vertex at p (within tol), or -1. */
static long find_vertex(const xyl_mesh *m, double x, double y, double z, double tol)
{
    for (size_t v = 0; v < m->vertex_count; ++v) {
        xyl_vec3 q = m->positions[v];
        if (fabs(q.x - x) <= tol && fabs(q.y - y) <= tol && fabs(q.z - z) <= tol) return (long)v;
    }
    return -1;
}

/* Turns every triangle of a convex mesh to face away from the origin. */
static void orient_outward(const xyl_vec3 *p, uint32_t *tris, size_t count)
{
    for (size_t t = 0; t < count; ++t) {
        uint32_t *f = tris + 3 * t;
        xyl_vec3 n = cross3(sub3(p[f[1]], p[f[0]]), sub3(p[f[2]], p[f[0]]));
        xyl_vec3 c = {p[f[0]].x + p[f[1]].x + p[f[2]].x, p[f[0]].y + p[f[1]].y + p[f[2]].y,
                      p[f[0]].z + p[f[1]].z + p[f[2]].z};
        if (dot3(n, c) < 0) {
            uint32_t s = f[1];
            f[1] = f[2];
            f[2] = s;
        }
    }
}

static xyl_mesh *subdivide_to_limit(const xyl_mesh *m, xyl_subdivision scheme)
{
    xyl_subdivide_desc sd;
    memset(&sd, 0, sizeof sd);
    sd.scheme = scheme; /* keep_control_points false: the default */
    xyl_mesh *out = NULL;
    xyl_diag diag = fresh_diag();
    xyl_result r = xyl_mesh_subdivide(m, &sd, &out, &diag);
    if (r != XYL_OK) fail_msg("subdivide: %s: %s", xyl_result_string(r), diag.message);
    return out;
}

/* Distance from p to the nearest vertex of m. */
static double nearest_vertex_distance(const xyl_mesh *m, xyl_vec3 p)
{
    double best = INFINITY;
    for (size_t v = 0; v < m->vertex_count; ++v) {
        xyl_vec3 q = m->positions[v];
        double dx = (double)q.x - p.x, dy = (double)q.y - p.y, dz = (double)q.z - p.z;
        best = fmin(best, dx * dx + dy * dy + dz * dz);
    }
    return sqrt(best);
}

/* ---- Catmull-Clark on a cube ------------------------------------------------------------- */

static void catmark_cube_has_24_quads_26_vertices_and_euler_2(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
    assert_int_equal(s->vertex_count, 26);
    assert_int_equal(s->quad_count, 24);
    assert_int_equal(s->triangle_count, 0);
    assert_int_equal(s->tri_view_count, 48);
    assert_int_equal(euler(c), 2);
    assert_int_equal(euler(s), 2);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

/* The Catmull-Clark vertex rule v' = (F + 2R + (n - 3) v) / n, computed here from the control
 * mesh: F averages the centroids of the faces around v, R the midpoints of its edges. */
static xyl_vec3 cc_vertex_point(const xyl_mesh *m, uint32_t v)
{
    double F[3] = {0, 0, 0}, R[3] = {0, 0, 0};
    int faces = 0, edges = 0;
    uint32_t seen[64];
    for (size_t f = 0; f < m->quad_count + m->triangle_count; ++f) {
        int n = 0;
        const uint32_t *idx = face_of(m, f, &n);
        for (int k = 0; k < n; ++k) {
            if (idx[k] != v) continue;
            xyl_vec3 c = face_centroid(m, f);
            F[0] += c.x, F[1] += c.y, F[2] += c.z;
            ++faces;
            uint32_t next = idx[(k + 1) % n];
            bool known = false;
            for (int e = 0; e < edges; ++e) known = known || seen[e] == next;
            if (!known) {
                assert_true(edges < 64);
                seen[edges++] = next;
            }
        }
    }
    for (int e = 0; e < edges; ++e) {
        xyl_vec3 a = m->positions[v], b = m->positions[seen[e]];
        R[0] += (a.x + b.x) / 2, R[1] += (a.y + b.y) / 2, R[2] += (a.z + b.z) / 2;
    }
    /* On a closed mesh each vertex has as many edges as faces; seen[] holds each edge once. */
    assert_int_equal(edges, faces);
    double n = faces, vp[3] = {m->positions[v].x, m->positions[v].y, m->positions[v].z};
    xyl_vec3 r;
    r.x = (float)((F[0] / n + 2 * R[0] / n + (n - 3) * vp[0]) / n);
    r.y = (float)((F[1] / n + 2 * R[1] / n + (n - 3) * vp[1]) / n);
    r.z = (float)((F[2] / n + 2 * R[2] / n + (n - 3) * vp[2]) / n);
    return r;
}

static void catmark_cube_points_follow_the_catmull_clark_rules(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
    const double tol = 1e-6;
    for (uint32_t v = 0; v < 8; ++v) {
        /* n = 3: F = p/3, R = 2p/3, so v' = (p/3 + 4p/3) / 3 = 5p/9. */
        xyl_vec3 expect = cc_vertex_point(c, v);
        assert_near(expect.x, c->positions[v].x * 5.0 / 9.0, tol);
        assert_near(expect.y, c->positions[v].y * 5.0 / 9.0, tol);
        assert_near(expect.z, c->positions[v].z * 5.0 / 9.0, tol);
        if (find_vertex(s, expect.x, expect.y, expect.z, tol) < 0)
            fail_msg("no vertex point for corner %u", v);
    }
    /* Edge points (ends + adjacent face points) / 4 have one zero and two +-3/4 coordinates;
     * face points stay at the face centres. */
    int vertex_points = 0, edge_points = 0, face_points = 0;
    for (size_t v = 0; v < s->vertex_count; ++v) {
        double a[3] = {fabs(s->positions[v].x), fabs(s->positions[v].y), fabs(s->positions[v].z)};
        int zeros = 0, five_ninths = 0, three_quarters = 0, ones = 0;
        for (int k = 0; k < 3; ++k) {
            assert_true(a[k] <= 1.0 + tol); /* inside the cube */
            zeros += a[k] < tol;
            five_ninths += fabs(a[k] - 5.0 / 9.0) < tol;
            three_quarters += fabs(a[k] - 0.75) < tol;
            ones += fabs(a[k] - 1.0) < tol;
        }
        vertex_points += five_ninths == 3;
        edge_points += zeros == 1 && three_quarters == 2;
        face_points += zeros == 2 && ones == 1;
        /* Symmetric: the mirror image of every vertex is a vertex too. */
        const double x = s->positions[v].x, y = s->positions[v].y, z = s->positions[v].z;
        assert_true(find_vertex(s, -x, y, z, tol) >= 0);
        assert_true(find_vertex(s, x, -y, z, tol) >= 0);
        assert_true(find_vertex(s, x, y, -z, tol) >= 0);
        assert_true(find_vertex(s, y, z, x, tol) >= 0); /* and under axis rotation */
    }
    assert_int_equal(vertex_points, 8);
    assert_int_equal(edge_points, 12);
    assert_int_equal(face_points, 6);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

/* OpenSubdiv's default order: the points of the input vertices first, in input order, then the
 * face points in face order, then the edge points. */
static void catmark_orders_vertex_then_face_then_edge_points(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
    for (uint32_t v = 0; v < 8; ++v) {
        assert_near(s->positions[v].x, c->positions[v].x * 5.0 / 9.0, 1e-6);
        assert_near(s->positions[v].y, c->positions[v].y * 5.0 / 9.0, 1e-6);
        assert_near(s->positions[v].z, c->positions[v].z * 5.0 / 9.0, 1e-6);
    }
    for (size_t f = 0; f < 6; ++f) {
        xyl_vec3 centre = face_centroid(c, f), got = s->positions[8 + f];
        assert_near(got.x, centre.x, 1e-6);
        assert_near(got.y, centre.y, 1e-6);
        assert_near(got.z, centre.z, 1e-6);
    }
    for (size_t v = 14; v < 26; ++v) { /* edge points: one coordinate 0, two +-3/4 */
        xyl_vec3 e = s->positions[v];
        assert_near(fabs(e.x) + fabs(e.y) + fabs(e.z), 1.5, 1e-6);
    }
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

static void catmark_preserves_orientation_and_gives_outward_normals(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    assert_faces_point_outward(c);
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
    assert_faces_point_outward(s);
    for (size_t v = 0; v < s->vertex_count; ++v) {
        assert_near(dot3(s->normals[v], s->normals[v]), 1.0, 1e-5);
        assert_true(dot3(s->normals[v], s->positions[v]) > 0);
    }
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

static void catmark_turns_triangles_into_quads(void **state)
{
    (void)state;
    /* The cube with its +x face split into two triangles. */
    xyl_vec3 p[8];
    cube_positions(p);
    const uint32_t tris[6] = {1, 3, 7, 1, 7, 5};
    xyl_mesh *c = make_mesh(p, 8, cube_quads, 5, tris, 2);
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
    assert_int_equal(s->quad_count, 5 * 4 + 2 * 3);
    assert_int_equal(s->triangle_count, 0);
    assert_int_equal(s->vertex_count, 8 + 13 + 7);
    assert_int_equal(euler(s), 2);
    assert_faces_point_outward(s);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

/* ---- Loop ---------------------------------------------------------------------------------- */

static void loop_tetrahedron_quadruples_faces(void **state)
{
    (void)state;
    const xyl_vec3 p[4] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    uint32_t t[12] = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    orient_outward(p, t, 4);
    xyl_mesh *c = make_mesh(p, 4, NULL, 0, t, 4);
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_LOOP);
    assert_int_equal(s->triangle_count, 16);
    assert_int_equal(s->quad_count, 0);
    assert_int_equal(s->vertex_count, 4 + 6);
    assert_int_equal(euler(s), 2);
    assert_faces_point_outward(s);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

static void loop_octahedron_quadruples_faces(void **state)
{
    (void)state;
    const xyl_vec3 p[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    uint32_t t[24];
    for (uint32_t o = 0; o < 8; ++o) {
        t[3 * o] = (o & 1) ? 1 : 0;
        t[3 * o + 1] = (o & 2) ? 3 : 2;
        t[3 * o + 2] = (o & 4) ? 5 : 4;
    }
    orient_outward(p, t, 8);
    xyl_mesh *c = make_mesh(p, 6, NULL, 0, t, 8);
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_LOOP);
    assert_int_equal(s->triangle_count, 32);
    assert_int_equal(s->vertex_count, 6 + 12);
    assert_int_equal(euler(s), 2);
    assert_faces_point_outward(s);
    /* Loop's vertex rule, v' = (1 - n beta) v + beta sum, with Loop's own weight
     * beta = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n = 31/256 for n = 4. The neighbours of
     * (1, 0, 0) sum to 0, so it moves to 1 - 4 * 31/256 = 33/64. */
    const double beta = (0.625 - pow(0.375 + cos(2 * PI / 4) / 4, 2)) / 4;
    assert_near(1 - 4 * beta, 33.0 / 64.0, 1e-12);
    assert_true(find_vertex(s, 1 - 4 * beta, 0, 0, 1e-6) >= 0);
    /* Edge rule 3/8 (ends) + 1/8 (opposite vertices): (1, 0, 0)-(0, 1, 0) goes to (3/8, 3/8, 0). */
    assert_true(find_vertex(s, 0.375, 0.375, 0, 1e-6) >= 0);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

static void loop_triangulates_quads_first(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_LOOP);
    /* 12 triangles; 12 edges + 6 diagonals. */
    assert_int_equal(s->triangle_count, 48);
    assert_int_equal(s->quad_count, 0);
    assert_int_equal(s->vertex_count, 8 + 18);
    assert_int_equal(euler(s), 2);
    assert_faces_point_outward(s);
    /* The diagonal of quad (a, b, c, d) is a-c: its midpoint region gets a vertex. For the -z face
     * (0, 2, 3, 1) that is 0-3, through (0, 0, -1) before smoothing: a vertex near (0, 0, z). */
    bool found = false;
    for (size_t v = 0; v < s->vertex_count; ++v)
        found = found || (fabs(s->positions[v].x) < 1e-6 && fabs(s->positions[v].y) < 1e-6 &&
                          s->positions[v].z < 0);
    assert_true(found);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

/* ---- branch ids ---------------------------------------------------------------------------- */

/* The cube with the +z face in branch 1, the +x face in branch 3, the others in branch 2; top
 * vertices in branch 1 except (1, 1, 1) in branch 7, bottom vertices in branch 2. */
static xyl_mesh *two_branch_cube(void)
{
    xyl_vec3 p[8];
    cube_positions(p);
    uint32_t vb[8], fb[6] = {2, 1, 2, 2, 2, 3};
    for (int i = 0; i < 8; ++i) vb[i] = p[i].z > 0 ? 1 : 2;
    vb[7] = 7;
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.positions = p;
    d.vertex_count = 8;
    d.quads = cube_quads;
    d.quad_count = 6;
    d.branch_ids = vb;
    d.face_branches = fb;
    xyl_mesh *m = NULL;
    assert_int_equal(xyl_mesh_create(&d, &m, NULL), XYL_OK);
    return m;
}

/* The branch of the cube face a child face lies on: by the dominant axis of its centroid. */
static uint32_t cube_face_branch(xyl_vec3 c)
{
    double ax = fabs(c.x), ay = fabs(c.y), az = fabs(c.z);
    if (az >= ax && az >= ay) return c.z > 0 ? 1 : 2;
    if (ax >= ay) return c.x > 0 ? 3 : 2;
    return 2;
}

static void face_branches_are_inherited_from_the_parent_face(void **state)
{
    (void)state;
    xyl_mesh *c = two_branch_cube();
    for (int scheme = XYL_SUBDIVIDE_CATMARK; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme) {
        xyl_mesh *s = subdivide(c, (xyl_subdivision)scheme);
        size_t counts[8] = {0};
        size_t per_face = scheme == XYL_SUBDIVIDE_CATMARK ? 4 : 8;
        for (size_t f = 0; f < s->quad_count + s->triangle_count; ++f) {
            assert_int_equal(s->face_branches[f], cube_face_branch(face_centroid(s, f)));
            /* the children of a face are consecutive, in parent order */
            assert_int_equal(s->face_branches[f], c->face_branches[f / per_face]);
            counts[s->face_branches[f]]++;
        }
        assert_int_equal(counts[1], per_face);
        assert_int_equal(counts[3], per_face);
        assert_int_equal(counts[2], 4 * per_face);
        xyl_mesh_destroy(s);
    }
    xyl_mesh_destroy(c);
}

static uint32_t branch_at(const xyl_mesh *s, double x, double y, double z)
{
    long v = find_vertex(s, x, y, z, 1e-6);
    if (v < 0) fail_msg("no vertex at (%g, %g, %g)", x, y, z);
    return s->branch_ids[v];
}

static void vertex_branches_follow_the_documented_rules(void **state)
{
    (void)state;
    xyl_mesh *c = two_branch_cube();
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
    const double k = 5.0 / 9.0, e = 0.75;
    /* vertex points keep their vertex's branch */
    assert_int_equal(branch_at(s, -k, -k, k), 1);
    assert_int_equal(branch_at(s, k, k, k), 7);
    assert_int_equal(branch_at(s, -k, -k, -k), 2);
    /* face points take their face's branch */
    assert_int_equal(branch_at(s, 0, 0, 1), 1);
    assert_int_equal(branch_at(s, 1, 0, 0), 3);
    assert_int_equal(branch_at(s, 0, 0, -1), 2);
    /* edge points: faces that agree win (vertical edges between side faces, bottom edges) */
    assert_int_equal(branch_at(s, -1 * e, -1 * e, 0), 2);
    assert_int_equal(branch_at(s, 0, -e, -e), 2);
    /* +x face (3) against -y (2): faces disagree, ends (vertices 1 and 5: 2 and 1) too: the
     * smaller face branch */
    assert_int_equal(branch_at(s, e, -e, 0), 2);
    /* +z (1) against -y (2): faces disagree, both ends in branch 1 */
    assert_int_equal(branch_at(s, 0, -e, e), 1);
    /* +z (1) against +x (3): ends 1 and 7 disagree: the smaller face branch, 1 */
    assert_int_equal(branch_at(s, e, 0, e), 1);
    /* +x (3) against +y (2), ends 3 (branch 2) and 7 (branch 7): 2 */
    assert_int_equal(branch_at(s, e, e, 0), 2);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

/* ---- UVs ----------------------------------------------------------------------------------- */

/* A flat n x n grid of unit quads in z = 0 with uv an affine function of (x, y). Varying
 * interpolation is linear: vertex points keep their vertex's uv, edge points take the edge's
 * midpoint uv, face points the face's average. On a uniform planar grid with sharp boundaries
 * every edge and face point lands on the refined grid, where the affine function must hold. So do
 * the vertex points of Catmull-Clark; with Loop the two corners that the diagonals touch are
 * not topological corners (two triangles) and slide along the boundary, keeping their uv. */
static void uvs_are_interpolated_linearly(void **state)
{
    (void)state;
    enum { N = 3, V = (N + 1) * (N + 1) };
    xyl_vec3 p[V];
    float uv[2 * V];
    uint32_t q[4 * N * N];
    for (int j = 0; j <= N; ++j)
        for (int i = 0; i <= N; ++i) {
            int v = j * (N + 1) + i;
            p[v].x = (float)i, p[v].y = (float)j, p[v].z = 0;
            uv[2 * v] = 0.25f + 0.5f * (float)i;
            uv[2 * v + 1] = 2.0f - 0.125f * (float)j + 0.25f * (float)i;
        }
    for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
            uint32_t a = (uint32_t)(j * (N + 1) + i), *f = q + 4 * (j * N + i);
            f[0] = a, f[1] = a + 1, f[2] = a + N + 2, f[3] = a + N + 1;
        }
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.positions = p;
    d.uvs = uv;
    d.vertex_count = V;
    d.quads = q;
    d.quad_count = N * N;
    xyl_mesh *c = NULL;
    assert_int_equal(xyl_mesh_create(&d, &c, NULL), XYL_OK);
    for (int scheme = XYL_SUBDIVIDE_CATMARK; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme) {
        xyl_mesh *s = subdivide(c, (xyl_subdivision)scheme);
        size_t expect_v = (2 * N + 1) * (2 * N + 1); /* the same for both schemes */
        assert_int_equal(s->vertex_count, expect_v);
        size_t moved = 0;
        for (size_t v = 0; v < s->vertex_count; ++v) {
            double x = s->positions[v].x, y = s->positions[v].y;
            assert_near(s->positions[v].z, 0, 1e-6);
            if (v < V) { /* vertex points come first, in input order */
                assert_near(s->uvs[2 * v], uv[2 * v], 1e-6);
                assert_near(s->uvs[2 * v + 1], uv[2 * v + 1], 1e-6);
                if (fabs(x - p[v].x) > 1e-6 || fabs(y - p[v].y) > 1e-6) {
                    ++moved;
                    continue;
                }
            }
            assert_near(2 * x, round(2 * x), 1e-5); /* on the refined grid */
            assert_near(2 * y, round(2 * y), 1e-5);
            assert_near(s->uvs[2 * v], 0.25 + 0.5 * x, 1e-5);
            assert_near(s->uvs[2 * v + 1], 2.0 - 0.125 * y + 0.25 * x, 1e-5);
        }
        assert_int_equal(moved, scheme == XYL_SUBDIVIDE_LOOP ? 2 : 0);
        xyl_mesh_destroy(s);
    }
    xyl_mesh_destroy(c);
}

/* ---- rings: what one level does to a k-sided tube, and its limit ---------------------------- */

/* A closed prism of `rings` k-gon rings of radius r along z, capped with two k-gons. */
enum { PRISM_MAX_K = 8, PRISM_MAX_RINGS = 12 };

static xyl_mesh *prism(int k, int rings, double r)
{
    assert_true(k >= 3 && k <= PRISM_MAX_K && rings >= 2 && rings <= PRISM_MAX_RINGS);
    xyl_vec3 p[PRISM_MAX_K * PRISM_MAX_RINGS];
    uint32_t q[4 * PRISM_MAX_K * PRISM_MAX_RINGS], t[2 * 3 * PRISM_MAX_K];
    for (int j = 0; j < rings; ++j)
        for (int i = 0; i < k; ++i) {
            double a = 2 * PI * i / k;
            p[j * k + i].x = (float)(r * cos(a));
            p[j * k + i].y = (float)(r * sin(a));
            p[j * k + i].z = (float)(0.5 * j);
        }
    for (int j = 0; j + 1 < rings; ++j)
        for (int i = 0; i < k; ++i) {
            uint32_t a = (uint32_t)(j * k + i), b = (uint32_t)(j * k + (i + 1) % k);
            uint32_t *f = q + 4 * (j * k + i);
            f[0] = a, f[1] = b, f[2] = b + (uint32_t)k, f[3] = a + (uint32_t)k;
        }
    /* The caps are k-gons: a fan of triangles each (Catmull-Clark turns them into quads). */
    uint32_t base = (uint32_t)((rings - 1) * k);
    for (int i = 1; i + 1 < k; ++i) {
        uint32_t *bottom = t + 3 * (i - 1), *top = t + 3 * (k - 2 + i - 1);
        bottom[0] = 0, bottom[1] = (uint32_t)(i + 1), bottom[2] = (uint32_t)i;
        top[0] = base, top[1] = base + (uint32_t)i, top[2] = base + (uint32_t)(i + 1);
    }
    return make_mesh(p, (size_t)(k * rings), q, (size_t)(k * (rings - 1)), t,
                     2 * (size_t)(k - 2));
}

static void catmark_ring_radius_follows_the_vertex_rule(void **state)
{
    (void)state;
    const int sides[] = {4, 6, 8};
    for (size_t n = 0; n < sizeof sides / sizeof *sides; ++n) {
        const int k = sides[n], rings = 12;
        const double r = 0.75;
        xyl_mesh *c = prism(k, rings, r);
        assert_int_equal(euler(c), 2);
        xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
        assert_int_equal(euler(s), 2);
        assert_faces_point_outward(s);
        /* Valence 4 with straight neighbours along z: (F + 2R + v) / 4 reduces to the cubic
         * B-spline rule around the ring, (p[i-1] + 6 p[i] + p[i+1]) / 8. */
        const double expect = r * (6 + 2 * cos(2 * PI / k)) / 8;
        for (int j = 3; j < rings - 3; ++j)
            for (int i = 0; i < k; ++i) {
                uint32_t v = (uint32_t)(j * k + i);
                xyl_vec3 e = cc_vertex_point(c, v);
                assert_near(hypot(e.x, e.y), expect, 1e-6);
                long got = find_vertex(s, e.x, e.y, e.z, 1e-5);
                if (got < 0) fail_msg("k = %d: no vertex point for ring %d vertex %d", k, j, i);
                assert_near(hypot(s->positions[got].x, s->positions[got].y), expect, 1e-6);
                assert_near(s->positions[got].z, c->positions[v].z, 1e-6);
            }
        xyl_mesh_destroy(s);
        xyl_mesh_destroy(c);
    }
}

/* A k-sided ring of a long tube shrinks to (4 + 2 cos(2 pi / k)) / 6 of its radius at a ring
 * vertex of the limit surface (the cubic B-spline limit rule (1, 4, 1) / 6 around the ring, the
 * axial direction being constant): the closed form is checked against OpenSubdiv's own limit
 * evaluation. */
static void limit_radius_factor_matches_opensubdiv(void **state)
{
    (void)state;
    double worst = 0;
    for (uint32_t k = 3; k <= 8; ++k) {
        double measured = 0;
        assert_int_equal(xyl__subdivide_limit_radius_factor(k, &measured), XYL_OK);
        double formula = (4 + 2 * cos(2 * PI / k)) / 6;
        double diff = fabs(measured - formula);
        printf("limit radius factor k = %u: OpenSubdiv %.15f, (4 + 2cos(2pi/k))/6 = %.15f, "
               "|diff| = %.2e\n", k, measured, formula, diff);
        if (diff > worst) worst = diff;
        assert_true(diff < 1e-6);
    }
    printf("limit radius factor: max |diff| over k = 3..8: %.2e\n", worst);
    double f = 0;
    assert_int_equal(xyl__subdivide_limit_radius_factor(4, &f), XYL_OK);
    assert_near(f, 2.0 / 3.0, 1e-12);
    assert_int_equal(xyl__subdivide_limit_radius_factor(2, &f), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__subdivide_limit_radius_factor(33, &f), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__subdivide_limit_radius_factor(4, NULL), XYL_ERR_INVALID_ARGUMENT);
}

/* The default (limit) mode against plain refinement, which does not use PrimvarRefiner::Limit:
 * every vertex of the one-level limit mesh is the limit of its vertex child, so after five more
 * control levels a refined vertex lies within (gap) / 4^5 of it (in the regular middle part of
 * the prism). The control points of level 1
 * are far from every such vertex (the negative control). */
static void limit_points_match_repeated_refinement(void **state)
{
    (void)state;
    static const xyl_subdivision schemes[] = {XYL_SUBDIVIDE_CATMARK, XYL_SUBDIVIDE_LOOP};
    for (size_t s = 0; s < 2; ++s) {
        xyl_mesh *c = prism(6, 8, 0.75);
        xyl_mesh *lim = subdivide_to_limit(c, schemes[s]);
        xyl_mesh *ctl = subdivide(c, schemes[s]);
        assert_int_equal(lim->vertex_count, ctl->vertex_count);
        assert_int_equal(lim->quad_count, ctl->quad_count);
        assert_int_equal(lim->triangle_count, ctl->triangle_count);
        assert_memory_equal(lim->quads, ctl->quads, 4 * lim->quad_count * sizeof *lim->quads);
        xyl_mesh *fine = subdivide(ctl, schemes[s]);
        for (int level = 0; level < 4; ++level) {
            xyl_mesh *finer = subdivide(fine, schemes[s]);
            xyl_mesh_destroy(fine);
            fine = finer;
        }
        double worst_limit = 0, worst_control = 0;
        for (size_t v = 0; v < lim->vertex_count; ++v) {
            /* Near the caps' extraordinary vertices refinement converges more slowly than 4^-L */
            if (ctl->positions[v].z < 1.0f || ctl->positions[v].z > 2.5f) continue;
            worst_limit = fmax(worst_limit, nearest_vertex_distance(fine, lim->positions[v]));
            worst_control = fmax(worst_control, nearest_vertex_distance(fine, ctl->positions[v]));
        }
        printf("%s: one-level limit points %.2e from the 6-level mesh, control points %.2e\n",
               s ? "Loop" : "Catmark", worst_limit, worst_control);
        assert_true(worst_limit < 2e-4);
        assert_true(worst_control > 1e-2);
        assert_faces_point_outward(lim);
        xyl_mesh_destroy(fine);
        xyl_mesh_destroy(ctl);
        xyl_mesh_destroy(lim);
        xyl_mesh_destroy(c);
    }
}

/* On a long Catmull-Clark prism every level-1 vertex of the middle part sits where the limit
 * cross-section is mirror-symmetric (ring vertices and edge midpoints), so its limit normal is
 * exactly radial: what the limit normals (limit tangents' cross product, oriented by the
 * faces) must give. */
static void limit_normals_are_radial_on_a_catmark_prism(void **state)
{
    (void)state;
    for (int k = 3; k <= 8; ++k) {
        xyl_mesh *c = prism(k, 12, 0.75);
        xyl_mesh *lim = subdivide_to_limit(c, XYL_SUBDIVIDE_CATMARK);
        double worst = 0;
        size_t checked = 0;
        for (size_t v = 0; v < lim->vertex_count; ++v) {
            xyl_vec3 p = lim->positions[v], n = lim->normals[v];
            if (p.z < 1.5 || p.z > 4.0) continue;
            double r = hypot(p.x, p.y);
            double dev = fabs(n.x - p.x / r) + fabs(n.y - p.y / r) + fabs(n.z);
            worst = fmax(worst, dev);
            ++checked;
        }
        assert_true(checked >= (size_t)(10 * k));
        if (!(worst < 1e-5)) fail_msg("k = %d: limit normal off radial by %g", k, worst);
        xyl_mesh_destroy(lim);
        xyl_mesh_destroy(c);
    }
}

/* The numeric mean limit radius (OpenSubdiv's limit over one band of a probe prism) against
 * the cubic B-spline integral that the mesher inflates by (docs/stems.md's table), for
 * Catmull-Clark and for Loop on the split rings: on a tube both limits are that B-spline. */
static void mean_limit_radius_matches_the_b_spline_integral(void **state)
{
    (void)state;
    static const uint32_t ks[] = {4, 6, 8};
    static const double spline[] = {0.657042, 0.831545, 0.901818};
    for (size_t i = 0; i < 3; ++i) {
        double cc = 0, loop = 0;
        assert_int_equal(xyl__subdivide_mean_limit_radius(XYL_SUBDIVIDE_CATMARK, ks[i], &cc), XYL_OK);
        assert_int_equal(xyl__subdivide_mean_limit_radius(XYL_SUBDIVIDE_LOOP, ks[i], &loop), XYL_OK);
        printf("mean limit radius k = %u: Catmark %.9f (B-spline integral %.6f), Loop %.9f\n",
               ks[i], cc, spline[i], loop);
        assert_near(cc, spline[i], 2e-6);
        assert_near(loop, cc, 1e-9);
    }
    double m = 0;
    assert_int_equal(xyl__subdivide_mean_limit_radius(XYL_SUBDIVIDE_NONE, 4, &m), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__subdivide_mean_limit_radius(XYL_SUBDIVIDE_LOOP, 2, &m), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__subdivide_mean_limit_radius(XYL_SUBDIVIDE_LOOP, 33, &m), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__subdivide_mean_limit_radius(XYL_SUBDIVIDE_LOOP, 4, NULL), XYL_ERR_INVALID_ARGUMENT);
}

/* The same factor without trusting PrimvarRefiner::Limit: plain refinement, level after level.
 * The probe's radius after L levels is limit + (1 - limit) / 4^L (the error shrinks by the
 * subdominant eigenvalue 1/4 of the regular vertex rule), so one Richardson step,
 * (4 f_L - f_(L-1)) / 3, recovers the limit. */
static void repeated_refinement_converges_to_the_limit_factor(void **state)
{
    (void)state;
    double worst = 0;
    for (uint32_t k = 3; k <= 8; ++k) {
        const double limit = (4 + 2 * cos(2 * PI / k)) / 6;
        double f[5];
        for (uint32_t level = 0; level <= 4; ++level) {
            assert_int_equal(xyl__subdivide_refined_radius_factor(k, level, &f[level]), XYL_OK);
            assert_near(f[level] - limit, (1 - limit) / pow(4, level), 1e-12);
        }
        assert_near(f[1], (3 + cos(2 * PI / k)) / 4, 1e-12); /* the vertex rule */
        double extrapolated = (4 * f[4] - f[3]) / 3;
        if (fabs(extrapolated - limit) > worst) worst = fabs(extrapolated - limit);
        assert_near(extrapolated, limit, 1e-9);
    }
    printf("refined radius factor: Richardson from 3 and 4 levels, max |diff| over k = 3..8: "
           "%.2e\n", worst);
    double f = 0;
    assert_int_equal(xyl__subdivide_refined_radius_factor(4, 7, &f), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl__subdivide_refined_radius_factor(2, 1, &f), XYL_ERR_INVALID_ARGUMENT);
}

/* ---- copies and edge cases ----------------------------------------------------------------- */

static void assert_same_mesh(const xyl_mesh *a, const xyl_mesh *b)
{
    assert_int_equal(a->vertex_count, b->vertex_count);
    assert_int_equal(a->quad_count, b->quad_count);
    assert_int_equal(a->triangle_count, b->triangle_count);
    size_t nv = a->vertex_count, nf = a->quad_count + a->triangle_count;
    assert_memory_equal(a->positions, b->positions, nv * sizeof *a->positions);
    assert_memory_equal(a->normals, b->normals, nv * sizeof *a->normals);
    assert_memory_equal(a->uvs, b->uvs, 2 * nv * sizeof *a->uvs);
    assert_memory_equal(a->branch_ids, b->branch_ids, nv * sizeof *a->branch_ids);
    if (a->quad_count)
        assert_memory_equal(a->quads, b->quads, 4 * a->quad_count * sizeof(uint32_t));
    if (a->triangle_count)
        assert_memory_equal(a->triangles, b->triangles, 3 * a->triangle_count * sizeof(uint32_t));
    assert_memory_equal(a->face_branches, b->face_branches, nf * sizeof(uint32_t));
    assert_int_equal(a->tri_view_count, b->tri_view_count);
    assert_memory_equal(a->tri_view, b->tri_view, 3 * a->tri_view_count * sizeof(uint32_t));
}

static void none_copies_exactly_and_null_desc_means_none(void **state)
{
    (void)state;
    xyl_vec3 p[8], n[8];
    float uv[16];
    uint32_t vb[8], fb[7] = {1, 2, 3, 4, 5, 6, 7};
    cube_positions(p);
    for (int i = 0; i < 8; ++i) {
        n[i].x = 0, n[i].y = 0, n[i].z = 1; /* not what smooth normals would give */
        uv[2 * i] = 0.1f * (float)i, uv[2 * i + 1] = 1 - 0.1f * (float)i;
        vb[i] = (uint32_t)(10 + i);
    }
    const uint32_t tris[6] = {1, 3, 7, 1, 7, 5};
    xyl_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.positions = p, d.normals = n, d.uvs = uv, d.branch_ids = vb, d.vertex_count = 8;
    d.quads = cube_quads, d.quad_count = 5, d.triangles = tris, d.triangle_count = 2;
    d.face_branches = fb;
    xyl_mesh *c = NULL;
    assert_int_equal(xyl_mesh_create(&d, &c, NULL), XYL_OK);
    xyl_subdivide_desc sd;
    memset(&sd, 0, sizeof sd);
    xyl_mesh *s = NULL;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_subdivide(c, &sd, &s, &diag), XYL_OK);
    assert_int_equal(diag.code, XYL_OK);
    assert_same_mesh(c, s);
    assert_ptr_not_equal(c->positions, s->positions);
    xyl_mesh_destroy(s);
    s = NULL;
    assert_int_equal(xyl_mesh_subdivide(c, NULL, &s, NULL), XYL_OK);
    assert_same_mesh(c, s);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(c);
}

static void mesh_without_faces_keeps_its_vertices(void **state)
{
    (void)state;
    const xyl_vec3 p[2] = {{1, 2, 3}, {4, 5, 6}};
    xyl_mesh *c = make_mesh(p, 2, NULL, 0, NULL, 0);
    xyl_mesh *s = subdivide(c, XYL_SUBDIVIDE_CATMARK);
    assert_int_equal(s->vertex_count, 2);
    assert_int_equal(s->quad_count + s->triangle_count, 0);
    assert_memory_equal(s->positions, p, sizeof p);
    xyl_mesh_destroy(s);
    xyl_mesh *e = make_mesh(NULL, 0, NULL, 0, NULL, 0);
    s = subdivide(e, XYL_SUBDIVIDE_LOOP);
    assert_int_equal(s->vertex_count, 0);
    xyl_mesh_destroy(s);
    xyl_mesh_destroy(e);
    xyl_mesh_destroy(c);
}

static void unused_vertices_stay_where_they_are(void **state)
{
    (void)state;
    xyl_vec3 p[9];
    cube_positions(p);
    p[8].x = 5, p[8].y = 6, p[8].z = 7; /* in no face */
    xyl_mesh *c = make_mesh(p, 9, cube_quads, 6, NULL, 0);
    for (int scheme = XYL_SUBDIVIDE_CATMARK; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme) {
        xyl_mesh *s = subdivide(c, (xyl_subdivision)scheme);
        assert_int_equal(s->vertex_count, 27); /* 8 + 12 + 6 + 1, and 8 + 18 + 1 */
        assert_true(find_vertex(s, 5, 6, 7, 0) >= 0);
        for (size_t v = 0; v < s->vertex_count; ++v)
            assert_true(isfinite(s->positions[v].x) && isfinite(s->positions[v].y) &&
                        isfinite(s->positions[v].z));
        xyl_mesh_destroy(s);
    }
    xyl_mesh_destroy(c);
}

/* OpenSubdiv refines non-manifold and inconsistently oriented input too (treating the offending
 * edges as sharp); it must come out finite, with the counts of one level. */
static void non_manifold_and_flipped_input_is_refined(void **state)
{
    (void)state;
    xyl_vec3 p[10];
    cube_positions(p);
    p[8].x = 0, p[8].y = -3, p[8].z = -1; /* a fin on the edge 0-1 */
    p[9].x = 0, p[9].y = -3, p[9].z = 1;
    uint32_t q[7 * 4];
    memcpy(q, cube_quads, sizeof cube_quads);
    const uint32_t fin[4] = {0, 1, 9, 8};
    memcpy(q + 24, fin, sizeof fin);
    uint32_t s0 = q[4 * 1 + 1]; /* flip the +z face */
    q[4 * 1 + 1] = q[4 * 1 + 3];
    q[4 * 1 + 3] = s0;
    xyl_mesh *c = make_mesh(p, 10, q, 7, NULL, 0);
    for (int scheme = XYL_SUBDIVIDE_CATMARK; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme) {
        xyl_mesh *s = subdivide(c, (xyl_subdivision)scheme);
        size_t edges = 12 + 3 + (scheme == XYL_SUBDIVIDE_LOOP ? 7 : 0);
        size_t faces = scheme == XYL_SUBDIVIDE_LOOP ? 14 : 7;
        assert_int_equal(s->vertex_count, 10 + edges + (scheme == XYL_SUBDIVIDE_LOOP ? 0 : faces));
        assert_int_equal(s->quad_count + s->triangle_count, 4 * faces);
        for (size_t v = 0; v < s->vertex_count; ++v)
            assert_true(isfinite(s->positions[v].x) && isfinite(s->positions[v].y) &&
                        isfinite(s->positions[v].z) && isfinite(s->normals[v].x));
        xyl_mesh_destroy(s);
    }
    xyl_mesh_destroy(c);
}

/* ---- errors -------------------------------------------------------------------------------- */

static xyl_mesh untouched_mesh;
#define UNTOUCHED (&untouched_mesh)

static void rejects_null_arguments_and_unknown_schemes(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    xyl_mesh *out = UNTOUCHED;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_subdivide(NULL, NULL, &out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.code, XYL_ERR_INVALID_ARGUMENT);
    assert_true(strlen(diag.message) > 0);
    assert_ptr_equal(out, UNTOUCHED);
    assert_int_equal(xyl_mesh_subdivide(c, NULL, NULL, NULL), XYL_ERR_INVALID_ARGUMENT);
    xyl_subdivide_desc sd;
    memset(&sd, 0, sizeof sd);
    sd.scheme = (xyl_subdivision)3;
    assert_int_equal(xyl_mesh_subdivide(c, &sd, &out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(out, UNTOUCHED);
    sd.scheme = (xyl_subdivision)-1;
    assert_int_equal(xyl_mesh_subdivide(c, &sd, &out, &diag), XYL_ERR_INVALID_ARGUMENT);
    /* the internal entry point zeroes out on failure */
    xyl__mesh_arrays a;
    memset(&a, 0xab, sizeof a);
    assert_int_equal(xyl__subdivide(NULL, XYL_SUBDIVIDE_CATMARK, false, NULL, NULL, &a, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_null(a.positions);
    assert_int_equal(a.vertex_count, 0);
    assert_int_equal(xyl__subdivide(NULL, XYL_SUBDIVIDE_CATMARK, false, NULL, NULL, NULL, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    const xyl__mesh *im = (const xyl__mesh *)c;
    memset(&a, 0xab, sizeof a);
    assert_int_equal(xyl__subdivide(&im->a, (xyl_subdivision)7, false, NULL, NULL, &a, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_null(a.quads);
    xyl_mesh_destroy(c);
}

static void limits_exceeded_fail_with_limit_exceeded(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    xyl_subdivide_desc sd;
    memset(&sd, 0, sizeof sd);
    xyl_mesh *out = UNTOUCHED;
    xyl_diag diag = fresh_diag();
    struct {
        xyl_subdivision scheme;
        uint64_t max_v, max_f;
        xyl_result expect;
    } cases[] = {
        {XYL_SUBDIVIDE_CATMARK, 25, 0, XYL_ERR_LIMIT_EXCEEDED},
        {XYL_SUBDIVIDE_CATMARK, 0, 23, XYL_ERR_LIMIT_EXCEEDED},
        {XYL_SUBDIVIDE_CATMARK, 26, 24, XYL_OK},
        {XYL_SUBDIVIDE_LOOP, 25, 0, XYL_ERR_LIMIT_EXCEEDED},
        {XYL_SUBDIVIDE_LOOP, 0, 47, XYL_ERR_LIMIT_EXCEEDED},
        {XYL_SUBDIVIDE_LOOP, 26, 48, XYL_OK},
        {XYL_SUBDIVIDE_NONE, 7, 0, XYL_ERR_LIMIT_EXCEEDED},
        {XYL_SUBDIVIDE_NONE, 0, 5, XYL_ERR_LIMIT_EXCEEDED},
        {XYL_SUBDIVIDE_NONE, 8, 6, XYL_OK},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; ++i) {
        sd.scheme = cases[i].scheme;
        sd.limits.max_vertices = cases[i].max_v;
        sd.limits.max_faces = cases[i].max_f;
        out = UNTOUCHED;
        xyl_result r = xyl_mesh_subdivide(c, &sd, &out, &diag);
        if (r != cases[i].expect)
            fail_msg("case %zu: expected %s, got %s (%s)", i, xyl_result_string(cases[i].expect),
                     xyl_result_string(r), diag.message);
        if (r == XYL_OK) {
            xyl_mesh_destroy(out);
        } else {
            assert_ptr_equal(out, UNTOUCHED);
            assert_int_equal(diag.code, XYL_ERR_LIMIT_EXCEEDED);
        }
    }
    xyl_mesh_destroy(c);
}

static void rejects_broken_caller_built_views(void **state)
{
    (void)state;
    xyl_vec3 p[8];
    cube_positions(p);
    uint32_t q[24];
    memcpy(q, cube_quads, sizeof q);
    xyl_mesh view;
    memset(&view, 0, sizeof view);
    view.positions = p, view.vertex_count = 8, view.quads = q, view.quad_count = 6;
    xyl_subdivide_desc sd;
    memset(&sd, 0, sizeof sd);
    sd.scheme = XYL_SUBDIVIDE_CATMARK;
    xyl_mesh *out = UNTOUCHED;
    xyl_diag diag = fresh_diag();
    /* a view without uvs, branch ids or face branches is fine */
    assert_int_equal(xyl_mesh_subdivide(&view, &sd, &out, &diag), XYL_OK);
    assert_int_equal(out->quad_count, 24);
    xyl_mesh_destroy(out);
    out = UNTOUCHED;
    q[13] = 8;
    assert_int_equal(xyl_mesh_subdivide(&view, &sd, &out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.index, 3);
    q[13] = q[12];
    assert_int_equal(xyl_mesh_subdivide(&view, &sd, &out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.index, 3);
    q[13] = cube_quads[13];
    uint8_t wraps[6] = {0, 0, 0, 0x10, 0, 0}; /* a quad has corners 0..3 */
    view.uv_wraps = wraps;
    assert_int_equal(xyl_mesh_subdivide(&view, &sd, &out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(diag.index, 3);
    view.uv_wraps = NULL;
    p[5].y = NAN;
    assert_int_equal(xyl_mesh_subdivide(&view, &sd, &out, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(diag.index, 5);
    p[5].y = -1;
    view.quads = NULL;
    assert_int_equal(xyl_mesh_subdivide(&view, &sd, &out, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(out, UNTOUCHED);
}

/* A closed fan: one centre in more edges than OpenSubdiv's valence limit (65535). */
static void refused_topology_fails_with_unsupported(void **state)
{
    (void)state;
    enum { RIM = 65536 }; /* one more than the limit; Far takes seconds (quadratic in valence) */
    xyl_vec3 *p = malloc((RIM + 2) * sizeof *p);
    uint32_t *t = malloc(2 * 3 * (size_t)RIM * sizeof *t);
    assert_true(p && t);
    for (uint32_t i = 0; i < RIM; ++i) {
        p[i].x = (float)cos(2 * PI * i / RIM), p[i].y = (float)sin(2 * PI * i / RIM), p[i].z = 0;
        uint32_t *up = t + 6 * i, next = (i + 1) % RIM;
        up[0] = RIM, up[1] = i, up[2] = next;          /* apex above */
        up[3] = RIM + 1, up[4] = next, up[5] = i;      /* apex below */
    }
    p[RIM].x = 0, p[RIM].y = 0, p[RIM].z = 1;
    p[RIM + 1].x = 0, p[RIM + 1].y = 0, p[RIM + 1].z = -1;
    xyl_mesh *c = make_mesh(p, RIM + 2, NULL, 0, t, 2 * RIM);
    free(p);
    free(t);
    xyl_subdivide_desc sd;
    memset(&sd, 0, sizeof sd);
    sd.scheme = XYL_SUBDIVIDE_CATMARK;
    xyl_mesh *out = UNTOUCHED;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl_mesh_subdivide(c, &sd, &out, &diag), XYL_ERR_UNSUPPORTED);
    assert_true(strlen(diag.message) > 0);
    assert_ptr_equal(out, UNTOUCHED);
    xyl_mesh_destroy(c);
}

static void allocation_failures_fail_cleanly_and_leak_nothing(void **state)
{
    (void)state;
    xyl_mesh *c = two_branch_cube();
    for (int scheme = XYL_SUBDIVIDE_NONE; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme) {
        size_t failures = 0;
        for (size_t n = 1;; ++n) {
            tu_counter cnt = {0, 0, 0, n};
            xyl_subdivide_desc sd;
            memset(&sd, 0, sizeof sd);
            sd.scheme = (xyl_subdivision)scheme;
            sd.alloc = tu_counting(&cnt);
            xyl_mesh *out = UNTOUCHED;
            xyl_diag diag = fresh_diag();
            xyl_result r = xyl_mesh_subdivide(c, &sd, &out, &diag);
            if (r == XYL_OK) {
                xyl_mesh_destroy(out);
                assert_int_equal(cnt.allocs, cnt.frees);
                break;
            }
            assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
            assert_ptr_equal(out, UNTOUCHED);
            assert_int_equal(cnt.allocs, cnt.frees);
            ++failures;
        }
        assert_true(failures > 3);
    }
    xyl_mesh_destroy(c);
}

/* ---- creases: edges kept infinitely sharp (xyl__subdivide_creased) ------------------------- */

/* The prism's bottom ring as creases: (i, i + 1 mod k), the ring's own direction. With
 * corner_and_dart, also the band edge (0, k) up from vertex 0, which makes vertex 0 a corner
 * (three creases) and vertex k a dart (one). Returns the number of pairs. */
static size_t prism_creases(int k, bool corner_and_dart, uint32_t *pairs)
{
    size_t n = 0;
    for (int i = 0; i < k; ++i, ++n) {
        pairs[2 * n] = (uint32_t)i;
        pairs[2 * n + 1] = (uint32_t)((i + 1) % k);
    }
    if (corner_and_dart) {
        pairs[2 * n] = (uint32_t)k; /* either order */
        pairs[2 * n + 1] = 0;
        ++n;
    }
    return n;
}

static void assert_same_bits(const void *a, const void *b, size_t bytes, const char *what,
                             const char *array)
{
    if ((a == NULL) != (b == NULL)) fail_msg("%s: %s is NULL on one path only", what, array);
    if (a && bytes && memcmp(a, b, bytes) != 0) fail_msg("%s: %s differ", what, array);
}

/* Every array of two refined meshes, bit for bit. */
static void assert_same_refined(const xyl__mesh_arrays *a, const xyl__mesh_arrays *b,
                                const char *what)
{
    assert_int_equal(a->vertex_count, b->vertex_count);
    assert_int_equal(a->quad_count, b->quad_count);
    assert_int_equal(a->triangle_count, b->triangle_count);
    const size_t nv = a->vertex_count, nf = a->quad_count + a->triangle_count;
    assert_same_bits(a->positions, b->positions, nv * sizeof *a->positions, what, "positions");
    assert_same_bits(a->normals, b->normals, nv * sizeof *a->normals, what, "normals");
    assert_same_bits(a->uvs, b->uvs, 2 * nv * sizeof *a->uvs, what, "uvs");
    assert_same_bits(a->branch_ids, b->branch_ids, nv * sizeof *a->branch_ids, what, "branches");
    assert_same_bits(a->quads, b->quads, 4 * a->quad_count * sizeof *a->quads, what, "quads");
    assert_same_bits(a->triangles, b->triangles, 3 * a->triangle_count * sizeof *a->triangles,
                     what, "triangles");
    assert_same_bits(a->face_branches, b->face_branches, nf * sizeof *a->face_branches, what,
                     "face branches");
    assert_same_bits(a->uv_wraps, b->uv_wraps, nf * sizeof *a->uv_wraps, what, "uv wraps");
}

/* The direct path takes creases with Sdc's crease, corner and dart masks and gives Far's bits:
 * a creased ring, and a ring with a corner and a dart, k = 3..8, both schemes, limit or not. */
static void creased_direct_path_matches_far_bit_for_bit(void **state)
{
    (void)state;
    for (int k = 3; k <= 8; ++k)
        for (int extra = 0; extra <= 1; ++extra)
            for (int scheme = XYL_SUBDIVIDE_CATMARK; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme)
                for (int limit = 0; limit <= 1; ++limit) {
                    xyl_mesh *m = prism(k, 4, 1.0);
                    uint32_t pairs[2 * (PRISM_MAX_K + 1)];
                    const xyl__creases c = {pairs, prism_creases(k, extra, pairs)};
                    char what[96];
                    snprintf(what, sizeof what, "k=%d %s %s %s", k, extra ? "corner" : "ring",
                             scheme == XYL_SUBDIVIDE_LOOP ? "loop" : "catmark",
                             limit ? "limit" : "control points");
                    const xyl__mesh_arrays *in = &((const xyl__mesh *)m)->a;
                    xyl__mesh_arrays far, direct, plain;
                    xyl_diag diag = fresh_diag();
                    xyl_subdivision sch = (xyl_subdivision)scheme;
                    assert_int_equal(xyl__subdivide_creased(in, &c, sch, limit, NULL,
                                                            XYL__SUBDIVIDE_FAR, NULL, &far, &diag),
                                     XYL_OK);
                    assert_int_equal(xyl__subdivide_creased(in, &c, sch, limit, NULL,
                                                            XYL__SUBDIVIDE_DIRECT, NULL, &direct,
                                                            &diag),
                                     XYL_OK);
                    assert_same_refined(&far, &direct, what);
                    /* the creases change the result: the check above compares something */
                    assert_int_equal(xyl__subdivide_by(in, sch, limit, NULL, XYL__SUBDIVIDE_DIRECT,
                                                       NULL, &plain, &diag),
                                     XYL_OK);
                    assert_true(memcmp(plain.positions, direct.positions,
                                       plain.vertex_count * sizeof *plain.positions) != 0);
                    xyl__mesh_arrays_free(&far, NULL);
                    xyl__mesh_arrays_free(&direct, NULL);
                    xyl__mesh_arrays_free(&plain, NULL);
                    xyl_mesh_destroy(m);
                }
}

/* A creased bottom ring stays in its plane (z = 0) and the cap inside it stays flat: every
 * refined vertex born of the cap is at z = 0 exactly and none is below it, with or without the
 * limit. Without the creases the smooth rules lift the ring off the plane. */
static void a_creased_ring_and_its_cap_stay_in_their_plane(void **state)
{
    (void)state;
    for (int k = 3; k <= 8; ++k)
        for (int scheme = XYL_SUBDIVIDE_CATMARK; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme)
            for (int limit = 0; limit <= 1; ++limit) {
                xyl_mesh *m = prism(k, 4, 1.0);
                uint32_t pairs[2 * PRISM_MAX_K];
                const xyl__creases c = {pairs, prism_creases(k, false, pairs)};
                const xyl__mesh_arrays *in = &((const xyl__mesh *)m)->a;
                const bool loop = scheme == XYL_SUBDIVIDE_LOOP;
                for (int creased = 0; creased <= 1; ++creased) {
                    xyl__mesh_arrays out;
                    xyl_diag diag = fresh_diag();
                    assert_int_equal(xyl__subdivide_creased(in, creased ? &c : NULL,
                                                            (xyl_subdivision)scheme, limit, NULL,
                                                            XYL__SUBDIVIDE_ANY, NULL, &out, &diag),
                                     XYL_OK);
                    size_t on_plane = 0;
                    double lowest = INFINITY, ring_lowest = INFINITY;
                    for (size_t v = 0; v < out.vertex_count; ++v) {
                        lowest = fmin(lowest, out.positions[v].z);
                        on_plane += out.positions[v].z == 0.0f;
                        /* vertex points come first: the ring's are 0 .. k - 1 */
                        if (v < (size_t)k) ring_lowest = fmin(ring_lowest, out.positions[v].z);
                    }
                    /* the ring's k vertex and k edge points, the fan's k - 3 inner edges'
                     * points and (Catmull-Clark) its k - 2 face points */
                    const size_t cap = (size_t)(2 * k + (k - 3) + (loop ? 0 : k - 2));
                    if (creased) {
                        assert_true(lowest == 0.0);
                        assert_int_equal(on_plane, cap);
                    } else {
                        assert_true(lowest >= 0.0);
                        assert_true(ring_lowest > 0.01);
                        assert_true(on_plane < cap);
                    }
                    xyl__mesh_arrays_free(&out, NULL);
                }
                xyl_mesh_destroy(m);
            }
}

/* Creases name two distinct vertices that are the ends of an edge (for Loop, of the triangles
 * its quads are split into), on both paths; else XYL_ERR_INVALID_ARGUMENT, diag.index the
 * pair, and the output zeroed. */
static void creases_must_be_edges_of_the_mesh(void **state)
{
    (void)state;
    const int k = 4;
    xyl_mesh *m = prism(k, 3, 1.0);
    const xyl__mesh_arrays *in = &((const xyl__mesh *)m)->a;
    const uint32_t out_of_range[] = {0, 1, 1, 12}, same[] = {0, 1, 2, 2};
    const uint32_t diagonal[] = {0, 1, 0, k + 1}; /* the band quad (0, 1, 5, 4)'s diagonal */
    struct {
        const uint32_t *pairs;
        size_t count;
        int64_t index;
        bool loop_ok; /* Loop splits (0, 1, 5, 4) into (0, 1, 5), (0, 5, 4) */
    } cases[] = {{NULL, 1, -1, false},
                 {out_of_range, 2, 1, false},
                 {same, 2, 1, false},
                 {diagonal, 2, 1, true}};
    xyl__mesh_arrays zero;
    memset(&zero, 0, sizeof zero);
    for (size_t i = 0; i < sizeof cases / sizeof *cases; ++i)
        for (int scheme = XYL_SUBDIVIDE_CATMARK; scheme <= XYL_SUBDIVIDE_LOOP; ++scheme)
            for (int path = XYL__SUBDIVIDE_ANY; path <= XYL__SUBDIVIDE_DIRECT; ++path) {
                const xyl__creases c = {cases[i].pairs, cases[i].count};
                const bool ok = cases[i].loop_ok && scheme == XYL_SUBDIVIDE_LOOP;
                xyl__mesh_arrays out;
                memset(&out, 0xab, sizeof out);
                xyl_diag diag = fresh_diag();
                xyl_result r = xyl__subdivide_creased(in, &c, (xyl_subdivision)scheme, true, NULL,
                                                      (xyl__subdivide_path)path, NULL, &out,
                                                      &diag);
                if (ok) {
                    assert_int_equal(r, XYL_OK);
                    xyl__mesh_arrays_free(&out, NULL);
                    continue;
                }
                assert_int_equal(r, XYL_ERR_INVALID_ARGUMENT);
                assert_int_equal(diag.index, cases[i].index);
                assert_true(strstr(diag.message, "crease") != NULL);
                assert_memory_equal(&out, &zero, sizeof out);
            }
    /* no creases: exactly xyl__subdivide_by */
    xyl__mesh_arrays a, b;
    const xyl__creases none = {NULL, 0};
    assert_int_equal(xyl__subdivide_creased(in, &none, XYL_SUBDIVIDE_CATMARK, true, NULL,
                                            XYL__SUBDIVIDE_ANY, NULL, &a, NULL),
                     XYL_OK);
    assert_int_equal(xyl__subdivide(in, XYL_SUBDIVIDE_CATMARK, true, NULL, NULL, &b, NULL), XYL_OK);
    assert_same_refined(&a, &b, "no creases");
    xyl__mesh_arrays_free(&a, NULL);
    xyl__mesh_arrays_free(&b, NULL);
    xyl_mesh_destroy(m);
}

/* The creased paths fail cleanly on every allocation failure, Far's and the direct one's. */
static void creased_allocation_failures_fail_cleanly_and_leak_nothing(void **state)
{
    (void)state;
    const int k = 5;
    xyl_mesh *m = prism(k, 3, 1.0);
    const xyl__mesh_arrays *in = &((const xyl__mesh *)m)->a;
    uint32_t pairs[2 * PRISM_MAX_K];
    const xyl__creases c = {pairs, prism_creases(k, false, pairs)};
    for (int path = XYL__SUBDIVIDE_FAR; path <= XYL__SUBDIVIDE_DIRECT; ++path) {
        size_t failures = 0;
        for (size_t n = 1;; ++n) {
            tu_counter cnt = {0, 0, 0, n};
            xyl_allocator alloc = tu_counting(&cnt);
            xyl__mesh_arrays out;
            xyl_result r = xyl__subdivide_creased(in, &c, XYL_SUBDIVIDE_CATMARK, true, NULL,
                                                  (xyl__subdivide_path)path, &alloc, &out, NULL);
            if (r == XYL_OK) {
                xyl__mesh_arrays_free(&out, &alloc);
                assert_int_equal(cnt.allocs, cnt.frees);
                break;
            }
            assert_int_equal(r, XYL_ERR_OUT_OF_MEMORY);
            assert_int_equal(cnt.allocs, cnt.frees);
            ++failures;
        }
        assert_true(failures > 3);
    }
    xyl_mesh_destroy(m);
}

static void internal_entry_leaves_normals_to_the_caller(void **state)
{
    (void)state;
    xyl_mesh *c = cube();
    const xyl__mesh *im = (const xyl__mesh *)c;
    xyl__mesh_arrays out;
    xyl_diag diag = fresh_diag();
    assert_int_equal(xyl__subdivide(&im->a, XYL_SUBDIVIDE_CATMARK, false, NULL, NULL, &out, &diag),
                     XYL_OK);
    assert_null(out.normals);
    assert_non_null(out.triangles); /* empty but allocated */
    assert_int_equal(out.vertex_count, 26);
    xyl__mesh_arrays_free(&out, NULL);
    assert_int_equal(xyl__subdivide(&im->a, XYL_SUBDIVIDE_NONE, false, NULL, NULL, &out, &diag), XYL_OK);
    assert_non_null(out.normals); /* NONE copies them */
    xyl__mesh_arrays_free(&out, NULL);
    xyl_mesh_limits lim = {10, 0};
    memset(&out, 0xab, sizeof out);
    assert_int_equal(xyl__subdivide(&im->a, XYL_SUBDIVIDE_LOOP, false, &lim, NULL, &out, &diag),
                     XYL_ERR_LIMIT_EXCEEDED);
    xyl__mesh_arrays zero;
    memset(&zero, 0, sizeof zero);
    assert_memory_equal(&out, &zero, sizeof out);
    xyl_mesh_destroy(c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(catmark_cube_has_24_quads_26_vertices_and_euler_2),
        cmocka_unit_test(catmark_cube_points_follow_the_catmull_clark_rules),
        cmocka_unit_test(catmark_orders_vertex_then_face_then_edge_points),
        cmocka_unit_test(catmark_preserves_orientation_and_gives_outward_normals),
        cmocka_unit_test(catmark_turns_triangles_into_quads),
        cmocka_unit_test(loop_tetrahedron_quadruples_faces),
        cmocka_unit_test(loop_octahedron_quadruples_faces),
        cmocka_unit_test(loop_triangulates_quads_first),
        cmocka_unit_test(face_branches_are_inherited_from_the_parent_face),
        cmocka_unit_test(vertex_branches_follow_the_documented_rules),
        cmocka_unit_test(uvs_are_interpolated_linearly),
        cmocka_unit_test(catmark_ring_radius_follows_the_vertex_rule),
        cmocka_unit_test(limit_radius_factor_matches_opensubdiv),
        cmocka_unit_test(repeated_refinement_converges_to_the_limit_factor),
        cmocka_unit_test(limit_points_match_repeated_refinement),
        cmocka_unit_test(limit_normals_are_radial_on_a_catmark_prism),
        cmocka_unit_test(mean_limit_radius_matches_the_b_spline_integral),
        cmocka_unit_test(none_copies_exactly_and_null_desc_means_none),
        cmocka_unit_test(mesh_without_faces_keeps_its_vertices),
        cmocka_unit_test(unused_vertices_stay_where_they_are),
        cmocka_unit_test(non_manifold_and_flipped_input_is_refined),
        cmocka_unit_test(rejects_null_arguments_and_unknown_schemes),
        cmocka_unit_test(limits_exceeded_fail_with_limit_exceeded),
        cmocka_unit_test(rejects_broken_caller_built_views),
        cmocka_unit_test(refused_topology_fails_with_unsupported),
        cmocka_unit_test(allocation_failures_fail_cleanly_and_leak_nothing),
        cmocka_unit_test(internal_entry_leaves_normals_to_the_caller),
        cmocka_unit_test(creased_direct_path_matches_far_bit_for_bit),
        cmocka_unit_test(a_creased_ring_and_its_cap_stay_in_their_plane),
        cmocka_unit_test(creases_must_be_edges_of_the_mesh),
        cmocka_unit_test(creased_allocation_failures_fail_cleanly_and_leak_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
