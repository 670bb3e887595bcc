/* Leaves from a leaf mesh: a strict Wavefront OBJ reader (v and f records), the connected
 * components of its faces, and each component reduced to one quad as Zhang reduces a leaf: the
 * area-weighted least-squares plane, the long axis of the area in it from the stalk end to the
 * tip end, and the bounding rectangle along that axis.
 *
 * Lines, tokens and numbers are read with core's text_reader.h: no strtod, whose radix character
 * depends on the C locale. */
#include <float.h>
#include <stdio.h>
#include <string.h>

#include "foliage_internal.h"
#include "text_reader.h"

#define DEFAULT_PLANARITY 0.1
/* Characters of a token quoted in a message. */
#define SHOW_CHARS 20
/* Vertex and face indices are uint32_t; UINT32_MAX marks "none". */
#define MAX_VERTICES ((size_t)UINT32_MAX - 1)
#define NONE UINT32_MAX
/* A component whose area is below this fraction of its bounding box's squared diagonal has no
 * plane: its vertices are collinear or coincident. */
#define MIN_RELATIVE_AREA 1e-12
/* Two ends of a component closer than this fraction of its length to a rule's reference count
 * as tied, and the next rule decides. */
#define END_TIE 1e-6
/* A component whose faces' area vectors add up to less than this fraction of its area has no
 * winding to face by. */
#define MIN_RELATIVE_WINDING 1e-9
#define JACOBI_SWEEPS 32

/* ==== reader ================================================================================ */

typedef struct reader {
    xyl__text_reader txt;
    const xyl_allocator *alloc;
    double max_coordinate;
    xyl__dvec3 *v;
    size_t v_count, v_cap;
    uint32_t *corner;   /* the faces' vertex indices, face after face */
    size_t corner_count, corner_cap;
    size_t *face_start; /* face f's corners: [face_start[f], face_end(f)) */
    uint32_t *face_line;
    size_t face_count, face_cap, line_cap;
} reader;

static size_t face_end(const reader *r, size_t f)
{
    return f + 1 < r->face_count ? r->face_start[f + 1] : r->corner_count;
}

/* A record with too few fields: cut short by the end of the text, or malformed. */
static xyl_result missing(reader *r, const char *what)
{
    if (r->txt.open_end)
        return xyl__text_fail(&r->txt, XYL_ERR_TRUNCATED, xyl__to_u32(r->txt.len + 1),
                              "the text ends inside a record: %s expected", what);
    return xyl__text_fail(&r->txt, XYL_ERR_PARSE, xyl__to_u32(r->txt.len + 1),
                          "the line ends where %s was expected", what);
}

/* ---- numbers ------------------------------------------------------------------------------- */

/* A number as xyl__text_real reads it; beyond the double range +-DBL_MAX, which every limit
 * refuses. */
static xyl__num_status parse_real(const char *s, size_t n, double *out)
{
    xyl__num_status st = xyl__text_real(s, n, out);
    if (st == XYL__NUM_OK && isinf(*out)) *out = *out < 0 ? -DBL_MAX : DBL_MAX;
    return st;
}

/* ---- records ------------------------------------------------------------------------------- */

