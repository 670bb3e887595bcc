/* Mesh checks: edge use, components, vertex fans, degenerate and duplicate faces
 * (xyl_mesh_check). Definitions and tolerances: docs/mesh-checks.md.
 *
 * Every face corner is a "slot": quads own slots 4f..4f+3, triangles follow at 4Q + 3t. Slot h
 * starts the half-edge from its vertex to the next one of its face, and is also the corner of its
 * face at its vertex. Half-edges are bucketed by their smaller vertex (a counting sort) and sorted
 * by the larger one inside each bucket, so every undirected edge becomes one run: O(V + F) plus
 * O(k log k) per bucket of k half-edges, O(F log F) at worst. Duplicate faces are found the same
 * way, bucketed by their smallest vertex. */
#include <string.h>

#include "mesh_internal.h"

/* A face whose area is at most this times the squared diagonal of the bounding box of the used
 * vertices is degenerate. The same rule skips triangles in mesh_intersect.c. */
#define DEGENERATE_AREA_REL XYL__EPS_REL

/* Buckets up to this size are sorted by insertion (typical buckets hold 2 to 8 entries). */
#define SMALL_BUCKET 16

/* Vertex indices are shifted left by one in a half-edge key, so they must stay below 2^31. */
#define MAX_CHECK_VERTICES (UINT64_C(1) << 31)

typedef struct half_edge {
    uint32_t key;  /* (larger vertex << 1) | 1 when the half-edge runs from smaller to larger */
    uint32_t slot; /* where the half-edge starts */
} half_edge;

/* Sorted vertex set of a face; a triangle's fourth entry is UINT32_MAX, never a valid index. */
typedef struct face_key {
    uint32_t v[4];
} face_key;

typedef struct scratch {
    uint32_t *offsets;       /* vertex_count + 1: bucket starts */
    half_edge *he;           /* one per slot, bucketed by smaller vertex */
    uint32_t *face_parent;   /* union-find over faces (components) */
    uint32_t *corner_parent; /* union-find over corners (fans around a vertex) */
    uint8_t *vertex_state;   /* used, then 0 unused, 1 one fan, 2 several fans */
    face_key *keys;          /* one per face, bucketed by smallest vertex */
} scratch;

/* ---- faces and slots ------------------------------------------------------------------------ */

static uint32_t face_first_slot(const xyl_mesh *m, size_t f)
{
    size_t q = m->quad_count;
    return (uint32_t)(f < q ? 4 * f : 4 * q + 3 * (f - q));
}

static uint32_t slot_face(const xyl_mesh *m, uint32_t h)
{
    size_t q4 = 4 * m->quad_count;
    return (uint32_t)(h < q4 ? h / 4 : m->quad_count + (h - q4) / 3);
}

/* The slot after h in its face, wrapping around: the corner at the half-edge's end. */
static uint32_t slot_next(const xyl_mesh *m, uint32_t h)
{
    size_t q4 = 4 * m->quad_count;
    if (h < q4) return (h & 3u) == 3u ? h - 3u : h + 1u;
    return (h - q4) % 3 == 2 ? h - 2u : h + 1u;
}

/* ---- limits and scratch memory --------------------------------------------------------------- */

/* Slots are numbered with uint32_t. */
static xyl_result check_limits(const xyl_mesh *m, xyl_diag *diag)
{
    if ((uint64_t)m->vertex_count > MAX_CHECK_VERTICES || m->quad_count > UINT32_MAX / 4 ||
        m->triangle_count > (UINT32_MAX - 4 * m->quad_count) / 3)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu vertices, %zu quads and %zu triangles exceed the check's indexing",
                         m->vertex_count, m->quad_count, m->triangle_count);
    return XYL_OK;
}

static void scratch_free(scratch *s, const xyl_allocator *a)
{
    xyl__free(a, s->offsets);
    xyl__free(a, s->he);
    xyl__free(a, s->face_parent);
    xyl__free(a, s->corner_parent);
    xyl__free(a, s->vertex_state);
    xyl__free(a, s->keys);
    memset(s, 0, sizeof *s);
}

/* Arrays of he, face_parent, corner_parent and keys are left uninitialised: every entry is
 * written before it is read. */
static bool scratch_alloc(scratch *s, size_t vertices, size_t faces, size_t slots,
                          const xyl_allocator *a)
{
    s->offsets = xyl__calloc(a, vertices + 1, sizeof *s->offsets);
    s->he = xyl__alloc_array(a, slots, sizeof *s->he);
    s->face_parent = xyl__alloc_array(a, faces, sizeof *s->face_parent);
    s->corner_parent = xyl__alloc_array(a, slots, sizeof *s->corner_parent);
    s->vertex_state = xyl__calloc(a, vertices, sizeof *s->vertex_state);
    s->keys = xyl__alloc_array(a, faces, sizeof *s->keys);
    bool ok = s->offsets && s->he && s->face_parent && s->corner_parent && s->vertex_state &&
              s->keys;
    if (!ok) scratch_free(s, a);
    return ok;
}

