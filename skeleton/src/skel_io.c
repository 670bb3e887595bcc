/* The .skel text format (docs/skeleton-format.md) and the OBJ polyline export.
 *
 * The reader is strict and line based: every error names a 1-based line and column. Neither
 * direction depends on the C locale: the reader parses numbers with text_reader.h rather than
 * strtod, and the writer prints them with float_text.h. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "float_text.h"
#include "text_reader.h"
#include "skeleton_internal.h"
#include "xylem/xyl_skeleton.h"

#define SKEL_VERSION 1
/* A .skel file of the default limits' size is far below this; larger files are refused before
 * they are read into memory. */
#define MAX_FILE_BYTES ((size_t)1 << 30)
/* The defaults xyl_skeleton.h documents for xyl_skeleton_limits (skeleton.c applies the same). */
/* The shortest records with their line break ("n 0 -1 0 0 0 1\n"): the remaining text bounds
 * how many records it can hold, so an announced count never reserves more memory than that. */
#define MIN_NODE_RECORD_BYTES 14
#define MIN_LEAF_RECORD_BYTES 30
/* Characters of a token quoted in a message. */
#define SHOW_CHARS 24

/* ==== reader ================================================================================ */

typedef enum stage {
    STAGE_HEADER,
    STAGE_NODE_COUNT,
    STAGE_LEAF_COUNT,
    STAGE_NODES,
    STAGE_LEAVES,
    STAGE_END,
    STAGE_DONE
} stage;

typedef struct parser {
    xyl__text_reader txt; /* txt.index: the node or leaf being read, -1 outside records */
    stage stage;
    xyl_allocator alloc;
    xyl_skeleton_limits limits;
    uint64_t max_nodes, max_leaves;
    size_t node_total, leaf_total; /* announced */
    xyl_skel_node *nodes;
    size_t node_cap, node_count;
    xyl_skel_leaf *leaves;
    size_t leaf_cap, leaf_count;
    double *node_world, *leaf_world; /* 3 per node / leaf: positions as read, in double */
    size_t node_world_cap, leaf_world_cap;
    double origin[3]; /* chosen once all is read (choose_origin) */
} parser;

static xyl_result need_token(parser *p, xyl__token *t, const char *what)
{
    if (xyl__text_next_token(&p->txt, t)) return XYL_OK;
    return xyl__text_fail(&p->txt, XYL_ERR_PARSE, xyl__to_u32(p->txt.last_end + 1),
                          "the line ends where %s was expected", what);
}

static xyl_result need_record_end(parser *p)
{
    xyl__token t = {0};
    char buf[40];
    if (!xyl__text_next_token(&p->txt, &t)) return XYL_OK;
    return xyl__text_fail(&p->txt, XYL_ERR_PARSE, t.col,
                          "unexpected '%s' after the end of the record",
                          xyl__text_show(&t, SHOW_CHARS, buf));
}

/* The first token of the next line that has one; *eof at the end of the text. */
static xyl_result next_record(parser *p, xyl__token *keyword, bool *eof)
{
    for (;;) {
        if (!xyl__text_next_line(&p->txt)) {
            *eof = true;
            return XYL_OK;
        }
        const char *nul = memchr(p->txt.line, '\0', p->txt.len);
        if (nul)
            return xyl__text_fail(&p->txt, XYL_ERR_PARSE,
                                  xyl__to_u32((size_t)(nul - p->txt.line) + 1),
                                  "a NUL byte; .skel files are text");
        if (xyl__text_next_token(&p->txt, keyword)) {
            *eof = false;
            return XYL_OK;
        }
    }
}

/* ---- numbers ------------------------------------------------------------------------------- */

typedef enum num_status { NUM_OK, NUM_BAD, NUM_NON_FINITE, NUM_TOO_LARGE } num_status;

/* A number as xyl__text_real reads it (NaN payloads "nan(...)" are non-finite too), in the range
 * of a float (a double up to FLT_MAX + half an ulp is FLT_MAX). Rounded to a float, every value
 * the writer or "%.9g" prints comes back as the same float. */
