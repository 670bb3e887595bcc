/* The .skel text format (docs/skeleton-format.md) and the OBJ polyline export.
 *
 * The reader is strict and line based: every error names a 1-based line and column. Neither
 * direction depends on the C locale: numbers are parsed here rather than with strtod, and the
 * writer prints them with float_text.h. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "float_text.h"
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
/* Significant digits kept when parsing a number: exact in a uint64_t, and ten more than a
 * float needs, so dropping the rest cannot change the nearest float. */
#define MAX_SIGNIFICANT_DIGITS 19
/* |decimal exponent| beyond which every non-zero float is 0 or infinite. */
#define MAX_DECIMAL_EXPONENT 400
/* Written exponents saturate here: far beyond MAX_DECIMAL_EXPONENT, yet adding the digit
 * count of any text that fits in memory cannot overflow an int64_t. */
#define MAX_EXPONENT_DIGITS_VALUE (INT64_C(1) << 56)

/* ==== reader ================================================================================ */

typedef struct token {
    const char *s;
    size_t n;
    uint32_t col; /* 1-based */
} token;

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
    const char *text;
    size_t length;
    size_t next;          /* offset of the next line */
    uint32_t line_no;     /* 1-based number of the current line (saturates) */
    const char *line;     /* the current line without its LF / CRLF */
    size_t line_len;
    size_t cur;           /* cursor in the current line */
    size_t last_end;      /* offset just past the last token of the current line */
    int64_t index;        /* the node or leaf being read, -1 outside records */
    stage stage;
    xyl_diag *diag;
    xyl_allocator alloc;
    xyl_skeleton_limits limits;
    uint64_t max_nodes, max_leaves;
    size_t node_total, leaf_total; /* announced */
    xyl_skel_node *nodes;
    size_t node_cap, node_count;
    xyl_skel_leaf *leaves;
    size_t leaf_cap, leaf_count;
} parser;

static uint32_t to_u32(size_t v)
{
    return v > UINT32_MAX ? UINT32_MAX : (uint32_t)v;
}

static bool is_blank(char c)
{
    return c == ' ' || c == '\t';
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static bool tok_is(const token *t, const char *word)
{
    size_t n = strlen(word);
    return t->n == n && memcmp(t->s, word, n) == 0;
}

/* ASCII-only on purpose: tolower() would depend on the locale. */
static bool ieq(const char *s, size_t n, const char *lower_word)
{
    size_t k = strlen(lower_word);
    if (n != k) return false;
    for (size_t i = 0; i < n; ++i) {
        char c = s[i] >= 'A' && s[i] <= 'Z' ? (char)(s[i] - 'A' + 'a') : s[i];
        if (c != lower_word[i]) return false;
    }
    return true;
}

/* A token for a message: non-printable bytes shown as '?', long tokens cut. */
static const char *show(const token *t, char out[40])
{
    size_t n = t->n > 24 ? 24 : t->n;
    for (size_t i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)t->s[i];
        out[i] = c >= 0x20 && c < 0x7f ? (char)c : '?';
    }
    strcpy(out + n, t->n > n ? "..." : "");
    return out;
}