/* ---- union-find ----------------------------------------------------------------------------- */

static uint32_t uf_find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]]; /* path halving keeps later finds short */
        x = parent[x];
    }
    return x;
}

static void uf_union(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = uf_find(parent, a);
    b = uf_find(parent, b);
    /* The smaller index becomes the root: deterministic, and roots are found by parent[x] == x. */
    if (a < b) parent[b] = a;
    else if (b < a) parent[a] = b;
}

static void uf_init(uint32_t *parent, size_t n)
{
    for (size_t i = 0; i < n; ++i) parent[i] = (uint32_t)i;
}

static size_t uf_roots(const uint32_t *parent, size_t n)
{
    size_t roots = 0;
    for (size_t i = 0; i < n; ++i) roots += parent[i] == i;
    return roots;
}

/* ---- degenerate faces ----------------------------------------------------------------------- */

/* Marks used vertices in state and returns the area tolerance from their bounding box. */
static double area_tolerance(const xyl_mesh *m, uint8_t *state)
{
    size_t faces = m->quad_count + m->triangle_count;
    for (size_t f = 0; f < faces; ++f) {
        int n;
        const uint32_t *idx = xyl__mesh_face(m, f, &n);
        for (int k = 0; k < n; ++k) state[idx[k]] = 1;
    }
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < m->vertex_count; ++v) {
        if (!state[v]) continue;
        const float p[3] = {m->positions[v].x, m->positions[v].y, m->positions[v].z};
        for (int k = 0; k < 3; ++k) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
    if (faces == 0) return 0.0;
    xyl__dvec3 d = xyl__d3((double)hi[0] - lo[0], (double)hi[1] - lo[1], (double)hi[2] - lo[2]);
    return DEGENERATE_AREA_REL * xyl__d3_dot(d, d);
}

/* Squared length of (b - a) x (c - a), four times the squared area of the triangle. */
static double twice_area_sq(const xyl_vec3 *p, uint32_t a, uint32_t b, uint32_t c)
{
    xyl__dvec3 pa = xyl__from_f3(p[a]);
    xyl__dvec3 n = xyl__d3_cross(xyl__d3_sub(xyl__from_f3(p[b]), pa),
                                 xyl__d3_sub(xyl__from_f3(p[c]), pa));
    return xyl__d3_dot(n, n);
}

/* Area <= tol, compared squared. A quad is degenerate when either triangle of its split is (the
 * triangulated view must not hold a sliver), or when its vector area vanishes (folded flat). */
static bool face_degenerate(const xyl_mesh *m, size_t f, double tol)
{
    const xyl_vec3 *p = m->positions;
    double limit = 4.0 * tol * tol;
    int n;
    const uint32_t *q = xyl__mesh_face(m, f, &n);
    if (n == 3) return twice_area_sq(p, q[0], q[1], q[2]) <= limit;
    xyl__dvec3 a = xyl__from_f3(p[q[0]]), b = xyl__from_f3(p[q[1]]);
    xyl__dvec3 c = xyl__from_f3(p[q[2]]), d = xyl__from_f3(p[q[3]]);
    xyl__dvec3 vector_area = xyl__d3_cross(xyl__d3_sub(c, a), xyl__d3_sub(d, b));
    return xyl__d3_dot(vector_area, vector_area) <= limit ||
           twice_area_sq(p, q[0], q[1], q[2]) <= limit ||
           twice_area_sq(p, q[0], q[2], q[3]) <= limit;
}

/* ---- edges ---------------------------------------------------------------------------------- */

/* Counting sort of the half-edges by their smaller vertex. offsets[v] ends as the start of v's
 * bucket: the counts are summed inclusively, then every placement steps its bucket end back. */