/* v x y z [w] or v x y z r g b [a]: every field a finite number, x y z within the limit. */
static xyl_result vertex_record(reader *r)
{
    static const char *const names[3] = {"x", "y", "z"};
    double c[3] = {0, 0, 0};
    int fields = 0;
    xyl__token t;
    char buf[32];
    while (xyl__text_next_token(&r->txt, &t)) {
        double v;
        xyl__num_status st = parse_real(t.s, t.n, &v);
        if (st == XYL__NUM_NON_FINITE)
            return xyl__text_fail(&r->txt, XYL_ERR_NON_FINITE, t.col,
                                  "vertex coordinate '%s' is not finite",
                                  xyl__text_show(&t, SHOW_CHARS, buf));
        if (st != XYL__NUM_OK)
            return xyl__text_fail(&r->txt, XYL_ERR_PARSE, t.col, "'%s' is not a number",
                                  xyl__text_show(&t, SHOW_CHARS, buf));
        if (fields == 7)
            return xyl__text_fail(&r->txt, XYL_ERR_PARSE, t.col,
                                  "a vertex has at most 7 numbers (x y z [w], or x y z r g b [a])");
        if (fields < 3) {
            if (!(fabs(v) <= r->max_coordinate))
                return xyl__text_fail(&r->txt, XYL_ERR_LIMIT_EXCEEDED, t.col,
                                      "vertex %s '%s' is beyond limits.max_coordinate (%g)",
                                      names[fields], xyl__text_show(&t, SHOW_CHARS, buf),
                                      r->max_coordinate);
            c[fields] = v;
        }
        ++fields;
    }
    if (fields < 3) return missing(r, names[fields]);
    if (fields == 5)
        return xyl__text_fail(&r->txt, XYL_ERR_PARSE, xyl__to_u32(r->txt.len + 1),
                              "a vertex with 5 numbers: x y z [w], or x y z r g b [a]");
    if (r->v_count == MAX_VERTICES)
        return xyl__text_fail(&r->txt, XYL_ERR_LIMIT_EXCEEDED, 1, "more than 2^32 - 2 vertices");
    void *p = r->v;
    if (!xyl__grow(r->alloc, &p, &r->v_cap, r->v_count, r->v_count + 1, sizeof *r->v))
        return xyl__text_fail(&r->txt, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for %zu vertices",
                              r->v_count + 1);
    r->v = p;
    r->v[r->v_count++] = xyl__d3(c[0], c[1], c[2]);
    return XYL_OK;
}

/* One face corner, i, i/t, i//n or i/t/n, to a 0-based vertex index. */
static xyl_result corner_field(reader *r, const xyl__token *t, uint32_t *vertex)
{
    char buf[32];
    const char *slash1 = memchr(t->s, '/', t->n);
    size_t in = slash1 ? (size_t)(slash1 - t->s) : t->n;
    int64_t i = 0, other;
    if (!xyl__text_i64(t->s, in, &i) || i == 0)
        return xyl__text_fail(
            &r->txt, XYL_ERR_PARSE, t->col, "face corner '%s' has no vertex index%s",
            xyl__text_show(t, SHOW_CHARS, buf), i == 0 && in > 0 ? " (indices count from 1)" : "");
    if (slash1) {
        const char *rest = slash1 + 1, *end = t->s + t->n;
        const char *slash2 = memchr(rest, '/', (size_t)(end - rest));
        size_t tn = slash2 ? (size_t)(slash2 - rest) : (size_t)(end - rest);
        bool ok = slash2 ? (tn == 0 || (xyl__text_i64(rest, tn, &other) && other != 0))
                         : xyl__text_i64(rest, tn, &other) && other != 0;
        if (ok && slash2) {
            size_t nn = (size_t)(end - slash2 - 1);
            ok = xyl__text_i64(slash2 + 1, nn, &other) && other != 0;
        }
        if (!ok)
            return xyl__text_fail(
                &r->txt, XYL_ERR_PARSE, t->col,
                "face corner '%s' is not i, i/t, i//n or i/t/n (indices non-zero)",
                xyl__text_show(t, SHOW_CHARS, buf));
    }
    int64_t n = (int64_t)r->v_count;
    int64_t at = i > 0 ? i - 1 : n + i;
    if (at < 0 || at >= n)
        return xyl__text_fail(
            &r->txt, XYL_ERR_PARSE, t->col,
            "face corner '%s' names a vertex that does not exist (%zu defined so far)",
            xyl__text_show(t, SHOW_CHARS, buf), r->v_count);
    *vertex = (uint32_t)at;
    return XYL_OK;
}