static num_status parse_real(const xyl__token *t, double *out)
{
    double v;
    xyl__num_status st = xyl__text_real(t->s, t->n, &v);
    if (st == XYL__NUM_NON_FINITE) return NUM_NON_FINITE;
    if (st != XYL__NUM_OK) {
        size_t i = t->n > 0 && (t->s[0] == '-' || t->s[0] == '+') ? 1 : 0;
        size_t n = t->n - i;
        bool nan_payload = n >= 4 && xyl__text_ieq(t->s + i, 4, "nan(") && t->s[t->n - 1] == ')';
        return nan_payload ? NUM_NON_FINITE : NUM_BAD;
    }
    /* A double up to FLT_MAX + half an ulp still rounds to FLT_MAX; from there on to inf. */
    if (!(fabs(v) < (double)FLT_MAX + ldexp(1.0, 103))) return NUM_TOO_LARGE;
    if (fabs(v) > FLT_MAX) v = v < 0 ? -(double)FLT_MAX : (double)FLT_MAX;
    *out = v;
    return NUM_OK;
}

/* ---- records ------------------------------------------------------------------------------- */

static xyl_result real_field_d(parser *p, const char *what, double *out, uint32_t *col)
{
    xyl__token t = {0};
    char buf[40];
    xyl_result r = need_token(p, &t, what);
    if (r != XYL_OK) return r;
    if (col) *col = t.col;
    switch (parse_real(&t, out)) {
    case NUM_OK:
        return XYL_OK;
    case NUM_NON_FINITE:
        return xyl__text_fail(&p->txt, XYL_ERR_NON_FINITE, t.col,
                              "%s is '%s'; numbers must be finite", what,
                              xyl__text_show(&t, SHOW_CHARS, buf));
    case NUM_TOO_LARGE:
        return xyl__text_fail(&p->txt, XYL_ERR_NON_FINITE, t.col,
                              "%s '%s' is too large for a float", what,
                              xyl__text_show(&t, SHOW_CHARS, buf));
    default:
        return xyl__text_fail(&p->txt, XYL_ERR_PARSE, t.col, "%s '%s' is not a number", what,
                              xyl__text_show(&t, SHOW_CHARS, buf));
    }
}

static xyl_result real_field(parser *p, const char *what, float *out, uint32_t *col)
{
    double v = 0.0;
    xyl_result r = real_field_d(p, what, &v, col);
    if (r == XYL_OK) *out = (float)v;
    return r;
}

/* The names of a vector's three fields, in messages: fixed text, so that reading a number costs
 * no formatting. */
typedef const char *const vec3_names[3];
static vec3_names NODE_POSITION = {"the node position x", "the node position y",
                                   "the node position z"};
static vec3_names LEAF_POSITION = {"the leaf position x", "the leaf position y",
                                   "the leaf position z"};
static vec3_names LEAF_HEADING = {"the leaf heading x", "the leaf heading y",
                                  "the leaf heading z"};
static vec3_names LEAF_LEFT = {"the leaf left vector x", "the leaf left vector y",
                               "the leaf left vector z"};
static vec3_names LEAF_UP = {"the leaf up vector x", "the leaf up vector y",
                             "the leaf up vector z"};

static xyl_result vec3_field(parser *p, vec3_names names, xyl_vec3 *v)
{
    float *c[3] = {&v->x, &v->y, &v->z};
    for (int k = 0; k < 3; ++k) {
        xyl_result r = real_field(p, names[k], c[k], NULL);
        if (r != XYL_OK) return r;
    }
    return XYL_OK;
}

/* A position, kept in double until the origin is chosen (choose_origin); *v stays 0 till then. */
static xyl_result position_field(parser *p, vec3_names names, double **world, size_t *cap,
                                 size_t count)
{
    double w[3];
    for (int k = 0; k < 3; ++k) {
        xyl_result r = real_field_d(p, names[k], &w[k], NULL);
        if (r != XYL_OK) return r;
    }
    void *arr = *world;
    if (!xyl__grow(&p->alloc, &arr, cap, 3 * count, 3 * count + 3, sizeof **world))
        return xyl__text_fail(&p->txt, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for %zu positions",
                              count + 1);
    *world = arr;
    memcpy(*world + 3 * count, w, sizeof w);
    return XYL_OK;
}

static xyl_result int_field(parser *p, const char *what, int64_t *out, uint32_t *col)
{
    xyl__token t = {0};
    char buf[40];
    xyl_result r = need_token(p, &t, what);
    if (r != XYL_OK) return r;
    *col = t.col;
    if (xyl__text_i64(t.s, t.n, out)) return XYL_OK;
    return xyl__text_fail(&p->txt, XYL_ERR_PARSE, t.col, "%s '%s' is not an integer", what,
                          xyl__text_show(&t, SHOW_CHARS, buf));
}