static xyl_result fail_at(parser *p, xyl_result code, uint32_t col, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static xyl_result fail_at(parser *p, xyl_result code, uint32_t col, const char *fmt, ...)
{
    char msg[XYL_DIAG_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    xyl__fail(p->diag, code, p->line_no, col, p->index, "%s", msg);
    return code;
}

/* Moves to the next line; false at the end of the text. A final line without a line break
 * counts, and a trailing LF does not open an empty last line. */
static bool next_line(parser *p)
{
    if (p->next >= p->length) return false;
    const char *start = p->text + p->next;
    size_t left = p->length - p->next;
    const char *lf = memchr(start, '\n', left);
    size_t len = lf ? (size_t)(lf - start) : left;
    p->next += lf ? len + 1 : len;
    if (len > 0 && start[len - 1] == '\r') --len;
    p->line = start;
    p->line_len = len;
    p->cur = 0;
    p->last_end = 0;
    if (p->line_no < UINT32_MAX) ++p->line_no;
    return true;
}

/* The next token of the current line; '#' starts a comment that runs to the line's end. */
static bool next_token(parser *p, token *t)
{
    while (p->cur < p->line_len && is_blank(p->line[p->cur])) ++p->cur;
    if (p->cur >= p->line_len || p->line[p->cur] == '#') {
        p->cur = p->line_len;
        return false;
    }
    size_t start = p->cur;
    while (p->cur < p->line_len && !is_blank(p->line[p->cur]) && p->line[p->cur] != '#') ++p->cur;
    t->s = p->line + start;
    t->n = p->cur - start;
    t->col = to_u32(start + 1);
    p->last_end = p->cur;
    return true;
}

static xyl_result need_token(parser *p, token *t, const char *what)
{
    if (next_token(p, t)) return XYL_OK;
    return fail_at(p, XYL_ERR_PARSE, to_u32(p->last_end + 1), "the line ends where %s was expected",
                   what);
}

static xyl_result need_record_end(parser *p)
{
    token t = {0};
    char buf[40];
    if (!next_token(p, &t)) return XYL_OK;
    return fail_at(p, XYL_ERR_PARSE, t.col, "unexpected '%s' after the end of the record",
                   show(&t, buf));
}

/* The first token of the next line that has one; *eof at the end of the text. */
static xyl_result next_record(parser *p, token *keyword, bool *eof)
{
    for (;;) {
        if (!next_line(p)) {
            *eof = true;
            return XYL_OK;
        }
        const char *nul = memchr(p->line, '\0', p->line_len);
        if (nul)
            return fail_at(p, XYL_ERR_PARSE, to_u32((size_t)(nul - p->line) + 1),
                           "a NUL byte; .skel files are text");
        if (next_token(p, keyword)) {
            *eof = false;
            return XYL_OK;
        }
    }
}

/* ---- numbers ------------------------------------------------------------------------------- */

/* Decimal digits only. Saturates at UINT64_MAX so an absurd count reads as "too many". */
static bool parse_u64(const char *s, size_t n, uint64_t *out)
{
    if (n == 0) return false;
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!is_digit(s[i])) return false;
        unsigned d = (unsigned)(s[i] - '0');
        v = v > (UINT64_MAX - d) / 10 ? UINT64_MAX : v * 10 + d;
    }
    *out = v;
    return true;
}

/* An optional '-' and decimal digits, saturating at the int64_t range. */
static bool parse_i64(const token *t, int64_t *out)
{
    size_t skip = t->n > 0 && t->s[0] == '-' ? 1 : 0;
    bool neg = skip == 1;
    uint64_t v;
    if (!parse_u64(t->s + skip, t->n - skip, &v)) return false;
    if (v > (uint64_t)INT64_MAX) *out = neg ? INT64_MIN : INT64_MAX;
    else *out = neg ? -(int64_t)v : (int64_t)v;
    return true;
}

typedef enum num_status { NUM_OK, NUM_BAD, NUM_NON_FINITE, NUM_TOO_LARGE } num_status;

typedef struct decimal {
    uint64_t mant;   /* significant digits */
    int digits;      /* how many are in mant */
    int64_t exp10;   /* value = mant * 10^exp10 */
    bool any;        /* a digit was seen */
} decimal;

static void add_digit(decimal *d, char c, bool fraction)
{
    unsigned v = (unsigned)(c - '0');
    d->any = true;
    if (d->mant == 0 && v == 0) {
        d->exp10 -= fraction; /* leading zeros are not significant */
    } else if (d->digits < MAX_SIGNIFICANT_DIGITS) {
        d->mant = d->mant * 10 + v;
        d->digits++;
        d->exp10 -= fraction;
    } else {
        d->exp10 += !fraction; /* a dropped integer digit still scales the value */
    }
}