static xyl_result face_record(reader *r)
{
    size_t first = r->corner_count;
    xyl__token t;
    void *p;
    while (xyl__text_next_token(&r->txt, &t)) {
        uint32_t vertex = 0;
        xyl_result res = corner_field(r, &t, &vertex);
        if (res != XYL_OK) return res;
        p = r->corner;
        if (!xyl__grow(r->alloc, &p, &r->corner_cap, r->corner_count, r->corner_count + 1,
                       sizeof *r->corner))
            return xyl__text_fail(&r->txt, XYL_ERR_OUT_OF_MEMORY, 0,
                                  "out of memory for the face corners");
        r->corner = p;
        r->corner[r->corner_count++] = vertex;
    }
    if (r->corner_count - first < 3) return missing(r, "a face corner (a face has 3 or more)");
    if (r->face_count == MAX_VERTICES)
        return xyl__text_fail(&r->txt, XYL_ERR_LIMIT_EXCEEDED, 1, "more than 2^32 - 2 faces");
    p = r->face_start;
    if (!xyl__grow(r->alloc, &p, &r->face_cap, r->face_count, r->face_count + 1,
                   sizeof *r->face_start))
        return xyl__text_fail(&r->txt, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for the faces");
    r->face_start = p;
    p = r->face_line;
    if (!xyl__grow(r->alloc, &p, &r->line_cap, r->face_count, r->face_count + 1,
                   sizeof *r->face_line))
        return xyl__text_fail(&r->txt, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for the faces");
    r->face_line = p;
    r->face_start[r->face_count] = first;
    r->face_line[r->face_count++] = r->txt.line_no;
    return XYL_OK;
}

/* Records read for what they say and skipped: texture coordinates, normals, names, groups,
 * smoothing, materials, polylines, points. */
static bool skipped(const xyl__token *t)
{
    static const char *const words[] = {"vt", "vn", "vp", "o", "g", "s", "l", "p", "usemtl",
                                        "mtllib"};
    for (size_t k = 0; k < sizeof words / sizeof words[0]; ++k)
        if (xyl__token_is(t, words[k])) return true;
    return false;
}

static xyl_result read_obj(reader *r)
{
    xyl__token kw;
    char buf[32];
    while (xyl__text_next_line(&r->txt)) {
        const char *nul = memchr(r->txt.line, '\0', r->txt.len);
        if (nul)
            return xyl__text_fail(&r->txt, XYL_ERR_PARSE,
                                  xyl__to_u32((size_t)(nul - r->txt.line) + 1),
                                  "a NUL byte; OBJ files are text");
        if (!xyl__text_next_token(&r->txt, &kw)) continue;
        xyl_result res = XYL_OK;
        if (xyl__token_is(&kw, "v"))
            res = vertex_record(r);
        else if (xyl__token_is(&kw, "f"))
            res = face_record(r);
        else if (!skipped(&kw))
            res = xyl__text_fail(&r->txt, XYL_ERR_PARSE, kw.col, "unknown record '%s'",
                                 xyl__text_show(&kw, SHOW_CHARS, buf));
        if (res != XYL_OK) return res;
    }
    return XYL_OK;
}

static void reader_free(reader *r)
{
    xyl__free(r->alloc, r->v);
    xyl__free(r->alloc, r->corner);
    xyl__free(r->alloc, r->face_start);
    xyl__free(r->alloc, r->face_line);
}

/* ==== components ============================================================================ */

/* The root of vertex x's set, halving the path on the way. */
static uint32_t find_root(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/* The faces grouped by component, components in the order of their first faces. */
typedef struct components {
    size_t count;
    size_t *start;   /* count + 1: component k's faces are order[start[k] .. start[k + 1]) */
    uint32_t *order; /* face indices; each component's in file order */
} components;

static xyl_result find_components(const reader *r, components *c, xyl_diag *diag)
{
    const xyl_allocator *a = r->alloc;
    uint32_t *parent = xyl__alloc_array(a, r->v_count, sizeof *parent);
    uint32_t *face_comp = xyl__alloc_array(a, r->face_count, sizeof *face_comp);
    c->order = xyl__alloc_array(a, r->face_count, sizeof *c->order);
    c->start = NULL;
    if (!parent || !face_comp || !c->order) {
        xyl__free(a, parent);
        xyl__free(a, face_comp);
        xyl__free(a, c->order);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the components");
    }
    for (size_t i = 0; i < r->v_count; ++i) parent[i] = (uint32_t)i;
    for (size_t f = 0; f < r->face_count; ++f) {
        uint32_t root = find_root(parent, r->corner[r->face_start[f]]);
        for (size_t k = r->face_start[f] + 1; k < face_end(r, f); ++k) {
            uint32_t other = find_root(parent, r->corner[k]);
            /* the lower root stays: a deterministic forest whatever the path halving did */
            if (other < root) parent[root] = other, root = other;
            else parent[other] = root;
        }
    }
    for (size_t f = 0; f < r->face_count; ++f)
        face_comp[f] = find_root(parent, r->corner[r->face_start[f]]);
    /* the forest has done its work: its array now numbers the roots in first-face order */
    size_t count = 0;
    for (size_t i = 0; i < r->v_count; ++i) parent[i] = NONE;
    for (size_t f = 0; f < r->face_count; ++f) {
        uint32_t root = face_comp[f];
        if (parent[root] == NONE) parent[root] = (uint32_t)count++;
        face_comp[f] = parent[root];
    }
    xyl__free(a, parent);
    c->start = xyl__calloc(a, count + 1, sizeof *c->start);
    if (!c->start) {
        xyl__free(a, face_comp);
        xyl__free(a, c->order);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the components");
    }
    for (size_t f = 0; f < r->face_count; ++f) c->start[face_comp[f] + 1]++;
    for (size_t k = 0; k < count; ++k) c->start[k + 1] += c->start[k];
    for (size_t f = 0; f < r->face_count; ++f) c->order[c->start[face_comp[f]]++] = (uint32_t)f;
    for (size_t k = count; k > 0; --k) c->start[k] = c->start[k - 1];
    c->start[0] = 0;
    c->count = count;
    xyl__free(a, face_comp);
    return XYL_OK;
}

/* ==== the reduction ========================================================================= */

/* Eigenvalues w and unit eigenvectors (columns of v) of the symmetric 3x3 m, by cyclic Jacobi
 * rotations: each zeroes one off-diagonal entry with the rotation angle's tangent taken as the
 * smaller root, so no entry grows and the result is orthonormal to rounding. */
static void jacobi3(double m[3][3], double w[3], double v[3][3])
{
    double a[3][3];
    memcpy(a, m, sizeof a);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) v[i][j] = i == j;
    for (int sweep = 0; sweep < JACOBI_SWEEPS; ++sweep) {
        double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (!(off > 1e-32 * diag)) break;
        for (int p = 0; p < 2; ++p) {
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = fabs(theta) > 1e150 ? 0.5 / fabs(theta) /* theta^2 would overflow */
                                                : 1.0 / (fabs(theta) + sqrt(theta * theta + 1.0));
                if (theta < 0.0) t = -t;
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; ++k) { /* a = a J, then J^T a */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                a[p][q] = a[q][p] = 0.0;
                for (int k = 0; k < 3; ++k) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (int i = 0; i < 3; ++i) w[i] = a[i][i];
}

static xyl__dvec3 column(double v[3][3], int j)
{
    return xyl__d3(v[0][j], v[1][j], v[2][j]);
}

/* What every component's reduction shares. */
typedef struct reduce_ctx {
    const reader *r;
    const components *c;
    double planarity;
    bool has_ref;       /* the stalk end is the end nearer ref, unless tied */
    bool ref_is_line;   /* nearer the vertical line through ref, rather than ref itself */
    xyl__dvec3 ref;
    float uv[4];
    const xyl__foliage_limits *limits;
    xyl_diag *diag;
} reduce_ctx;

/* Calls fn(ctx, a, b, c) for every triangle of component k's faces (fans), in file order. */
typedef void (*triangle_fn)(void *ctx, xyl__dvec3 a, xyl__dvec3 b, xyl__dvec3 c);

static void each_triangle(const reader *r, const components *cs, size_t k, xyl__dvec3 origin,
                          double scale, triangle_fn fn, void *ctx)
{
    for (size_t i = cs->start[k]; i < cs->start[k + 1]; ++i) {
        size_t f = cs->order[i], s = r->face_start[f], e = face_end(r, f);
        xyl__dvec3 p0 = xyl__d3_scale(xyl__d3_sub(r->v[r->corner[s]], origin), scale);
        for (size_t j = s + 1; j + 1 < e; ++j) {
            xyl__dvec3 p1 = xyl__d3_scale(xyl__d3_sub(r->v[r->corner[j]], origin), scale);
            xyl__dvec3 p2 = xyl__d3_scale(xyl__d3_sub(r->v[r->corner[j + 1]], origin), scale);
            fn(ctx, p0, p1, p2);
        }
    }
}

typedef struct moments {
    double area;
    xyl__dvec3 first;   /* the integral of x over the area */
    xyl__dvec3 winding; /* the faces' area vectors, summed */
    xyl__dvec3 centre;  /* for the second pass */
    double second[3][3]; /* the integral of (x - centre)(x - centre)^T over the area */
} moments;

static void add_first(void *ctx, xyl__dvec3 a, xyl__dvec3 b, xyl__dvec3 c)
{
    moments *m = ctx;
    xyl__dvec3 n = xyl__d3_cross(xyl__d3_sub(b, a), xyl__d3_sub(c, a));
    double area = 0.5 * xyl__d3_len(n);
    m->area += area;
    m->first = xyl__d3_add(m->first, xyl__d3_scale(xyl__d3_add(a, xyl__d3_add(b, c)), area / 3.0));
    m->winding = xyl__d3_add(m->winding, xyl__d3_scale(n, 0.5));
}

/* Over a triangle of area A, the integral of x x^T is A / 12 (sum of p p^T over its corners
 * + s s^T, s the corners' sum). */
static void add_second(void *ctx, xyl__dvec3 a, xyl__dvec3 b, xyl__dvec3 c)
{
    moments *m = ctx;
    double area = 0.5 * xyl__d3_len(xyl__d3_cross(xyl__d3_sub(b, a), xyl__d3_sub(c, a)));
    xyl__dvec3 p[3] = {xyl__d3_sub(a, m->centre), xyl__d3_sub(b, m->centre),
                       xyl__d3_sub(c, m->centre)};
    xyl__dvec3 s = xyl__d3_add(p[0], xyl__d3_add(p[1], p[2]));
    double sv[3] = {s.x, s.y, s.z};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            double sum = sv[i] * sv[j];
            for (int k = 0; k < 3; ++k) {
                double pk[3] = {p[k].x, p[k].y, p[k].z};
                sum += pk[i] * pk[j];
            }
            m->second[i][j] += area / 12.0 * sum;
        }
    }
}

/* +1 or -1: which way a unit vector is turned for a fixed sign, its largest component
 * positive (the first of equal ones). */
static double canonical_sign(xyl__dvec3 d)
{
    double c[3] = {d.x, d.y, d.z};
    int best = 0;
    for (int k = 1; k < 3; ++k)
        if (fabs(c[k]) > fabs(c[best])) best = k;
    return c[best] < 0.0 ? -1.0 : 1.0;
}

/* -1 when the stalk is at the end lo (the axis runs along +d), +1 at hi, 0 when x is tied. */
static int nearer_end(double lo_distance, double hi_distance, double tie)
{
    if (lo_distance < hi_distance - tie) return -1;
    if (hi_distance < lo_distance - tie) return 1;
    return 0;
}

static xyl_result reduce_fail(const reduce_ctx *x, size_t k, xyl_result code, const char *fmt,
                              double a, double b)
{
    uint32_t line = x->r->face_line[x->c->order[x->c->start[k]]];
    char msg[XYL_DIAG_MESSAGE_SIZE];
    snprintf(msg, sizeof msg, fmt, a, b);
    return xyl__fail(x->diag, code, line, 0, (int64_t)k, "component %zu (faces from line %u): %s",
                     k, (unsigned)line, msg);
}

static xyl_result reduce(const reduce_ctx *x, size_t k, xyl_leaf *out)
{
    const reader *r = x->r;
    const components *cs = x->c;
    /* local coordinates: the component's box corner at the origin, its diagonal 1 */
    xyl__dvec3 lo = r->v[r->corner[r->face_start[cs->order[cs->start[k]]]]], hi = lo;
    for (size_t i = cs->start[k]; i < cs->start[k + 1]; ++i) {
        size_t f = cs->order[i];
        for (size_t j = r->face_start[f]; j < face_end(r, f); ++j) {
            xyl__dvec3 p = r->v[r->corner[j]];
            lo = xyl__d3(fmin(lo.x, p.x), fmin(lo.y, p.y), fmin(lo.z, p.z));
            hi = xyl__d3(fmax(hi.x, p.x), fmax(hi.y, p.y), fmax(hi.z, p.z));
        }
    }
    double extent = xyl__d3_len(xyl__d3_sub(hi, lo));
    moments m;
    memset(&m, 0, sizeof m);
    if (extent > 0.0) each_triangle(r, cs, k, lo, 1.0 / extent, add_first, &m);
    if (!(m.area > MIN_RELATIVE_AREA))
        return reduce_fail(x, k, XYL_ERR_INVALID_ARGUMENT,
                           "its area is %g of its size squared: its vertices are collinear or "
                           "coincident (size %g)", m.area, extent);
    m.centre = xyl__d3_scale(m.first, 1.0 / m.area);
    each_triangle(r, cs, k, lo, 1.0 / extent, add_second, &m);
    double w[3], v[3][3];
    jacobi3(m.second, w, v);
    int small = 0, large = 0;
    for (int i = 1; i < 3; ++i) {
        if (w[i] < w[small]) small = i;
        if (w[i] > w[large]) large = i;
    }
    if (large == small) large = (small + 1) % 3;
    xyl__dvec3 n = column(v, small);
    double wind = xyl__d3_dot(n, m.winding);
    if (fabs(wind) > MIN_RELATIVE_WINDING * m.area) n = xyl__d3_scale(n, wind < 0.0 ? -1.0 : 1.0);
    else n = xyl__d3_scale(n, canonical_sign(n));
    xyl__dvec3 d = column(v, large);
    d = xyl__d3_normalize_or(xyl__d3_sub(d, xyl__d3_scale(n, xyl__d3_dot(d, n))),
                             xyl__d3_any_orthogonal(n));
    d = xyl__d3_scale(d, canonical_sign(d));
    xyl__dvec3 side = xyl__d3_cross(d, n);
    /* the projected box, in local units, about the centre */
    double t0 = INFINITY, t1 = -INFINITY, s0 = INFINITY, s1 = -INFINITY, off = 0.0;
    for (size_t i = cs->start[k]; i < cs->start[k + 1]; ++i) {
        size_t f = cs->order[i];
        for (size_t j = r->face_start[f]; j < face_end(r, f); ++j) {
            xyl__dvec3 p = xyl__d3_sub(xyl__d3_scale(xyl__d3_sub(r->v[r->corner[j]], lo),
                                                     1.0 / extent), m.centre);
            double t = xyl__d3_dot(p, d), s = xyl__d3_dot(p, side);
            t0 = fmin(t0, t), t1 = fmax(t1, t), s0 = fmin(s0, s), s1 = fmax(s1, s);
            off = fmax(off, fabs(xyl__d3_dot(p, n)));
        }
    }
    double length = fmax(t1 - t0, s1 - s0);
    if (!(off <= x->planarity * length))
        return reduce_fail(x, k, XYL_ERR_INVALID_ARGUMENT,
                           "not flat: a vertex lies %g of its length from its plane, beyond the "
                           "planarity %g", off / length, x->planarity);
    /* back to world units */
    xyl__dvec3 centre = xyl__d3_add(lo, xyl__d3_scale(m.centre, extent));
    xyl__dvec3 mid = xyl__d3_add(centre, xyl__d3_add(xyl__d3_scale(d, 0.5 * (t0 + t1) * extent),
                                                     xyl__d3_scale(side, 0.5 * (s0 + s1) * extent)));
    double half_t = 0.5 * (t1 - t0) * extent, half_s = 0.5 * (s1 - s0) * extent;
    xyl__dvec3 end_lo = xyl__d3_sub(mid, xyl__d3_scale(d, half_t));
    xyl__dvec3 end_hi = xyl__d3_add(mid, xyl__d3_scale(d, half_t));
    double tie = END_TIE * 2.0 * half_t;
    int stalk = 0;
    if (x->has_ref) {
        xyl__dvec3 to_lo = xyl__d3_sub(end_lo, x->ref), to_hi = xyl__d3_sub(end_hi, x->ref);
        if (x->ref_is_line) to_lo.y = to_hi.y = 0.0;
        stalk = nearer_end(xyl__d3_len(to_lo), xyl__d3_len(to_hi), tie);
    }
    if (stalk == 0) stalk = nearer_end(end_lo.y, end_hi.y, tie);
    if (stalk == 0) stalk = nearer_end(xyl__d3_len(end_lo), xyl__d3_len(end_hi), tie);
    if (stalk > 0) d = xyl__d3_scale(d, -1.0);
    side = xyl__d3_cross(d, n);
    xyl_leaf l;
    memset(&l, 0, sizeof l);
    l.center = xyl__to_f3(mid);
    l.normal = xyl__to_f3(n);
    l.axis = xyl__to_f3(xyl__d3_scale(d, half_t));
    l.side = xyl__to_f3(xyl__d3_scale(side, half_s));
    memcpy(l.uv, x->uv, sizeof l.uv);
    l.count = 1;
    l.node = -1;
    xyl_result res = xyl__leaf_check(&l, k, x->limits, x->diag);
    if (res != XYL_OK) {
        if (x->diag) x->diag->line = r->face_line[cs->order[cs->start[k]]];
        return res;
    }
    *out = l;
    return XYL_OK;
}

/* ==== the call ============================================================================== */

static xyl_result resolve(const xyl_leaf_mesh_desc *in, reduce_ctx *x, xyl__foliage_limits *lim,
                          xyl_diag *diag)
{
    xyl_result res = xyl__foliage_limits_resolve(&in->limits, lim, diag);
    if (res != XYL_OK) return res;
    const float f[8] = {in->planarity, in->stalk_point.x, in->stalk_point.y, in->stalk_point.z,
                        in->uv[0], in->uv[1], in->uv[2], in->uv[3]};
    for (int k = 0; k < 8; ++k)
        if (!isfinite(f[k]))
            return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "a leaf mesh option is NaN or infinite");
    if (in->planarity < 0.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "planarity is %g; it must be >= 0 (0: 0.1)", (double)in->planarity);
    for (int k = 0; k < 4; ++k)
        if (in->uv[k] < 0.0f || in->uv[k] > 1.0f)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                             "leaf mesh: texture coordinate %g outside [0, 1]", (double)in->uv[k]);
    x->planarity = in->planarity > 0.0f ? (double)in->planarity : DEFAULT_PLANARITY;
    memcpy(x->uv, in->uv, sizeof x->uv);
    if (x->uv[0] == 0.0f && x->uv[1] == 0.0f && x->uv[2] == 0.0f && x->uv[3] == 0.0f)
        x->uv[2] = x->uv[3] = 1.0f;
    x->has_ref = in->has_stalk_point;
    x->ref = xyl__from_f3(in->stalk_point);
    return XYL_OK;
}

