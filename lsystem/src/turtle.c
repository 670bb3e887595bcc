/* The ABOP turtle: walks a module string, grows nodes and leaf attachments, then applies the
 * radius rule and (optionally) Murray fork angles and hands the arrays to a skeleton.
 * docs/turtle.md lists every symbol and every decision taken here. */
#include <float.h>
#include <string.h>

#include "skeleton_internal.h"
#include "turtle_internal.h"

#define DEG_TO_RAD (XYL__PI / 180.0)
#define NO_ANCHOR SIZE_MAX
#define FLOAT_MAX ((double)FLT_MAX)

typedef struct tstate {
    xyl__dvec3 pos;
    xyl__frame frame;
    double width;       /* diameter */
    double elasticity;
    int32_t node;       /* node the next F grows from, -1: the next F starts a new root */
    size_t anchor;      /* with node -1: the root shared by branches saved here, or NO_ANCHOR */
    size_t open;        /* module index of the '[' that saved this state */
} tstate;

typedef struct turtle {
    const xyl_grammar *g;
    const xyl_lstring *s;
    const lsys_turtle_opts *o;
    xyl_diag *diag;
    tstate st;
    tstate *stack;
    size_t depth, stack_cap;
    lsys_tnode *nodes;
    size_t node_count, node_cap;
    lsys_tleaf *leaves;
    size_t leaf_count, leaf_cap;
    int32_t *anchors;   /* root node of each anchor, -1 until an F makes it */
    size_t anchor_count, anchor_cap;
    double turn_angle, turn_cos, turn_sin; /* the last turn's angle: grammars repeat a few */
} turtle;

/* ---- frame rotations ----------------------------------------------------------------------- */

/* Right-handed rotation by an angle of cosine c and sine s in the plane (a, b) about a x b:
 * a turns towards b. */
static void rotate_pair(xyl__dvec3 *a, xyl__dvec3 *b, double c, double s)
{
    xyl__dvec3 na = xyl__d3_add(xyl__d3_scale(*a, c), xyl__d3_scale(*b, s));
    xyl__dvec3 nb = xyl__d3_sub(xyl__d3_scale(*b, c), xyl__d3_scale(*a, s));
    *a = na;
    *b = nb;
}

/* ABOP's $: L = V x H / |V x H| with V the world up (+Y). A (nearly) vertical heading has no
 * horizontal left vector; the frame is kept as it is. */
static void roll_horizontal(xyl__frame *f)
{
    xyl__dvec3 l = xyl__d3_cross(xyl__d3(0, 1, 0), f->h);
    double l2 = xyl__d3_dot(l, l);
    if (!(l2 > XYL__EPS_COLLINEAR)) return;
    f->l = xyl__d3_scale(l, 1.0 / sqrt(l2));
}

/* xyl__lsys_turtle_rotate with the angle's cosine and sine given: sin(-a) = -sin(a) exactly, and
 * cos(-a) = cos(a), so the negative turns need no second evaluation. */
static bool rotate_cs(xyl__frame *f, char symbol, double c, double s)
{
    switch (symbol) {
    case '+': rotate_pair(&f->h, &f->l, c, s); break;   /* R_U(+a): H towards L */
    case '-': rotate_pair(&f->h, &f->l, c, -s); break;
    case '&': rotate_pair(&f->h, &f->u, c, -s); break;  /* R_L(+a): H towards -U */
    case '^': rotate_pair(&f->h, &f->u, c, s); break;
    case '\\': rotate_pair(&f->l, &f->u, c, s); break;  /* R_H(+a): L towards U */
    case '/': rotate_pair(&f->l, &f->u, c, -s); break;
    case '|':
        f->h = xyl__d3_scale(f->h, -1.0);
        f->l = xyl__d3_scale(f->l, -1.0);
        break;
    case '$': roll_horizontal(f); break;
    default: return false;
    }
    xyl__frame_orthonormalize(f);
    return true;
}

bool xyl__lsys_turtle_rotate(xyl__frame *f, char symbol, double angle)
{
    return rotate_cs(f, symbol, cos(angle), sin(angle));
}

/* ---- options ------------------------------------------------------------------------------- */

static xyl_result bad_option(xyl_diag *diag, const char *what)
{
    return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "xyl_turtle_desc: %s", what);
}