/* Parses digits [. digits] [e [+-] digits] from s[*i]; false on a malformed exponent. */
static bool parse_decimal(const char *s, size_t n, size_t *i, decimal *d)
{
    for (; *i < n && is_digit(s[*i]); ++*i) add_digit(d, s[*i], false);
    if (*i < n && s[*i] == '.')
        for (++*i; *i < n && is_digit(s[*i]); ++*i) add_digit(d, s[*i], true);
    if (*i >= n || (s[*i] != 'e' && s[*i] != 'E')) return true;
    ++*i;
    bool neg = *i < n && s[*i] == '-';
    if (*i < n && (s[*i] == '-' || s[*i] == '+')) ++*i;
    if (*i >= n || !is_digit(s[*i])) return false;
    int64_t e = 0;
    for (; *i < n && is_digit(s[*i]); ++*i)
        if (e < MAX_EXPONENT_DIGITS_VALUE) e = e * 10 + (s[*i] - '0');
    d->exp10 += neg ? -e : e;
    return true;
}

static bool is_non_finite_word(const char *s, size_t n)
{
    return ieq(s, n, "nan") || ieq(s, n, "inf") || ieq(s, n, "infinity") ||
           (n >= 4 && ieq(s, 4, "nan(") && s[n - 1] == ')');
}

/* [+-] (digits [. digits*] | . digits) [(e|E) [+-] digits], nearest float. Accurate enough
 * (a few double ulps) that every value the writer or "%.9g" prints comes back as the same float. */
static num_status parse_real(const token *t, float *out)
{
    size_t i = 0;
    bool neg = t->n > 0 && t->s[0] == '-';
    if (t->n > 0 && (t->s[0] == '-' || t->s[0] == '+')) i = 1;
    if (is_non_finite_word(t->s + i, t->n - i)) return NUM_NON_FINITE;
    decimal d = {0, 0, 0, false};
    if (!parse_decimal(t->s, t->n, &i, &d) || !d.any || i != t->n) return NUM_BAD;
    double v = 0.0;
    if (d.mant != 0 && d.exp10 > MAX_DECIMAL_EXPONENT) return NUM_TOO_LARGE;
    if (d.mant != 0 && d.exp10 >= -MAX_DECIMAL_EXPONENT) {
        /* 10^k is exact up to k = 22: dividing by it rounds once, multiplying by the inexact
         * 10^-k would round twice. */
        v = d.exp10 < 0 ? (double)d.mant / pow(10.0, (double)-d.exp10)
                        : (double)d.mant * pow(10.0, (double)d.exp10);
    }
    /* A double up to FLT_MAX + half an ulp still rounds to FLT_MAX; from there on to inf. */
    if (!(v < (double)FLT_MAX + ldexp(1.0, 103))) return NUM_TOO_LARGE;
    if (v > FLT_MAX) v = FLT_MAX;
    *out = (float)(neg ? -v : v);
    return NUM_OK;
}

/* ---- records ------------------------------------------------------------------------------- */

static xyl_result real_field(parser *p, const char *what, float *out, uint32_t *col)
{
    token t = {0};
    char buf[40];
    xyl_result r = need_token(p, &t, what);
    if (r != XYL_OK) return r;
    if (col) *col = t.col;
    switch (parse_real(&t, out)) {
    case NUM_OK:
        return XYL_OK;
    case NUM_NON_FINITE:
        return fail_at(p, XYL_ERR_NON_FINITE, t.col, "%s is '%s'; numbers must be finite", what,
                       show(&t, buf));
    case NUM_TOO_LARGE:
        return fail_at(p, XYL_ERR_NON_FINITE, t.col, "%s '%s' is too large for a float", what,
                       show(&t, buf));
    default:
        return fail_at(p, XYL_ERR_PARSE, t.col, "%s '%s' is not a number", what, show(&t, buf));
    }
}