static xyl_result node_id(parser *p)
{
    xyl__token t = {0};
    char buf[40];
    uint64_t id;
    xyl_result r = need_token(p, &t, "the node id");
    if (r != XYL_OK) return r;
    if (!xyl__text_u64(t.s, t.n, &id))
        return xyl__text_fail(&p->txt, XYL_ERR_PARSE, t.col,
                              "node id '%s' is not an unsigned integer",
                              xyl__text_show(&t, SHOW_CHARS, buf));
    if (id != (uint64_t)p->node_count)
        return xyl__text_fail(
            &p->txt, XYL_ERR_PARSE, t.col,
            "node id %s is out of order: ids count 0, 1, 2, ... so %zu belongs here",
            xyl__text_show(&t, SHOW_CHARS, buf), p->node_count);
    return XYL_OK;
}

static xyl_result push_node(parser *p, const xyl_skel_node *n)
{
    void *arr = p->nodes;
    if (!xyl__grow(&p->alloc, &arr, &p->node_cap, p->node_count, p->node_count + 1, sizeof *n))
        return xyl__text_fail(&p->txt, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for %zu nodes",
                              p->node_total);
    p->nodes = arr;
    p->nodes[p->node_count++] = *n;
    return XYL_OK;
}

static xyl_result push_leaf(parser *p, const xyl_skel_leaf *l)
{
    void *arr = p->leaves;
    if (!xyl__grow(&p->alloc, &arr, &p->leaf_cap, p->leaf_count, p->leaf_count + 1, sizeof *l))
        return xyl__text_fail(&p->txt, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for %zu leaves",
                              p->leaf_total);
    p->leaves = arr;
    p->leaves[p->leaf_count++] = *l;
    return XYL_OK;
}

/* n <id> <parent> <x> <y> <z> <radius>. The invariants xyl_skeleton_create checks are checked
 * here too, so that their errors carry a line and column. */
static xyl_result parse_node(parser *p)
{
    xyl_skel_node n = {{0, 0, 0}, 0, 0, 0, 0};
    int64_t parent = 0;
    uint32_t col = 0;
    p->txt.index = (int64_t)p->node_count;
    xyl_result r = node_id(p);
    if (r == XYL_OK) r = int_field(p, "the parent id", &parent, &col);
    if (r != XYL_OK) return r;
    if (parent < -1 || parent >= (int64_t)p->node_count)
        return xyl__text_fail(&p->txt, XYL_ERR_INVALID_SKELETON, col,
                              "node %zu has parent %lld; a parent must come before its child "
                              "(or be -1 for a root)",
                              p->node_count, (long long)parent);
    n.parent = (int32_t)parent;
    r = position_field(p, NODE_POSITION, &p->node_world, &p->node_world_cap, p->node_count);
    if (r == XYL_OK) r = real_field(p, "the node radius", &n.radius, &col);
    if (r != XYL_OK) return r;
    if (!(n.radius > 0.0f))
        return xyl__text_fail(&p->txt, XYL_ERR_INVALID_SKELETON, col,
                              "node %zu has radius %g; radii must be > 0", p->node_count,
                              (double)n.radius);
    r = need_record_end(p);
    return r == XYL_OK ? push_node(p, &n) : r;
}

/* l <node> <x y z> <heading xyz> <left xyz> <up xyz> <size> */
static xyl_result parse_leaf(parser *p)
{
    xyl_skel_leaf l;
    memset(&l, 0, sizeof l);
    int64_t node = 0;
    uint32_t col = 0;
    p->txt.index = (int64_t)p->leaf_count;
    xyl_result r = int_field(p, "the leaf's node", &node, &col);
    if (r != XYL_OK) return r;
    if (node < -1 || node >= (int64_t)p->node_count)
        return xyl__text_fail(&p->txt, XYL_ERR_INVALID_SKELETON, col,
                              "leaf %zu hangs from node %lld, which does not exist", p->leaf_count,
                              (long long)node);
    l.node = (int32_t)node;
    r = position_field(p, LEAF_POSITION, &p->leaf_world, &p->leaf_world_cap, p->leaf_count);
    if (r == XYL_OK) r = vec3_field(p, LEAF_HEADING, &l.heading);
    if (r == XYL_OK) r = vec3_field(p, LEAF_LEFT, &l.left);
    if (r == XYL_OK) r = vec3_field(p, LEAF_UP, &l.up);
    if (r == XYL_OK) r = real_field(p, "the leaf size", &l.size, &col);
    if (r != XYL_OK) return r;
    if (!(l.size > 0.0f))
        return xyl__text_fail(&p->txt, XYL_ERR_INVALID_SKELETON, col,
                              "leaf %zu has size %g; sizes must be > 0", p->leaf_count,
                              (double)l.size);
    r = need_record_end(p);
    return r == XYL_OK ? push_leaf(p, &l) : r;
}