static xyl_result resolve_angles(const xyl_turtle_desc *d, lsys_turtle_opts *o, xyl_diag *diag)
{
    double lo = d->murray_min_angle, hi = d->murray_max_angle;
    if (!isfinite(lo) || !isfinite(hi) || lo < 0.0 || hi < 0.0)
        return bad_option(diag, "Murray angles must be finite and >= 0");
    o->min_angle = lo > 0.0 ? lo : 10.0 * DEG_TO_RAD;
    o->max_angle = hi > 0.0 ? hi : 90.0 * DEG_TO_RAD;
    if (o->min_angle > o->max_angle || o->max_angle > XYL__PI)
        return bad_option(diag, "Murray angles need min <= max <= pi");
    return XYL_OK;
}

static xyl_result resolve_radii(const xyl_grammar *g, const xyl_turtle_desc *d,
                                lsys_turtle_opts *o, xyl_diag *diag)
{
    double n = d->radius_exponent, tip = d->tip_radius;
    if (!isfinite(n) || (n != 0.0 && !(n > 0.5 && n <= 8.0)))
        return bad_option(diag, "radius_exponent must be in (0.5, 8] (or 0 for 2)");
    if (!isfinite(tip) || tip < 0.0 || tip > FLOAT_MAX || (tip > 0.0 && !((float)tip > 0.0f)))
        return bad_option(diag, "tip_radius must be finite, >= 0 and representable as a float");
    o->exponent = n != 0.0 ? n : 2.0;
    o->tip_radius = tip != 0.0 ? tip : 0.5 * g->info.width;
    if (o->radius_mode == XYL_RADIUS_PIPE && tip == 0.0 &&
        !(o->tip_radius <= FLOAT_MAX && (float)o->tip_radius > 0.0f))
        return xyl__fail(diag, XYL_ERR_INVALID_GRAMMAR, 0, 0, -1,
                         "#width %g gives no usable tip radius; set tip_radius", g->info.width);
    return XYL_OK;
}

static xyl_result resolve_options(const xyl_grammar *g, const xyl_turtle_desc *d,
                                  lsys_turtle_opts *o, xyl_diag *diag)
{
    if ((unsigned)d->radius_mode > (unsigned)XYL_RADIUS_GRAMMAR)
        return bad_option(diag, "unknown radius_mode");
    if ((unsigned)d->angle_mode > (unsigned)XYL_ANGLES_MURRAY)
        return bad_option(diag, "unknown angle_mode");
    o->radius_mode = d->radius_mode;
    o->angle_mode = d->angle_mode;
    o->merge = d->merge_collinear;
    o->alloc = d->alloc;
    o->max_nodes = d->limits.max_nodes ? d->limits.max_nodes : XYL__SKEL_DEFAULT_MAX_NODES;
    o->max_leaves = d->limits.max_leaves ? d->limits.max_leaves : XYL__SKEL_DEFAULT_MAX_LEAVES;
    o->max_nesting = g->limits.max_nesting ? g->limits.max_nesting : LSYS_DEFAULT_MAX_NESTING;
    if (!isfinite(d->origin[0]) || !isfinite(d->origin[1]) || !isfinite(d->origin[2]))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "xyl_turtle_desc: the origin is not "
                                                             "finite");
    memcpy(o->origin, d->origin, sizeof o->origin);
    xyl_result r = resolve_angles(d, o, diag);
    return r != XYL_OK ? r : resolve_radii(g, d, o, diag);
}

static xyl_result check_info(const xyl_grammar_info *in, xyl_diag *diag)
{
    bool ok = isfinite(in->angle) && isfinite(in->step) && isfinite(in->width) &&
              isfinite(in->elasticity) && isfinite(in->tropism[0]) &&
              isfinite(in->tropism[1]) && isfinite(in->tropism[2]);
    if (ok) return XYL_OK;
    return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1,
                     "the grammar's #angle, #step, #width or #tropism is not finite");
}

/* ---- helpers ------------------------------------------------------------------------------- */

static bool fits_float(xyl__dvec3 v)
{
    return fabs(v.x) <= FLOAT_MAX && fabs(v.y) <= FLOAT_MAX && fabs(v.z) <= FLOAT_MAX;
}

/* The first parameter (extra ones are ignored), or fallback when the module has none. */
static xyl_result first_param(const turtle *t, size_t i, double fallback, double *v)
{
    if (lsys_np(t->s, i) == 0) {
        *v = fallback;
        return XYL_OK;
    }
    *v = lsys_par(t->s, i)[0];
    if (isfinite(*v)) return XYL_OK;
    return xyl__fail(t->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                     "module %zu ('%c') has a non-finite parameter", i, (char)t->s->sym[i]);
}