static void add_centroid(void *ctx, xyl__dvec3 a, xyl__dvec3 b, xyl__dvec3 c)
{
    moments *m = ctx;
    double area = 0.5 * xyl__d3_len(xyl__d3_cross(xyl__d3_sub(b, a), xyl__d3_sub(c, a)));
    m->area += area;
    m->first = xyl__d3_add(m->first, xyl__d3_scale(xyl__d3_add(a, xyl__d3_add(b, c)), area / 3.0));
}

/* The area-weighted centroid of every component: with several leaves and no stalk point, the
 * stalk end is the end nearer the vertical line through it (foliage's default trunk axis). */
static xyl__dvec3 mesh_centroid(const reader *r, const components *cs)
{
    moments m;
    memset(&m, 0, sizeof m);
    for (size_t k = 0; k < cs->count; ++k)
        each_triangle(r, cs, k, xyl__d3(0, 0, 0), 1.0, add_centroid, &m);
    return m.area > 0.0 ? xyl__d3_scale(m.first, 1.0 / m.area) : xyl__d3(0, 0, 0);
}

static xyl_result reduce_all(reduce_ctx *x, xyl_leaf *leaves, size_t capacity, size_t *count)
{
    const reader *r = x->r;
    components cs = {0, NULL, NULL};
    xyl_result res = find_components(r, &cs, x->diag);
    if (res != XYL_OK) return res;
    x->c = &cs;
    xyl_leaf *tmp = NULL;
    if ((uint64_t)cs.count > x->limits->max_leaves) {
        size_t k = (size_t)x->limits->max_leaves;
        uint32_t line = r->face_line[cs.order[cs.start[k]]];
        res = xyl__fail(x->diag, XYL_ERR_LIMIT_EXCEEDED, line, 0, (int64_t)k,
                        "component %zu (faces from line %u) is one more than limits.max_leaves "
                        "(%llu)", k, (unsigned)line, (unsigned long long)x->limits->max_leaves);
    } else if (leaves && capacity < cs.count) {
        res = xyl__fail(x->diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                        "capacity %zu is less than the %zu leaves", capacity, cs.count);
    } else if (!x->has_ref && cs.count > 1) {
        x->has_ref = x->ref_is_line = true;
        x->ref = mesh_centroid(r, &cs);
    }
    if (res == XYL_OK && leaves) {
        tmp = xyl__alloc_array(r->alloc, cs.count, sizeof *tmp);
        if (!tmp) res = xyl__fail(x->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the leaves");
    }
    for (size_t k = 0; res == XYL_OK && k < cs.count; ++k) {
        xyl_leaf l;
        res = reduce(x, k, &l);
        if (res == XYL_OK && tmp) tmp[k] = l;
    }
    if (res == XYL_OK && leaves && cs.count) memcpy(leaves, tmp, cs.count * sizeof *tmp);
    if (res == XYL_OK) *count = cs.count;
    xyl__free(r->alloc, tmp);
    xyl__free(r->alloc, cs.start);
    xyl__free(r->alloc, cs.order);
    return res;
}

xyl_result xyl_foliage_leaves_from_obj(const char *text, size_t size,
                                       const xyl_leaf_mesh_desc *desc, xyl_leaf *leaves,
                                       size_t capacity, size_t *count, xyl_diag *diag)
{
    if ((!text && size) || !count)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "text (with a size) and count must not be NULL");
    xyl_leaf_mesh_desc zero;
    memset(&zero, 0, sizeof zero);
    if (!desc) desc = &zero;
    reduce_ctx x;
    memset(&x, 0, sizeof x);
    xyl__foliage_limits lim;
    xyl_result res = resolve(desc, &x, &lim, diag);
    if (res != XYL_OK) return res;
    reader r;
    memset(&r, 0, sizeof r);
    xyl__text_init(&r.txt, text, size, diag);
    r.alloc = &desc->alloc;
    r.max_coordinate = lim.max_coordinate;
    res = read_obj(&r);
    x.r = &r;
    x.limits = &lim;
    x.diag = diag;
    size_t n = 0;
    if (res == XYL_OK) res = reduce_all(&x, leaves, capacity, &n);
    reader_free(&r);
    if (res != XYL_OK) return res;
    *count = n;
    xyl__diag_ok(diag);
    return XYL_OK;
}