/* ---- header and counts --------------------------------------------------------------------- */

static xyl_result parse_header(parser *p, const xyl__token *kw)
{
    xyl__token t = {0};
    char buf[40];
    uint64_t version;
    if (!xyl__token_is(kw, "xylem-skeleton"))
        return xyl__text_fail(
            &p->txt, XYL_ERR_PARSE, kw->col,
            "not a .skel file: found '%s' where 'xylem-skeleton %d' must come first",
            xyl__text_show(kw, SHOW_CHARS, buf), SKEL_VERSION);
    xyl_result r = need_token(p, &t, "the format version");
    if (r != XYL_OK) return r;
    if (!xyl__text_u64(t.s, t.n, &version))
        return xyl__text_fail(&p->txt, XYL_ERR_PARSE, t.col, "format version '%s' is not a number",
                              xyl__text_show(&t, SHOW_CHARS, buf));
    if (version != SKEL_VERSION)
        return xyl__text_fail(&p->txt, XYL_ERR_UNSUPPORTED, t.col,
                              "format version %s is not supported; this build reads version %d",
                              xyl__text_show(&t, SHOW_CHARS, buf), SKEL_VERSION);
    return need_record_end(p);
}

/* "<word> <count>"; the limit is checked here, before anything is allocated. */
static xyl_result parse_count(parser *p, const xyl__token *kw, const char *word, uint64_t max,
                              size_t *out)
{
    xyl__token t = {0};
    char buf[40];
    uint64_t v;
    if (!xyl__token_is(kw, word))
        return xyl__text_fail(&p->txt, XYL_ERR_PARSE, kw->col, "expected '%s <count>', found '%s'",
                              word, xyl__text_show(kw, SHOW_CHARS, buf));
    xyl_result r = need_token(p, &t, "a count");
    if (r != XYL_OK) return r;
    if (!xyl__text_u64(t.s, t.n, &v))
        return xyl__text_fail(&p->txt, XYL_ERR_PARSE, t.col,
                              "%s count '%s' is not an unsigned integer", word,
                              xyl__text_show(&t, SHOW_CHARS, buf));
    if (v > max)
        return xyl__text_fail(&p->txt, XYL_ERR_LIMIT_EXCEEDED, t.col,
                              "%s %s exceeds the limit of %llu", word,
                              xyl__text_show(&t, SHOW_CHARS, buf), (unsigned long long)max);
    *out = (size_t)v;
    return need_record_end(p);
}

/* Reserves what the announced counts need, but never more than the rest of the text can hold:
 * a short text announcing millions of nodes must not allocate for them. */