static xyl_result position_error(const turtle *t, size_t i)
{
    return xyl__fail(t->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                     "module %zu ('%c') moves the turtle out of the float range", i,
                     (char)t->s->sym[i]);
}

/* Grammar widths become radii; a radius must be a positive float. */
static xyl_result check_width(const turtle *t, size_t i)
{
    double r = 0.5 * t->st.width;
    if (t->o->radius_mode != XYL_RADIUS_GRAMMAR) return XYL_OK;
    if (!(fabs(r) <= FLOAT_MAX))
        return xyl__fail(t->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                         "module %zu: width %g overflows a float radius", i, t->st.width);
    if (!((float)r > 0.0f))
        return xyl__fail(t->diag, XYL_ERR_INVALID_GRAMMAR, 0, 0, (int64_t)i,
                         "module %zu draws with width %g; grammar radii need a width > 0", i,
                         t->st.width);
    return XYL_OK;
}

/* ---- nodes and leaves ---------------------------------------------------------------------- */

static xyl_result add_node(turtle *t, size_t i, xyl__dvec3 pos, int32_t parent)
{
    if ((uint64_t)t->node_count >= t->o->max_nodes || t->node_count >= (size_t)INT32_MAX)
        return xyl__fail(t->diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, (int64_t)i,
                         "module %zu: more than %llu skeleton nodes", i,
                         (unsigned long long)t->o->max_nodes);
    xyl_result r = check_width(t, i);
    if (r != XYL_OK) return r;
    if (!xyl__grow(&t->o->alloc, (void **)&t->nodes, &t->node_cap, t->node_count,
                   t->node_count + 1, sizeof *t->nodes))
        return xyl__fail(t->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, (int64_t)i, "out of memory");
    lsys_tnode *n = &t->nodes[t->node_count];
    memset(n, 0, sizeof *n);
    n->pos = pos;
    n->width = t->st.width;
    n->module = i;
    n->parent = parent;
    if (parent >= 0) t->nodes[parent].children++;
    t->st.node = (int32_t)t->node_count++;
    return XYL_OK;
}

static xyl__dvec3 direction(xyl__dvec3 from, xyl__dvec3 to)
{
    return xyl__d3_normalize_or(xyl__d3_sub(to, from), xyl__d3(0, 0, 0));
}

/* merge_collinear: the current node may slide forward to `to` when nothing hangs from it,
 * nothing may branch from it later (pinned), and the segment keeps direction and width. */
static bool mergeable(const turtle *t, xyl__dvec3 to)
{
    if (!t->o->merge || t->st.node < 0) return false;
    const lsys_tnode *n = &t->nodes[t->st.node];
    if (n->parent < 0 || n->children || n->has_leaf || n->pinned) return false;
    if (n->width != t->st.width) return false;
    xyl__dvec3 prev = direction(t->nodes[n->parent].pos, n->pos);
    xyl__dvec3 next = direction(n->pos, to);
    return 1.0 - xyl__d3_dot(prev, next) < XYL__EPS_COLLINEAR;
}

/* ABOP 2.2: after each F the heading bends about H x T by e |H x T|. */
static void bend(turtle *t)
{
    const double *tv = t->g->info.tropism;
    xyl__dvec3 tropism = xyl__d3(tv[0], tv[1], tv[2]);
    double e = t->st.elasticity;
    if (e == 0.0 || xyl__d3_dot(tropism, tropism) == 0.0) return;
    xyl__frame *f = &t->st.frame;
    xyl__dvec3 axis = xyl__d3_cross(f->h, tropism);
    double s = xyl__d3_len(axis);
    if (!(s > XYL__EPS_REL * xyl__d3_len(tropism))) return;
    axis = xyl__d3_scale(axis, 1.0 / s);
    double c = cos(e * s), sn = sin(e * s);
    f->h = xyl__d3_rotate_cs(f->h, axis, c, sn);
    f->l = xyl__d3_rotate_cs(f->l, axis, c, sn);
    xyl__frame_orthonormalize(f);
}

/* The node an F starts from when there is no current node: the root that an earlier branch
 * saved at the same state already made (so `[+F][-F]` forks at one root), or a new root. */
