/* Murray branching angles (docs/turtle.md, "Murray mode"): at a fork the children balance like
 * forces of magnitude w = r^2 against the parent, w0 d0 = sum wi di. Each child's angle comes
 * from the triangle of forces between it and a virtual branch carrying all its siblings; its
 * azimuth comes from the grammar. Rotations are found from the original geometry, then one
 * walk in node order (parents first) composes them, so the whole pass is O(nodes + leaves). */

#include "turtle_internal.h"

typedef struct mat3 {
    double m[9]; /* row-major */
} mat3;

/* Per child of the fork being solved. */
typedef struct kid {
    uint32_t node;
    double pw;        /* (r / scale)^n */
    double w;         /* (r / scale)^2 */
    double c, s;      /* cos and sin of the balanced angle to d0 */
    xyl__dvec3 dir;   /* original unit direction from the fork */
    xyl__dvec3 az;    /* unit azimuth, orthogonal to d0 */
    bool has_az;
} kid;

typedef struct murray {
    lsys_tnode *nodes;
    size_t count;
    const double *radius;
    double exponent, cos_lo, cos_hi; /* cos(max_angle), cos(min_angle) */
    uint32_t *first, *kids;          /* children of node i: kids[first[i] .. first[i + 1]) */
    mat3 *rot;
    kid *scratch;
    double *angles;                  /* scratch: given azimuths as angles about d0 */
} murray;

/* ---- 3x3 rotations ------------------------------------------------------------------------- */

static mat3 mat3_identity(void)
{
    mat3 r = {{1, 0, 0, 0, 1, 0, 0, 0, 1}};
    return r;
}

static mat3 mat3_mul(const mat3 *a, const mat3 *b)
{
    mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[3 * i + j] = a->m[3 * i] * b->m[j] + a->m[3 * i + 1] * b->m[3 + j] +
                             a->m[3 * i + 2] * b->m[6 + j];
    return r;
}

static xyl__dvec3 mat3_apply(const mat3 *a, xyl__dvec3 v)
{
    const double *m = a->m;
    return xyl__d3(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
                   m[6] * v.x + m[7] * v.y + m[8] * v.z);
}

/* R = c I + s [k]x + (1 - c) k k^T for a unit axis k. */
static mat3 axis_rotation(xyl__dvec3 k, double c, double s, double omc)
{
    mat3 r = {{c + omc * k.x * k.x, omc * k.x * k.y - s * k.z, omc * k.x * k.z + s * k.y,
               omc * k.y * k.x + s * k.z, c + omc * k.y * k.y, omc * k.y * k.z - s * k.x,
               omc * k.z * k.x - s * k.y, omc * k.z * k.y + s * k.x, c + omc * k.z * k.z}};
    return r;
}

/* The smallest rotation taking unit u to unit v; a half turn about some axis orthogonal to u
 * when they are opposite. */
static mat3 rotation_between(xyl__dvec3 u, xyl__dvec3 v)
{
    double c = xyl__d3_dot(u, v);
    xyl__dvec3 k = xyl__d3_cross(u, v);
    double s2 = xyl__d3_dot(k, k);
    if (!(s2 > XYL__EPS_NORMALIZE)) {
        if (c > 0.0) return mat3_identity();
        return axis_rotation(xyl__d3_any_orthogonal(u), -1.0, 0.0, 2.0);
    }
    double s = sqrt(s2);
    double omc = c > 0.0 ? s2 / (1.0 + c) : 1.0 - c; /* 1 - cos without cancellation */
    return axis_rotation(xyl__d3_scale(k, 1.0 / s), c, s, omc);
}

/* ---- one fork ------------------------------------------------------------------------------ */

static xyl__dvec3 unit_from(const murray *m, uint32_t a, uint32_t b, xyl__dvec3 fallback)
{
    return xyl__d3_normalize_or(xyl__d3_sub(m->nodes[b].pos, m->nodes[a].pos), fallback);
}