static xyl_result reserve(parser *p)
{
    size_t left = p->txt.size - p->txt.next;
    size_t nodes = left / MIN_NODE_RECORD_BYTES + 1;
    size_t leaves = left / MIN_LEAF_RECORD_BYTES + 1;
    void *n = NULL, *l = NULL;
    if (nodes > p->node_total) nodes = p->node_total ? p->node_total : 1;
    if (leaves > p->leaf_total) leaves = p->leaf_total ? p->leaf_total : 1;
    if (!xyl__grow(&p->alloc, &n, &p->node_cap, 0, nodes, sizeof *p->nodes) ||
        !xyl__grow(&p->alloc, &l, &p->leaf_cap, 0, leaves, sizeof *p->leaves)) {
        xyl__free(&p->alloc, n);
        p->node_cap = p->leaf_cap = 0;
        return xyl__text_fail(&p->txt, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for the skeleton");
    }
    p->nodes = n;
    p->leaves = l;
    return XYL_OK;
}

/* ---- record sequence ----------------------------------------------------------------------- */

/* The stage after a node or leaf record: more nodes, then leaves, then 'end'. */
static stage body_stage(const parser *p)
{
    if (p->node_count < p->node_total) return STAGE_NODES;
    if (p->leaf_count < p->leaf_total) return STAGE_LEAVES;
    return STAGE_END;
}

static xyl_result parse_body_record(parser *p, const xyl__token *kw)
{
    char buf[40];
    if (xyl__token_is(kw, "n")) {
        if (p->stage != STAGE_NODES)
            return xyl__text_fail(&p->txt, XYL_ERR_PARSE, kw->col,
                                  "more node records than the %zu announced", p->node_total);
        return parse_node(p);
    }
    if (xyl__token_is(kw, "l")) {
        if (p->stage == STAGE_NODES)
            return xyl__text_fail(&p->txt, XYL_ERR_PARSE, kw->col,
                                  "a leaf record after %zu of the %zu nodes; all nodes come first",
                                  p->node_count, p->node_total);
        if (p->stage != STAGE_LEAVES)
            return xyl__text_fail(&p->txt, XYL_ERR_PARSE, kw->col,
                                  "more leaf records than the %zu announced", p->leaf_total);
        return parse_leaf(p);
    }
    if (xyl__token_is(kw, "end")) {
        if (p->stage != STAGE_END)
            return xyl__text_fail(&p->txt, XYL_ERR_TRUNCATED, kw->col,
                                  "'end' after %zu of %zu nodes and %zu of %zu leaves",
                                  p->node_count, p->node_total, p->leaf_count, p->leaf_total);
        return need_record_end(p);
    }
    return xyl__text_fail(&p->txt, XYL_ERR_PARSE, kw->col,
                          "unknown record '%s'; expected 'n', 'l' or 'end'",
                          xyl__text_show(kw, SHOW_CHARS, buf));
}

static xyl_result parse_record(parser *p, const xyl__token *kw)
{
    xyl_result r;
    p->txt.index = -1;
    switch (p->stage) {
    case STAGE_HEADER:
        r = parse_header(p, kw);
        break;
    case STAGE_NODE_COUNT:
        r = parse_count(p, kw, "nodes", p->max_nodes, &p->node_total);
        break;
    case STAGE_LEAF_COUNT:
        r = parse_count(p, kw, "leaves", p->max_leaves, &p->leaf_total);
        if (r == XYL_OK) r = reserve(p);
        break;
    case STAGE_DONE:
        return xyl__text_fail(&p->txt, XYL_ERR_PARSE, kw->col, "text after 'end'");
    default:
        r = parse_body_record(p, kw);
        if (r == XYL_OK && p->stage == STAGE_END) p->stage = STAGE_DONE;
        else if (r == XYL_OK) p->stage = body_stage(p);
        return r;
    }
    if (r == XYL_OK)
        p->stage = p->stage == STAGE_LEAF_COUNT ? body_stage(p) : (stage)(p->stage + 1);
    return r;
}

/* Where the text ends: the line after a final line break, else just past the last line. */
static xyl_result fail_at_eof(parser *p)
{
    static const char *const what[] = {
        [STAGE_HEADER] = "before 'xylem-skeleton 1'",
        [STAGE_NODE_COUNT] = "before 'nodes <count>'",
        [STAGE_LEAF_COUNT] = "before 'leaves <count>'",
        [STAGE_NODES] = "before all announced nodes",
        [STAGE_LEAVES] = "before all announced leaves",
        [STAGE_END] = "without 'end'",
        [STAGE_DONE] = "",
    };
    uint32_t col = 1;
    if (p->txt.size > 0 && p->txt.text[p->txt.size - 1] != '\n')
        col = xyl__to_u32(p->txt.len + 1);
    else if (p->txt.line_no < UINT32_MAX)
        ++p->txt.line_no;
    p->txt.index = -1;
    return xyl__text_fail(&p->txt, XYL_ERR_TRUNCATED, col,
                          "the text ends %s (%zu of %zu nodes, %zu of %zu "
                          "leaves read)",
                          what[p->stage], p->node_count, p->node_total, p->leaf_count,
                          p->leaf_total);
}

static xyl_result parse_all(parser *p)
{
    for (;;) {
        xyl__token kw = {NULL, 0, 0};
        bool eof = false;
        xyl_result r = next_record(p, &kw, &eof);
        if (r != XYL_OK) return r;
        if (eof) return p->stage == STAGE_DONE ? XYL_OK : fail_at_eof(p);
        r = parse_record(p, &kw);
        if (r != XYL_OK) return r;
    }
}

static void init_parser(parser *p, const char *text, size_t length,
                        const xyl_skeleton_read_desc *desc, xyl_diag *diag)
{
    memset(p, 0, sizeof *p);
    xyl__text_init(&p->txt, text, length, diag);
    p->stage = STAGE_HEADER;
    if (desc) {
        p->alloc = desc->alloc;
        p->limits = desc->limits;
    }
    p->max_nodes = p->limits.max_nodes ? p->limits.max_nodes : XYL__SKEL_DEFAULT_MAX_NODES;
    p->max_leaves = p->limits.max_leaves ? p->limits.max_leaves : XYL__SKEL_DEFAULT_MAX_LEAVES;
    /* Parent ids are int32_t, and the arrays' byte sizes must fit in a size_t. */
    if (p->max_nodes > INT32_MAX) p->max_nodes = INT32_MAX;
    if (p->max_nodes > SIZE_MAX / sizeof(xyl_skel_node)) p->max_nodes = SIZE_MAX / sizeof(xyl_skel_node);
    if (p->max_leaves > SIZE_MAX / sizeof(xyl_skel_leaf))
        p->max_leaves = SIZE_MAX / sizeof(xyl_skel_leaf);
}

/* The exponent of a vector's largest coordinate: floats there are spaced 2^(e - 23). */
static int magnitude(const double v[3])
{
    double m = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
    return m > 0.0 ? ilogb(m) : INT32_MIN;
}

/* The origin: the first node's position where that keeps every node's float position at least
 * as fine as at (0, 0, 0) and makes some other node's finer (a tree far from the world's origin:
 * floats would round it), else 0 (a tree at the origin, or a forest spread around it, reads as it
 * always did). Then every position becomes a float relative to it. */
static void choose_origin(parser *p)
{
    const double *w0 = p->node_world;
    bool some_finer = false, none_coarser = p->node_count > 0;
    for (size_t i = 1; i < p->node_count && none_coarser; ++i) {
        const double *w = p->node_world + 3 * i;
        const double d[3] = {w[0] - w0[0], w[1] - w0[1], w[2] - w0[2]};
        int near = magnitude(d), far = magnitude(w);
        if (near > far || fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2]))) > FLT_MAX)
            none_coarser = false;
        some_finer = some_finer || near < far;
    }
    for (size_t i = 0; i < p->leaf_count && none_coarser && some_finer; ++i) {
        const double *w = p->leaf_world + 3 * i; /* leaves must stay in a float's range too */
        for (int k = 0; k < 3; ++k) none_coarser = none_coarser && fabs(w[k] - w0[k]) <= FLT_MAX;
    }
    if (none_coarser && some_finer) memcpy(p->origin, w0, sizeof p->origin);
    for (size_t i = 0; i < p->node_count; ++i) {
        const double *w = p->node_world + 3 * i;
        p->nodes[i].pos = (xyl_vec3){(float)(w[0] - p->origin[0]), (float)(w[1] - p->origin[1]),
                                     (float)(w[2] - p->origin[2])};
    }
    for (size_t i = 0; i < p->leaf_count; ++i) {
        const double *w = p->leaf_world + 3 * i;
        p->leaves[i].pos = (xyl_vec3){(float)(w[0] - p->origin[0]), (float)(w[1] - p->origin[1]),
                                      (float)(w[2] - p->origin[2])};
    }
}