static void bucket_half_edges(const xyl_mesh *m, scratch *s)
{
    size_t faces = m->quad_count + m->triangle_count;
    for (size_t f = 0; f < faces; ++f) {
        int n;
        const uint32_t *idx = xyl__mesh_face(m, f, &n);
        for (int k = 0; k < n; ++k) {
            uint32_t a = idx[k], b = idx[k + 1 < n ? k + 1 : 0];
            s->offsets[a < b ? a : b]++;
        }
    }
    for (size_t v = 1; v <= m->vertex_count; ++v) s->offsets[v] += s->offsets[v - 1];
    for (size_t f = 0; f < faces; ++f) {
        int n;
        const uint32_t *idx = xyl__mesh_face(m, f, &n);
        uint32_t first = face_first_slot(m, f);
        for (int k = 0; k < n; ++k) {
            uint32_t a = idx[k], b = idx[k + 1 < n ? k + 1 : 0];
            half_edge e = {a < b ? b << 1 | 1u : a << 1, first + (uint32_t)k};
            s->he[--s->offsets[a < b ? a : b]] = e;
        }
    }
}

static bool he_less(half_edge a, half_edge b)
{
    return a.key < b.key || (a.key == b.key && a.slot < b.slot);
}

static int he_compare(const void *pa, const void *pb)
{
    half_edge a = *(const half_edge *)pa, b = *(const half_edge *)pb;
    return he_less(a, b) ? -1 : he_less(b, a) ? 1 : 0;
}

static void sort_half_edges(half_edge *e, size_t n)
{
    if (n > SMALL_BUCKET) {
        xyl__sort(e, n, sizeof *e, he_compare);
        return;
    }
    for (size_t i = 1; i < n; ++i) {
        half_edge x = e[i];
        size_t j = i;
        for (; j > 0 && he_less(x, e[j - 1]); --j) e[j] = e[j - 1];
        e[j] = x;
    }
}

/* The corners of half-edge e's face at the edge's smaller and larger vertex. */
static void edge_corners(const xyl_mesh *m, half_edge e, uint32_t *at_lo, uint32_t *at_hi)
{
    uint32_t next = slot_next(m, e.slot);
    bool forward = e.key & 1u;
    *at_lo = forward ? e.slot : next;
    *at_hi = forward ? next : e.slot;
}

/* One undirected edge with its n uses e[0..n-1]. */
static void classify_edge(const xyl_mesh *m, const half_edge *e, size_t n, scratch *s,
                          xyl_mesh_report *r)
{
    r->edges++;
    for (size_t k = 1; k < n; ++k)
        uf_union(s->face_parent, slot_face(m, e[0].slot), slot_face(m, e[k].slot));
    if (n == 1) {
        r->boundary_edges++;
        return;
    }
    if (n >= 3) {
        /* Such an edge joins no fans, so its ends become non-manifold vertices too. */
        r->nonmanifold_edges++;
        return;
    }
    if ((e[0].key & 1u) == (e[1].key & 1u)) r->misoriented_edges++;
    /* Two faces across an edge are neighbours in the fans of both its ends. */
    uint32_t lo0, hi0, lo1, hi1;
    edge_corners(m, e[0], &lo0, &hi0);
    edge_corners(m, e[1], &lo1, &hi1);
    uf_union(s->corner_parent, lo0, lo1);
    uf_union(s->corner_parent, hi0, hi1);
}

static void classify_edges(const xyl_mesh *m, scratch *s, xyl_mesh_report *r)
{
    for (size_t v = 0; v < m->vertex_count; ++v) {
        half_edge *b = s->he + s->offsets[v];
        size_t n = s->offsets[v + 1] - s->offsets[v];
        sort_half_edges(b, n);
        for (size_t i = 0; i < n;) {
            size_t j = i + 1;
            while (j < n && b[j].key >> 1 == b[i].key >> 1) ++j;
            classify_edge(m, b + i, j - i, s, r);
            i = j;
        }
    }
}

/* Each root of the corner union-find is one fan; a vertex with two or more is non-manifold. */
static void count_fans(const xyl_mesh *m, uint32_t slots, scratch *s, xyl_mesh_report *r)
{
    memset(s->vertex_state, 0, m->vertex_count);
    size_t q4 = 4 * m->quad_count;
    for (uint32_t h = 0; h < slots; ++h) {
        if (s->corner_parent[h] != h) continue;
        uint8_t *st = &s->vertex_state[h < q4 ? m->quads[h] : m->triangles[h - q4]];
        if (*st < 2) ++*st;
    }
    for (size_t v = 0; v < m->vertex_count; ++v) {
        r->unused_vertices += s->vertex_state[v] == 0;
        r->nonmanifold_vertices += s->vertex_state[v] == 2;
    }
}

/* ---- duplicate faces ------------------------------------------------------------------------ */

static face_key make_key(const xyl_mesh *m, size_t f)
{
    face_key k = {{UINT32_MAX, UINT32_MAX, UINT32_MAX, UINT32_MAX}};
    int n;
    const uint32_t *idx = xyl__mesh_face(m, f, &n);
    for (int i = 0; i < n; ++i) {
        int j = i;
        for (; j > 0 && k.v[j - 1] > idx[i]; --j) k.v[j] = k.v[j - 1];
        k.v[j] = idx[i];
    }
    return k;
}