static xyl__dvec3 incoming(const murray *m, uint32_t f)
{
    xyl__dvec3 up = xyl__d3(0, 1, 0); /* a root fork: the turtle's initial heading */
    int32_t p = m->nodes[f].parent;
    return p < 0 ? up : unit_from(m, (uint32_t)p, f, up);
}

/* Loads the children, weights normalised by the largest radius at the fork (the angle formula
 * is scale-free; this keeps r^n within range for n up to 8). Returns the parent's weight. */
static double load_kids(const murray *m, uint32_t f, kid *kv, uint32_t k, xyl__dvec3 d0)
{
    double scale = m->radius[f];
    for (uint32_t j = 0; j < k; ++j) {
        double r = m->radius[m->kids[m->first[f] + j]];
        if (r > scale) scale = r;
    }
    for (uint32_t j = 0; j < k; ++j) {
        kid *c = &kv[j];
        c->node = m->kids[m->first[f] + j];
        double rho = m->radius[c->node] / scale;
        c->pw = pow(rho, m->exponent);
        c->w = rho * rho;
        c->dir = unit_from(m, f, c->node, d0);
    }
    double rho0 = m->radius[f] / scale;
    return rho0 * rho0;
}

/* Clamps c to [lo, hi]; NaN (a degenerate triangle of underflowed weights) counts as parallel. */
static bool clamp_cos(double *c, double lo, double hi)
{
    if (*c >= lo && *c <= hi) return false;
    *c = *c < lo ? lo : hi;
    return true;
}

/* cos(theta_i) = (w0^2 + wi^2 - wrest_i^2) / (2 w0 wi), wrest_i = (sum_{j != i} pw_j)^(2/n).
 * The sum over the siblings uses prefix and suffix sums, never total - own. */
static bool solve_angles(const murray *m, kid *kv, uint32_t k, double w0)
{
    double suffix = 0.0, prefix = 0.0;
    for (uint32_t j = k; j-- > 0;) {
        kv[j].c = suffix;
        suffix += kv[j].pw;
    }
    bool clamped = false;
    for (uint32_t j = 0; j < k; ++j) {
        double rest = prefix + kv[j].c;
        prefix += kv[j].pw;
        double wr = pow(rest, 2.0 / m->exponent);
        double c = (w0 * w0 + kv[j].w * kv[j].w - wr * wr) / (2.0 * w0 * kv[j].w);
        clamped |= clamp_cos(&c, m->cos_lo, m->cos_hi);
        kv[j].c = c;
        kv[j].s = sqrt(fmax(0.0, 1.0 - c * c));
    }
    return clamped;
}

/* The child that continues the branch: largest float radius, first on ties, exactly as
 * xyl__skeleton_adopt decides. */
static uint32_t main_kid(const murray *m, const kid *kv, uint32_t k)
{
    uint32_t best = 0;
    for (uint32_t j = 1; j < k; ++j)
        if ((float)m->radius[kv[j].node] > (float)m->radius[kv[best].node]) best = j;
    return best;
}

/* An orthonormal basis (e1, e2) of the plane orthogonal to d0, for azimuth angles. */
typedef struct plane {
    xyl__dvec3 e1, e2;
} plane;

static plane plane_of(xyl__dvec3 d0)
{
    plane p;
    p.e1 = xyl__d3_any_orthogonal(d0);
    p.e2 = xyl__d3_cross(d0, p.e1);
    return p;
}

static double angle_of(const plane *p, xyl__dvec3 az)
{
    return atan2(xyl__d3_dot(az, p->e2), xyl__d3_dot(az, p->e1));
}

static xyl__dvec3 azimuth_at(const plane *p, double phi)
{
    return xyl__d3_add(xyl__d3_scale(p->e1, cos(phi)), xyl__d3_scale(p->e2, sin(phi)));
}