/* Runs the same validation as xyl_skeleton_create and derives branches the same way. */
static xyl_result build(parser *p, xyl_skeleton **out)
{
    choose_origin(p);
    xyl_skeleton_desc d;
    memset(&d, 0, sizeof d);
    d.nodes = p->nodes;
    d.node_count = p->node_count;
    d.leaves = p->leaves;
    d.leaf_count = p->leaf_count;
    d.limits = p->limits;
    d.alloc = p->alloc;
    memcpy(d.origin, p->origin, sizeof d.origin);
    xyl_result r = xyl__skeleton_validate(&d, p->txt.diag);
    if (r != XYL_OK) {
        xyl__free(&p->alloc, p->nodes);
        xyl__free(&p->alloc, p->leaves);
        return r;
    }
    r = xyl__skeleton_adopt(p->nodes, p->node_count, p->leaves, p->leaf_count, p->origin,
                            &p->alloc, out, p->txt.diag);
    if (r == XYL_OK)
        xyl__skeleton_warn_precision((*out)->nodes, (*out)->node_count, "the skeleton",
                                     p->txt.diag);
    return r;
}

xyl_result xyl_skeleton_read_text(const char *text, size_t length,
                                  const xyl_skeleton_read_desc *desc, xyl_skeleton **out,
                                  xyl_diag *diag)
{
    if (!out || (!text && length))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "out must not be NULL, nor text when length is not 0");
    parser p;
    init_parser(&p, text, length, desc, diag);
    xyl_result r = parse_all(&p);
    if (r == XYL_OK) {
        r = build(&p, out);
    } else {
        xyl__free(&p.alloc, p.nodes);
        xyl__free(&p.alloc, p.leaves);
    }
    xyl__free(&p.alloc, p.node_world);
    xyl__free(&p.alloc, p.leaf_world);
    return r;
}