static xyl_result start_node(turtle *t, size_t i)
{
    int32_t *anchor = t->st.anchor != NO_ANCHOR ? &t->anchors[t->st.anchor] : NULL;
    if (anchor && *anchor >= 0) {
        t->st.node = *anchor;
        return XYL_OK;
    }
    xyl_result r = add_node(t, i, t->st.pos, -1);
    if (r == XYL_OK && anchor) *anchor = t->st.node;
    return r;
}

/* Where F or f at module i moves the turtle; *stay when its length is 0 (no effect at all). */
static xyl_result target(turtle *t, size_t i, xyl__dvec3 *to, bool *stay)
{
    double len;
    xyl_result r = first_param(t, i, t->g->info.step, &len);
    *stay = r != XYL_OK || len == 0.0;
    if (*stay) return r;
    *to = xyl__d3_add(t->st.pos, xyl__d3_scale(t->st.frame.h, len));
    return fits_float(*to) ? XYL_OK : position_error(t, i);
}

static xyl_result draw(turtle *t, size_t i)
{
    xyl__dvec3 to;
    bool stay;
    xyl_result r = target(t, i, &to, &stay);
    if (r != XYL_OK || stay) return r;
    if (t->st.node < 0 && (r = start_node(t, i)) != XYL_OK) return r;
    if (mergeable(t, to)) {
        t->nodes[t->st.node].pos = to;
        t->nodes[t->st.node].module = i;
    } else if ((r = add_node(t, i, to, t->st.node)) != XYL_OK) {
        return r;
    }
    t->st.pos = to;
    bend(t);
    return XYL_OK;
}

static xyl_result move(turtle *t, size_t i)
{
    xyl__dvec3 to;
    bool stay;
    xyl_result r = target(t, i, &to, &stay);
    if (r != XYL_OK || stay) return r;
    t->st.pos = to;
    t->st.node = -1;
    t->st.anchor = NO_ANCHOR;
    return XYL_OK;
}

static xyl_result add_leaf(turtle *t, size_t i)
{
    double size;
    xyl_result r = first_param(t, i, 0.5 * t->g->info.step, &size);
    if (r != XYL_OK) return r;
    if (!(fabs(size) <= FLOAT_MAX))
        return xyl__fail(t->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)i,
                         "module %zu: leaf size %g overflows a float", i, size);
    if (!((float)size > 0.0f)) return XYL_OK; /* documented: no leaf */
    if ((uint64_t)t->leaf_count >= t->o->max_leaves)
        return xyl__fail(t->diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, (int64_t)i,
                         "module %zu: more than %llu leaves", i,
                         (unsigned long long)t->o->max_leaves);
    if (!xyl__grow(&t->o->alloc, (void **)&t->leaves, &t->leaf_cap, t->leaf_count,
                   t->leaf_count + 1, sizeof *t->leaves))
        return xyl__fail(t->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, (int64_t)i, "out of memory");
    lsys_tleaf *l = &t->leaves[t->leaf_count++];
    l->pos = t->st.pos;
    l->frame = t->st.frame;
    l->size = size;
    l->module = i;
    l->node = t->st.node;
    if (l->node >= 0) t->nodes[l->node].has_leaf = true;
    return XYL_OK;
}

/* ---- state --------------------------------------------------------------------------------- */

/* A '[' before any node at this position opens an anchor its branches will share. */
static bool open_anchor(turtle *t)
{
    if (t->st.node >= 0 || t->st.anchor != NO_ANCHOR) return true;
    if (!xyl__grow(&t->o->alloc, (void **)&t->anchors, &t->anchor_cap, t->anchor_count,
                   t->anchor_count + 1, sizeof *t->anchors))
        return false;
    t->anchors[t->anchor_count] = -1;
    t->st.anchor = t->anchor_count++;
    return true;
}

static xyl_result push(turtle *t, size_t i)
{
    if (t->depth >= t->o->max_nesting)
        return xyl__fail(t->diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, (int64_t)i,
                         "module %zu: brackets nest deeper than %u", i, t->o->max_nesting);
    if (!xyl__grow(&t->o->alloc, (void **)&t->stack, &t->stack_cap, t->depth, t->depth + 1,
                   sizeof *t->stack) ||
        !open_anchor(t))
        return xyl__fail(t->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, (int64_t)i, "out of memory");
    t->st.open = i;
    t->stack[t->depth++] = t->st;
    if (t->st.node >= 0) t->nodes[t->st.node].pinned = true;
    return XYL_OK;
}