/* Ascending, -0 before +0: xyl__sort is not stable, so equal angles must be the same bits. */
static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    int order = (x > y) - (x < y);
    return order ? order : (signbit(y) != 0) - (signbit(x) != 0);
}

/* The widest empty sector between the sorted angles a[0 .. n): its start and width. With no
 * angle the whole circle, from e1. */
static double widest_gap(const double *a, uint32_t n, double *start)
{
    *start = n ? a[n - 1] : 0.0;
    double best = n ? a[0] + 2.0 * XYL__PI - a[n - 1] : 2.0 * XYL__PI;
    for (uint32_t j = 1; j < n; ++j) {
        if (a[j] - a[j - 1] > best) {
            best = a[j] - a[j - 1];
            *start = a[j - 1];
        }
    }
    return best;
}

/* Each child's azimuth as the grammar drew it. Children drawn along d0 have none; they are
 * spread evenly over the widest empty sector between the others (for two children: opposite
 * the other one, keeping a planar fork planar). */
static void grammar_azimuths(const murray *m, kid *kv, uint32_t k, xyl__dvec3 d0)
{
    plane p = plane_of(d0);
    uint32_t given = 0, missing = 0;
    for (uint32_t j = 0; j < k; ++j) {
        double along = xyl__d3_dot(kv[j].dir, d0);
        kv[j].has_az = 1.0 - fabs(along) >= XYL__EPS_COLLINEAR;
        if (!kv[j].has_az) {
            ++missing;
            continue;
        }
        kv[j].az = xyl__d3_normalize_or(xyl__d3_sub(kv[j].dir, xyl__d3_scale(d0, along)), p.e1);
        m->angles[given++] = angle_of(&p, kv[j].az);
    }
    if (missing == 0) return;
    xyl__sort(m->angles, given, sizeof *m->angles, cmp_double);
    double start, width = widest_gap(m->angles, given, &start);
    double denom = given ? (double)missing + 1.0 : (double)missing;
    double offset = given ? 1.0 : 0.0;
    for (uint32_t j = 0, placed = 0; j < k; ++j) {
        if (kv[j].has_az) continue;
        double t = ((double)placed++ + offset) / denom;
        kv[j].az = azimuth_at(&p, start + width * t);
    }
}

/* The continuing child leans against the laterals' sideways pull, so that for two children
 * both lie in one plane on opposite sides of d0 and the forces balance. */
static void balance_main(kid *kv, uint32_t k, uint32_t main)
{
    xyl__dvec3 pull = xyl__d3(0, 0, 0);
    double total = 0.0;
    for (uint32_t j = 0; j < k; ++j) {
        if (j == main) continue;
        pull = xyl__d3_add(pull, xyl__d3_scale(kv[j].az, kv[j].w * kv[j].s));
        total += kv[j].w * kv[j].s;
    }
    if (xyl__d3_len(pull) > XYL__EPS_REL * total)
        kv[main].az = xyl__d3_normalize_or(xyl__d3_scale(pull, -1.0), kv[main].az);
}

static bool solve_fork(murray *m, uint32_t f, uint32_t k)
{
    kid *kv = m->scratch;
    xyl__dvec3 d0 = incoming(m, f);
    double w0 = load_kids(m, f, kv, k, d0);
    bool clamped = solve_angles(m, kv, k, w0);
    grammar_azimuths(m, kv, k, d0);
    balance_main(kv, k, main_kid(m, kv, k));
    for (uint32_t j = 0; j < k; ++j) {
        xyl__dvec3 to = xyl__d3_add(xyl__d3_scale(d0, kv[j].c), xyl__d3_scale(kv[j].az, kv[j].s));
        to = xyl__d3_normalize_or(to, d0);
        m->rot[kv[j].node] = rotation_between(kv[j].dir, to);
    }
    return clamped;
}

/* ---- the whole tree ------------------------------------------------------------------------ */