static xyl_result vec3_field(parser *p, const char *what, xyl_vec3 *v)
{
    float *c[3] = {&v->x, &v->y, &v->z};
    char name[48];
    for (int k = 0; k < 3; ++k) {
        snprintf(name, sizeof name, "%s %c", what, "xyz"[k]);
        xyl_result r = real_field(p, name, c[k], NULL);
        if (r != XYL_OK) return r;
    }
    return XYL_OK;
}

static xyl_result int_field(parser *p, const char *what, int64_t *out, uint32_t *col)
{
    token t = {0};
    char buf[40];
    xyl_result r = need_token(p, &t, what);
    if (r != XYL_OK) return r;
    *col = t.col;
    if (parse_i64(&t, out)) return XYL_OK;
    return fail_at(p, XYL_ERR_PARSE, t.col, "%s '%s' is not an integer", what, show(&t, buf));
}

static xyl_result node_id(parser *p)
{
    token t = {0};
    char buf[40];
    uint64_t id;
    xyl_result r = need_token(p, &t, "the node id");
    if (r != XYL_OK) return r;
    if (!parse_u64(t.s, t.n, &id))
        return fail_at(p, XYL_ERR_PARSE, t.col, "node id '%s' is not an unsigned integer",
                       show(&t, buf));
    if (id != (uint64_t)p->node_count)
        return fail_at(p, XYL_ERR_PARSE, t.col,
                       "node id %s is out of order: ids count 0, 1, 2, ... so %zu belongs here",
                       show(&t, buf), p->node_count);
    return XYL_OK;
}