static xyl_result pop(turtle *t, size_t i)
{
    if (t->depth == 0)
        return xyl__fail(t->diag, XYL_ERR_INVALID_GRAMMAR, 0, 0, (int64_t)i,
                         "']' at module %zu closes no '['", i);
    t->st = t->stack[--t->depth];
    return XYL_OK;
}

static xyl_result turn(turtle *t, size_t i)
{
    double a = t->g->info.angle;
    if (lsys_np(t->s, i)) {
        xyl_result r = first_param(t, i, 0.0, &a);
        if (r != XYL_OK) return r;
        a *= DEG_TO_RAD;
    }
    if (!(a == t->turn_angle) || signbit(a) != signbit(t->turn_angle)) { /* NaN at first */
        t->turn_angle = a;
        t->turn_cos = cos(a);
        t->turn_sin = sin(a);
    }
    rotate_cs(&t->st.frame, (char)t->s->sym[i], t->turn_cos, t->turn_sin);
    return XYL_OK;
}

static xyl_result set_width(turtle *t, size_t i)
{
    return first_param(t, i, t->st.width, &t->st.width);
}

static xyl_result set_elasticity(turtle *t, size_t i)
{
    return first_param(t, i, t->g->info.elasticity, &t->st.elasticity);
}

/* '%': the index of the ']' that ends the current branch, or the end of the string. */
static size_t skip_branch(const xyl_lstring *s, size_t i)
{
    size_t level = 0;
    for (size_t j = i + 1; j < s->count; ++j) {
        if (s->sym[j] == '[') {
            ++level;
        } else if (s->sym[j] == ']') {
            if (level == 0) return j;
            --level;
        }
    }
    return s->count;
}

static xyl_result step(turtle *t, size_t i, size_t *next)
{
    *next = i + 1;
    switch (t->s->sym[i]) {
    case 'F': return draw(t, i);
    case 'f': return move(t, i);
    case '[': return push(t, i);
    case ']': return pop(t, i);
    case '!': return set_width(t, i);
    case 'T': return set_elasticity(t, i);
    case 'L': return add_leaf(t, i);
    case '%': *next = skip_branch(t->s, i); return XYL_OK;
    case '|': case '$': xyl__lsys_turtle_rotate(&t->st.frame, (char)t->s->sym[i], 0.0);
        return XYL_OK;
    case '+': case '-': case '&': case '^': case '\\': case '/': return turn(t, i);
    default: return XYL_OK;
    }
}

static xyl_result walk(turtle *t)
{
    size_t i = 0;
    while (i < t->s->count) {
        size_t next;
        xyl_result r = step(t, i, &next);
        if (r != XYL_OK) return r;
        i = next;
    }
    if (t->depth == 0) return XYL_OK;
    size_t open = t->stack[t->depth - 1].open;
    return xyl__fail(t->diag, XYL_ERR_INVALID_GRAMMAR, 0, 0, (int64_t)open,
                     "'[' at module %zu is never closed", open);
}

/* ---- output -------------------------------------------------------------------------------- */

/* Pipe radii grow with the number of tips; a huge tip radius could leave the float range. */
static xyl_result check_radii(const turtle *t, const double *radius)
{
    for (size_t i = 0; i < t->node_count; ++i) {
        if (radius[i] <= FLOAT_MAX) continue;
        return xyl__fail(t->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)t->nodes[i].module,
                         "the radius of the node of module %zu overflows a float",
                         t->nodes[i].module);
    }
    return XYL_OK;
}

static xyl_result fill_nodes(const turtle *t, const double *radius, xyl_skel_node *out)
{
    for (size_t i = 0; i < t->node_count; ++i) {
        const lsys_tnode *n = &t->nodes[i];
        if (!fits_float(n->pos))
            return xyl__fail(t->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)n->module,
                             "node of module %zu leaves the float range", n->module);
        out[i].pos = xyl__to_f3(n->pos);
        out[i].radius = (float)radius[i];
        out[i].parent = n->parent;
    }
    return XYL_OK;
}

static xyl_result fill_leaves(const turtle *t, xyl_skel_leaf *out)
{
    for (size_t i = 0; i < t->leaf_count; ++i) {
        const lsys_tleaf *l = &t->leaves[i];
        if (!fits_float(l->pos))
            return xyl__fail(t->diag, XYL_ERR_NON_FINITE, 0, 0, (int64_t)l->module,
                             "leaf of module %zu leaves the float range", l->module);
        out[i].pos = xyl__to_f3(l->pos);
        out[i].heading = xyl__to_f3(l->frame.h);
        out[i].left = xyl__to_f3(l->frame.l);
        out[i].up = xyl__to_f3(l->frame.u);
        out[i].size = (float)l->size;
        out[i].node = l->node;
    }
    return XYL_OK;
}