xyl_result xyl_skeleton_read_file(const char *path, const xyl_skeleton_read_desc *desc,
                                  xyl_skeleton **out, xyl_diag *diag)
{
    if (!path || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "path and out must not be NULL");
    xyl_allocator a = {NULL, NULL, NULL};
    if (desc) a = desc->alloc;
    char *text = NULL;
    size_t size = 0;
    xyl_result r = xyl__read_file(path, MAX_FILE_BYTES, &a, &text, &size, diag);
    if (r != XYL_OK) return r;
    r = xyl_skeleton_read_text(text, size, desc, out, diag);
    xyl__free(&a, text);
    return r;
}

/* ==== writers =============================================================================== */

/* Counts bytes, and also stores them when buf is set (the caller sized it by a counting pass). */
typedef struct sink {
    char *buf;
    size_t len;
    bool overflow; /* the text would not fit in a size_t (with its NUL) */
} sink;

static void put(sink *s, const char *text, size_t n)
{
    if (s->overflow || n > SIZE_MAX - 1 - s->len) {
        s->overflow = true;
        return;
    }
    if (s->buf) memcpy(s->buf + s->len, text, n);
    s->len += n;
}

static void put_str(sink *s, const char *text)
{
    put(s, text, strlen(text));
}

static void put_int(sink *s, long long v)
{
    char b[32];
    int n = snprintf(b, sizeof b, " %lld", v);
    put(s, b, (size_t)n);
}

/* " " and the shortest text that reads back as the same float (float_text.h), with '.' as
 * decimal point whatever the locale. */
static void put_float(sink *s, float v)
{
    char out[1 + XYL__FLOAT_TEXT_MAX];
    out[0] = ' ';
    put(s, out, 1 + xyl__float_text(v, out + 1));
}

static void put_vec3(sink *s, xyl_vec3 v)
{
    put_float(s, v.x);
    put_float(s, v.y);
    put_float(s, v.z);
}

/* A position in world coordinates. With origin 0 the float itself, as before origins existed;
 * else origin + v summed in double, as the shortest text that reads back as that double. */
static void put_position(sink *s, const double origin[3], xyl_vec3 v)
{
    if (origin[0] == 0.0 && origin[1] == 0.0 && origin[2] == 0.0) {
        put_vec3(s, v);
        return;
    }
    const float c[3] = {v.x, v.y, v.z};
    for (int k = 0; k < 3; ++k) {
        char out[1 + XYL__DOUBLE_TEXT_MAX];
        out[0] = ' ';
        put(s, out, 1 + xyl__double_text(origin[k] + (double)c[k], out + 1));
    }
}