static uint32_t smallest_vertex(const xyl_mesh *m, size_t f)
{
    int n;
    const uint32_t *idx = xyl__mesh_face(m, f, &n);
    uint32_t v = idx[0];
    for (int i = 1; i < n; ++i) v = idx[i] < v ? idx[i] : v;
    return v;
}

static int key_compare(const void *pa, const void *pb)
{
    const face_key *a = pa, *b = pb;
    for (int i = 0; i < 4; ++i)
        if (a->v[i] != b->v[i]) return a->v[i] < b->v[i] ? -1 : 1;
    return 0;
}

static void sort_keys(face_key *k, size_t n)
{
    if (n > SMALL_BUCKET) {
        xyl__sort(k, n, sizeof *k, key_compare);
        return;
    }
    for (size_t i = 1; i < n; ++i) {
        face_key x = k[i];
        size_t j = i;
        for (; j > 0 && key_compare(&x, &k[j - 1]) < 0; --j) k[j] = k[j - 1];
        k[j] = x;
    }
}

/* Faces whose vertex set another face has, bucketed by smallest vertex like the edges. */
static size_t count_duplicates(const xyl_mesh *m, scratch *s)
{
    size_t faces = m->quad_count + m->triangle_count, vc = m->vertex_count, dup = 0;
    memset(s->offsets, 0, (vc + 1) * sizeof *s->offsets);
    for (size_t f = 0; f < faces; ++f) s->offsets[smallest_vertex(m, f)]++;
    for (size_t v = 1; v <= vc; ++v) s->offsets[v] += s->offsets[v - 1];
    for (size_t f = 0; f < faces; ++f) {
        face_key k = make_key(m, f);
        s->keys[--s->offsets[k.v[0]]] = k;
    }
    for (size_t v = 0; v < vc; ++v) {
        face_key *b = s->keys + s->offsets[v];
        size_t n = s->offsets[v + 1] - s->offsets[v];
        if (n < 2) continue;
        sort_keys(b, n);
        for (size_t i = 0; i < n;) {
            size_t j = i + 1;
            while (j < n && key_compare(b + i, b + j) == 0) ++j;
            if (j - i > 1) dup += j - i;
            i = j;
        }
    }
    return dup;
}

/* ---- the check ------------------------------------------------------------------------------ */

static void fill_report(const xyl_mesh *m, scratch *s, xyl_mesh_report *r)
{
    size_t faces = m->quad_count + m->triangle_count;
    uint32_t slots = (uint32_t)(4 * m->quad_count + 3 * m->triangle_count);
    memset(r, 0, sizeof *r);
    r->vertices = m->vertex_count;
    r->faces = faces;
    double tol = area_tolerance(m, s->vertex_state);
    for (size_t f = 0; f < faces; ++f) r->degenerate_faces += face_degenerate(m, f, tol);
    uf_init(s->face_parent, faces);
    uf_init(s->corner_parent, slots);
    bucket_half_edges(m, s);
    classify_edges(m, s, r);
    r->components = uf_roots(s->face_parent, faces);
    count_fans(m, slots, s, r);
    r->duplicate_faces = count_duplicates(m, s);
    r->euler = (int64_t)r->vertices - (int64_t)r->edges + (int64_t)r->faces;
    r->closed_manifold = r->boundary_edges == 0 && r->nonmanifold_edges == 0 &&
                         r->misoriented_edges == 0 && r->nonmanifold_vertices == 0 &&
                         r->degenerate_faces == 0 && r->duplicate_faces == 0;
}

xyl_result xyl_mesh_check(const xyl_mesh *mesh, const xyl_allocator *alloc,
                          xyl_mesh_report *report, xyl_diag *diag)
{
    if (!mesh || !report)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "mesh and report must not be NULL");
    xyl_result res = check_limits(mesh, diag);
    if (res == XYL_OK) res = xyl__mesh_validate(mesh, XYL__MESH_FACES, diag);
    if (res) return res;
    size_t faces = mesh->quad_count + mesh->triangle_count;
    size_t slots = 4 * mesh->quad_count + 3 * mesh->triangle_count;
    scratch s;
    if (!scratch_alloc(&s, mesh->vertex_count, faces, slots, alloc))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the mesh check");
    xyl_mesh_report r;
    fill_report(mesh, &s, &r);
    scratch_free(&s, alloc);
    *report = r;
    xyl__diag_ok(diag);
    return XYL_OK;
}