static xyl_result adopt(const turtle *t, const double *radius, xyl_skeleton **out)
{
    const xyl_allocator *a = &t->o->alloc;
    xyl_skel_node *nodes = xyl__calloc(a, t->node_count ? t->node_count : 1, sizeof *nodes);
    xyl_skel_leaf *leaves = xyl__calloc(a, t->leaf_count ? t->leaf_count : 1, sizeof *leaves);
    xyl_result r = XYL_OK;
    if (!nodes || !leaves)
        r = xyl__fail(t->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    if (r == XYL_OK) r = fill_nodes(t, radius, nodes);
    if (r == XYL_OK) r = fill_leaves(t, leaves);
    if (r != XYL_OK) {
        xyl__free(a, nodes);
        xyl__free(a, leaves);
        return r;
    }
    return xyl__skeleton_adopt(nodes, t->node_count, leaves, t->leaf_count, t->o->origin, a, out,
                               t->diag);
}

static xyl_result finish(turtle *t, xyl_skeleton **out)
{
    const xyl_allocator *a = &t->o->alloc;
    double *radius = xyl__calloc(a, t->node_count ? t->node_count : 1, sizeof *radius);
    if (!radius) return xyl__fail(t->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    xyl__lsys_turtle_radii(t->nodes, t->node_count, t->o, radius);
    uint32_t forks = 0, clamped = 0;
    xyl_result r = check_radii(t, radius);
    if (r == XYL_OK && t->o->angle_mode == XYL_ANGLES_MURRAY &&
        xyl__lsys_turtle_murray(t->nodes, t->node_count, t->leaves, t->leaf_count, radius, t->o,
                           &forks, &clamped) != XYL_OK)
        r = xyl__fail(t->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for Murray angles");
    xyl_skeleton *sk = NULL;
    if (r == XYL_OK) r = adopt(t, radius, &sk);
    xyl__free(a, radius);
    if (r != XYL_OK) return r;
    sk->clamped_forks = clamped;
    if (clamped)
        xyl__warn(t->diag, "Murray angles clamped at %u of %u forks (min %.3g deg, max %.3g deg)",
                  clamped, forks, t->o->min_angle / DEG_TO_RAD, t->o->max_angle / DEG_TO_RAD);
    /* a grammar that walks far from where it started (f(1e6)) still holds floats */
    xyl__skeleton_warn_precision(sk->nodes, sk->node_count, "the skeleton", t->diag);
    *out = sk;
    return XYL_OK;
}

static void start(turtle *t)
{
    const xyl_grammar_info *in = &t->g->info;
    memset(&t->st, 0, sizeof t->st);
    t->st.frame.h = xyl__d3(0, 1, 0);  /* Y up, as in glTF */
    t->st.frame.l = xyl__d3(-1, 0, 0);
    t->st.frame.u = xyl__d3(0, 0, 1);
    t->st.width = in->width;
    t->st.elasticity = in->elasticity;
    t->st.node = -1;
    t->st.anchor = NO_ANCHOR;
}

xyl_result xyl_lsystem_interpret(const xyl_grammar *grammar, const xyl_lstring *string,
                                 const xyl_turtle_desc *desc, xyl_skeleton **out, xyl_diag *diag)
{
    if (!grammar || !string || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "grammar, string and out must not be NULL");
    xyl_turtle_desc zero;
    memset(&zero, 0, sizeof zero);
    lsys_turtle_opts o;
    memset(&o, 0, sizeof o);
    xyl_result r = check_info(&grammar->info, diag);
    if (r == XYL_OK) r = resolve_options(grammar, desc ? desc : &zero, &o, diag);
    if (r != XYL_OK) return r;
    turtle t;
    memset(&t, 0, sizeof t);
    t.g = grammar;
    t.s = string;
    t.o = &o;
    t.diag = diag;
    t.turn_angle = NAN;
    start(&t);
    r = walk(&t);
    if (r == XYL_OK) r = finish(&t, out);
    xyl__free(&o.alloc, t.stack);
    xyl__free(&o.alloc, t.nodes);
    xyl__free(&o.alloc, t.leaves);
    xyl__free(&o.alloc, t.anchors);
    return r;
}