/* Children lists in node order: count ends, then place children from the back. */
static uint32_t build_children(murray *m)
{
    uint32_t total = 0, widest = 0;
    for (size_t i = 0; i < m->count; ++i) {
        total += m->nodes[i].children;
        m->first[i] = total;
        if (m->nodes[i].children > widest) widest = m->nodes[i].children;
    }
    m->first[m->count] = total;
    for (size_t i = m->count; i-- > 0;) {
        int32_t p = m->nodes[i].parent;
        if (p >= 0) m->kids[--m->first[p]] = (uint32_t)i;
    }
    return widest;
}

/* new(c) = new(p) + R(c) (old(c) - old(p)), R(c) = R(p) Q(c); parents come first. */
static void apply_nodes(murray *m, const xyl__dvec3 *old)
{
    for (size_t i = 0; i < m->count; ++i) {
        int32_t p = m->nodes[i].parent;
        if (p < 0) continue;
        m->rot[i] = mat3_mul(&m->rot[p], &m->rot[i]);
        xyl__dvec3 rel = mat3_apply(&m->rot[i], xyl__d3_sub(old[i], old[p]));
        m->nodes[i].pos = xyl__d3_add(m->nodes[p].pos, rel);
    }
}

static void apply_leaves(const murray *m, const xyl__dvec3 *old, lsys_tleaf *leaves, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        lsys_tleaf *l = &leaves[i];
        if (l->node < 0) continue;
        const mat3 *r = &m->rot[l->node];
        xyl__dvec3 rel = mat3_apply(r, xyl__d3_sub(l->pos, old[l->node]));
        l->pos = xyl__d3_add(m->nodes[l->node].pos, rel);
        l->frame.h = mat3_apply(r, l->frame.h);
        l->frame.l = mat3_apply(r, l->frame.l);
        xyl__frame_orthonormalize(&l->frame);
    }
}

static void solve_all(murray *m, uint32_t *forks, uint32_t *clamped)
{
    for (size_t i = 0; i < m->count; ++i) m->rot[i] = mat3_identity();
    for (size_t i = 0; i < m->count; ++i) {
        uint32_t k = m->nodes[i].children;
        if (k < 2) continue;
        ++*forks;
        if (solve_fork(m, (uint32_t)i, k)) ++*clamped;
    }
}

xyl_result xyl__lsys_turtle_murray(lsys_tnode *nodes, size_t count, lsys_tleaf *leaves,
                              size_t leaf_count, const double *radius, const lsys_turtle_opts *o,
                              uint32_t *forks, uint32_t *clamped)
{
    const xyl_allocator *a = &o->alloc;
    murray m = {nodes, count, radius, o->exponent, cos(o->max_angle), cos(o->min_angle),
                NULL, NULL, NULL, NULL, NULL};
    *forks = *clamped = 0;
    m.first = xyl__calloc(a, count + 1, sizeof *m.first);
    m.kids = xyl__calloc(a, count ? count : 1, sizeof *m.kids);
    m.rot = xyl__calloc(a, count ? count : 1, sizeof *m.rot);
    xyl__dvec3 *old = xyl__calloc(a, count ? count : 1, sizeof *old);
    xyl_result r = XYL_ERR_OUT_OF_MEMORY;
    if (m.first && m.kids && m.rot && old) {
        size_t widest = (size_t)build_children(&m) + 1u;
        m.scratch = xyl__calloc(a, widest, sizeof *m.scratch);
        m.angles = xyl__calloc(a, widest, sizeof *m.angles);
    }
    if (m.scratch && m.angles) {
        for (size_t i = 0; i < count; ++i) old[i] = nodes[i].pos;
        solve_all(&m, forks, clamped);
        apply_nodes(&m, old);
        apply_leaves(&m, old, leaves, leaf_count);
        r = XYL_OK;
    }
    xyl__free(a, m.first);
    xyl__free(a, m.kids);
    xyl__free(a, m.rot);
    xyl__free(a, m.scratch);
    xyl__free(a, m.angles);
    xyl__free(a, old);
    return r;
}