static void render_skel(const xyl_skeleton *sk, sink *s)
{
    put_str(s, "xylem-skeleton");
    put_int(s, SKEL_VERSION);
    put_str(s, "\nnodes");
    put_int(s, (long long)sk->node_count);
    put_str(s, "\nleaves");
    put_int(s, (long long)sk->leaf_count);
    put_str(s, "\n");
    for (size_t i = 0; i < sk->node_count && !s->overflow; ++i) {
        const xyl_skel_node *n = &sk->nodes[i];
        put_str(s, "n");
        put_int(s, (long long)i);
        put_int(s, n->parent);
        put_position(s, sk->origin, n->pos);
        put_float(s, n->radius);
        put_str(s, "\n");
    }
    for (size_t i = 0; i < sk->leaf_count && !s->overflow; ++i) {
        const xyl_skel_leaf *l = &sk->leaves[i];
        put_str(s, "l");
        put_int(s, l->node);
        put_position(s, sk->origin, l->pos);
        put_vec3(s, l->heading);
        put_vec3(s, l->left);
        put_vec3(s, l->up);
        put_float(s, l->size);
        put_str(s, "\n");
    }
    put_str(s, "end\n");
}

/* One vertex per node, one two-point polyline per segment; OBJ has no leaf primitive, so
 * leaves are only counted in the header comment. */
static void render_obj(const xyl_skeleton *sk, sink *s)
{
    size_t segments = 0;
    for (size_t i = 0; i < sk->node_count; ++i) segments += sk->nodes[i].parent >= 0;
    put_str(s, "# xylem skeleton: nodes");
    put_int(s, (long long)sk->node_count);
    put_str(s, ", segments");
    put_int(s, (long long)segments);
    put_str(s, ", leaves");
    put_int(s, (long long)sk->leaf_count);
    put_str(s, " (leaves are not written to OBJ)\n");
    for (size_t i = 0; i < sk->node_count && !s->overflow; ++i) {
        put_str(s, "v");
        put_position(s, sk->origin, sk->nodes[i].pos);
        put_str(s, "\n");
    }
    for (size_t i = 0; i < sk->node_count && !s->overflow; ++i) {
        if (sk->nodes[i].parent < 0) continue;
        put_str(s, "l");
        put_int(s, (long long)sk->nodes[i].parent + 1);
        put_int(s, (long long)i + 1);
        put_str(s, "\n");
    }
}

/* The view is public, so it is checked like a desc: the writers index and print it. */
static xyl_result check_view(const xyl_skeleton *sk, xyl_diag *diag)
{
    return xyl__skeleton_check_view(sk, diag);
}

static bool format_ok(xyl_skel_format format)
{
    return format == XYL_SKEL_FORMAT_SKEL || format == XYL_SKEL_FORMAT_OBJ;
}

static void render(const xyl_skeleton *sk, xyl_skel_format format, sink *s)
{
    if (format == XYL_SKEL_FORMAT_OBJ) render_obj(sk, s);
    else render_skel(sk, s);
}

xyl_result xyl_skeleton_write_text(const xyl_skeleton *skeleton, xyl_skel_format format,
                                   char *buffer, size_t capacity, size_t *needed)
{
    if (!skeleton || !format_ok(format) || (!buffer && !needed)) return XYL_ERR_INVALID_ARGUMENT;
    xyl_result r = check_view(skeleton, NULL);
    if (r != XYL_OK) return r;
    sink count = {NULL, 0, false};
    render(skeleton, format, &count);
    if (count.overflow) return XYL_ERR_OUT_OF_MEMORY;
    if (needed) *needed = count.len;
    if (!buffer) return XYL_OK;
    if (capacity <= count.len) return XYL_ERR_INVALID_ARGUMENT;
    sink fill = {buffer, 0, false};
    render(skeleton, format, &fill);
    buffer[fill.len] = '\0';
    return XYL_OK;
}

xyl_result xyl_skeleton_write_file(const xyl_skeleton *skeleton, const char *path,
                                   xyl_skel_format format, const xyl_allocator *alloc,
                                   xyl_diag *diag)
{
    if (!skeleton || !path || !*path || !format_ok(format))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "skeleton and path must be given and the format must be SKEL or OBJ");
    xyl_result r = check_view(skeleton, diag);
    if (r != XYL_OK) return r;
    size_t size = 0;
    r = xyl_skeleton_write_text(skeleton, format, NULL, 0, &size);
    if (r != XYL_OK) return xyl__fail(diag, r, 0, 0, -1, "the text would not fit in memory");
    char *text = xyl__alloc(alloc, size + 1);
    if (!text)
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for %zu bytes",
                         size + 1);
    r = xyl_skeleton_write_text(skeleton, format, text, size + 1, &size);
    if (r == XYL_OK) r = xyl__write_file_atomic(path, text, size, alloc, diag);
    xyl__free(alloc, text);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}