/* ==== a template leaf as the shape of every attachment ====================================== */

xyl_result xyl_leaf_shape_from_template(const xyl_leaf *template_leaf, const xyl_vec3 *stalk_point,
                                        xyl_leaf_shape *shape, xyl_diag *diag)
{
    if (!template_leaf || !shape)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "template_leaf and shape must not be NULL");
    xyl__foliage_limits lim;
    xyl_result res = xyl__foliage_limits_resolve(NULL, &lim, diag);
    if (res == XYL_OK) res = xyl__leaf_check(template_leaf, 0, &lim, diag);
    if (res != XYL_OK) return res;
    xyl_vec3 origin = {0, 0, 0};
    if (!stalk_point) stalk_point = &origin;
    if (!isfinite(stalk_point->x) || !isfinite(stalk_point->y) || !isfinite(stalk_point->z))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "the stalk point is NaN or infinite");
    xyl_leaf t = xyl__leaf_tidy(template_leaf);
    xyl__dvec3 axis = xyl__from_f3(t.axis);
    double half = xyl__d3_len(axis);
    xyl__dvec3 stalk_end = xyl__d3_sub(xyl__from_f3(t.center), axis);
    /* along the axis, from the stalk point to the stalk end, in lengths */
    double stalk = xyl__d3_dot(xyl__d3_sub(stalk_end, xyl__from_f3(*stalk_point)), axis) /
                   (half * 2.0 * half);
    if (!(stalk >= -END_TIE))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the stalk point lies %g of the leaf's length past its stalk end, towards "
                         "its tip; a stalk cannot be negative", -stalk);
    float aspect = (float)(xyl__d3_len(xyl__from_f3(t.side)) / half);
    float stalk_f = (float)fmax(stalk, 0.0);
    /* an aspect of 0 would read as the default, one of inf as an error of the shape's user */
    if (!(aspect > 0.0f) || !isfinite(aspect) || !isfinite(stalk_f))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the template's aspect (%g) or stalk (%g) is not a positive float",
                         (double)aspect, stalk);
    shape->aspect = aspect;
    shape->stalk = stalk_f;
    memcpy(shape->uv, t.uv, sizeof shape->uv);
    xyl__diag_ok(diag);
    return XYL_OK;
}