static xyl_result push_node(parser *p, const xyl_skel_node *n)
{
    void *arr = p->nodes;
    if (!xyl__grow(&p->alloc, &arr, &p->node_cap, p->node_count, p->node_count + 1, sizeof *n))
        return fail_at(p, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for %zu nodes", p->node_total);
    p->nodes = arr;
    p->nodes[p->node_count++] = *n;
    return XYL_OK;
}

static xyl_result push_leaf(parser *p, const xyl_skel_leaf *l)
{
    void *arr = p->leaves;
    if (!xyl__grow(&p->alloc, &arr, &p->leaf_cap, p->leaf_count, p->leaf_count + 1, sizeof *l))
        return fail_at(p, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for %zu leaves", p->leaf_total);
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
    p->index = (int64_t)p->node_count;
    xyl_result r = node_id(p);
    if (r == XYL_OK) r = int_field(p, "the parent id", &parent, &col);
    if (r != XYL_OK) return r;
    if (parent < -1 || parent >= (int64_t)p->node_count)
        return fail_at(p, XYL_ERR_INVALID_SKELETON, col,
                       "node %zu has parent %lld; a parent must come before its child "
                       "(or be -1 for a root)",
                       p->node_count, (long long)parent);
    n.parent = (int32_t)parent;
    r = vec3_field(p, "the node position", &n.pos);
    if (r == XYL_OK) r = real_field(p, "the node radius", &n.radius, &col);
    if (r != XYL_OK) return r;
    if (!(n.radius > 0.0f))
        return fail_at(p, XYL_ERR_INVALID_SKELETON, col, "node %zu has radius %g; radii must be > 0",
                       p->node_count, (double)n.radius);
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
    p->index = (int64_t)p->leaf_count;
    xyl_result r = int_field(p, "the leaf's node", &node, &col);
    if (r != XYL_OK) return r;
    if (node < -1 || node >= (int64_t)p->node_count)
        return fail_at(p, XYL_ERR_INVALID_SKELETON, col,
                       "leaf %zu hangs from node %lld, which does not exist", p->leaf_count,
                       (long long)node);
    l.node = (int32_t)node;
    r = vec3_field(p, "the leaf position", &l.pos);
    if (r == XYL_OK) r = vec3_field(p, "the leaf heading", &l.heading);
    if (r == XYL_OK) r = vec3_field(p, "the leaf left vector", &l.left);
    if (r == XYL_OK) r = vec3_field(p, "the leaf up vector", &l.up);
    if (r == XYL_OK) r = real_field(p, "the leaf size", &l.size, &col);
    if (r != XYL_OK) return r;
    if (!(l.size > 0.0f))
        return fail_at(p, XYL_ERR_INVALID_SKELETON, col, "leaf %zu has size %g; sizes must be > 0",
                       p->leaf_count, (double)l.size);
    r = need_record_end(p);
    return r == XYL_OK ? push_leaf(p, &l) : r;
}

/* ---- header and counts --------------------------------------------------------------------- */

static xyl_result parse_header(parser *p, const token *kw)
{
    token t = {0};
    char buf[40];
    uint64_t version;
    if (!tok_is(kw, "xylem-skeleton"))
        return fail_at(p, XYL_ERR_PARSE, kw->col,
                       "not a .skel file: found '%s' where 'xylem-skeleton %d' must come first",
                       show(kw, buf), SKEL_VERSION);
    xyl_result r = need_token(p, &t, "the format version");
    if (r != XYL_OK) return r;
    if (!parse_u64(t.s, t.n, &version))
        return fail_at(p, XYL_ERR_PARSE, t.col, "format version '%s' is not a number",
                       show(&t, buf));
    if (version != SKEL_VERSION)
        return fail_at(p, XYL_ERR_UNSUPPORTED, t.col,
                       "format version %s is not supported; this build reads version %d",
                       show(&t, buf), SKEL_VERSION);
    return need_record_end(p);
}

/* "<word> <count>"; the limit is checked here, before anything is allocated. */
static xyl_result parse_count(parser *p, const token *kw, const char *word, uint64_t max,
                              size_t *out)
{
    token t = {0};
    char buf[40];
    uint64_t v;
    if (!tok_is(kw, word))
        return fail_at(p, XYL_ERR_PARSE, kw->col, "expected '%s <count>', found '%s'", word,
                       show(kw, buf));
    xyl_result r = need_token(p, &t, "a count");
    if (r != XYL_OK) return r;
    if (!parse_u64(t.s, t.n, &v))
        return fail_at(p, XYL_ERR_PARSE, t.col, "%s count '%s' is not an unsigned integer", word,
                       show(&t, buf));
    if (v > max)
        return fail_at(p, XYL_ERR_LIMIT_EXCEEDED, t.col, "%s %s exceeds the limit of %llu", word,
                       show(&t, buf), (unsigned long long)max);
    *out = (size_t)v;
    return need_record_end(p);
}

/* Reserves what the announced counts need, but never more than the rest of the text can hold:
 * a short text announcing millions of nodes must not allocate for them. */
static xyl_result reserve(parser *p)
{
    size_t left = p->length - p->next;
    size_t nodes = left / MIN_NODE_RECORD_BYTES + 1;
    size_t leaves = left / MIN_LEAF_RECORD_BYTES + 1;
    void *n = NULL, *l = NULL;
    if (nodes > p->node_total) nodes = p->node_total ? p->node_total : 1;
    if (leaves > p->leaf_total) leaves = p->leaf_total ? p->leaf_total : 1;
    if (!xyl__grow(&p->alloc, &n, &p->node_cap, 0, nodes, sizeof *p->nodes) ||
        !xyl__grow(&p->alloc, &l, &p->leaf_cap, 0, leaves, sizeof *p->leaves)) {
        xyl__free(&p->alloc, n);
        p->node_cap = p->leaf_cap = 0;
        return fail_at(p, XYL_ERR_OUT_OF_MEMORY, 0, "out of memory for the skeleton");
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

static xyl_result parse_body_record(parser *p, const token *kw)
{
    char buf[40];
    if (tok_is(kw, "n")) {
        if (p->stage != STAGE_NODES)
            return fail_at(p, XYL_ERR_PARSE, kw->col, "more node records than the %zu announced",
                           p->node_total);
        return parse_node(p);
    }
    if (tok_is(kw, "l")) {
        if (p->stage == STAGE_NODES)
            return fail_at(p, XYL_ERR_PARSE, kw->col,
                           "a leaf record after %zu of the %zu nodes; all nodes come first",
                           p->node_count, p->node_total);
        if (p->stage != STAGE_LEAVES)
            return fail_at(p, XYL_ERR_PARSE, kw->col, "more leaf records than the %zu announced",
                           p->leaf_total);
        return parse_leaf(p);
    }
    if (tok_is(kw, "end")) {
        if (p->stage != STAGE_END)
            return fail_at(p, XYL_ERR_TRUNCATED, kw->col,
                           "'end' after %zu of %zu nodes and %zu of %zu leaves", p->node_count,
                           p->node_total, p->leaf_count, p->leaf_total);
        return need_record_end(p);
    }
    return fail_at(p, XYL_ERR_PARSE, kw->col, "unknown record '%s'; expected 'n', 'l' or 'end'",
                   show(kw, buf));
}

static xyl_result parse_record(parser *p, const token *kw)
{
    xyl_result r;
    p->index = -1;
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
        return fail_at(p, XYL_ERR_PARSE, kw->col, "text after 'end'");
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
    if (p->length > 0 && p->text[p->length - 1] != '\n') col = to_u32(p->line_len + 1);
    else if (p->line_no < UINT32_MAX) ++p->line_no;
    p->index = -1;
    return fail_at(p, XYL_ERR_TRUNCATED, col, "the text ends %s (%zu of %zu nodes, %zu of %zu "
                   "leaves read)", what[p->stage], p->node_count, p->node_total, p->leaf_count,
                   p->leaf_total);
}

static xyl_result parse_all(parser *p)
{
    for (;;) {
        token kw = {NULL, 0, 0};
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
    p->text = text;
    p->length = length;
    p->diag = diag;
    p->index = -1;
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

/* Runs the same validation as xyl_skeleton_create and derives branches the same way. */
static xyl_result build(parser *p, xyl_skeleton **out)
{
    xyl_skeleton_desc d;
    memset(&d, 0, sizeof d);
    d.nodes = p->nodes;
    d.node_count = p->node_count;
    d.leaves = p->leaves;
    d.leaf_count = p->leaf_count;
    d.limits = p->limits;
    d.alloc = p->alloc;
    xyl_result r = xyl__skeleton_validate(&d, p->diag);
    if (r != XYL_OK) {
        xyl__free(&p->alloc, p->nodes);
        xyl__free(&p->alloc, p->leaves);
        return r;
    }
    return xyl__skeleton_adopt(p->nodes, p->node_count, p->leaves, p->leaf_count, &p->alloc, out,
                               p->diag);
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
    if (r == XYL_OK) return build(&p, out);
    xyl__free(&p.alloc, p.nodes);
    xyl__free(&p.alloc, p.leaves);
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
        put_vec3(s, n->pos);
        put_float(s, n->radius);
        put_str(s, "\n");
    }
    for (size_t i = 0; i < sk->leaf_count && !s->overflow; ++i) {
        const xyl_skel_leaf *l = &sk->leaves[i];
        put_str(s, "l");
        put_int(s, l->node);
        put_vec3(s, l->pos);
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
        put_vec3(s, sk->nodes[i].pos);
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
    xyl_skeleton_desc d;
    memset(&d, 0, sizeof d);
    d.nodes = sk->nodes;
    d.node_count = sk->node_count;
    d.leaves = sk->leaves;
    d.leaf_count = sk->leaf_count;
    d.limits.max_nodes = UINT64_MAX;
    d.limits.max_leaves = UINT64_MAX;
    return xyl__skeleton_validate(&d, diag);
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
