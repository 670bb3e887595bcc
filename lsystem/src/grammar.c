/* Grammar text to a compiled xyl_grammar: header directives, the axiom, productions with
 * contexts, conditions, weights and parametric successors (docs/lsystem.md). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsys_parse.h"

#define HARD_MAX_EXPR_DEPTH 1024u
#define DEFAULT_DEPTH 4u
#define DEFAULT_ANGLE_DEG 25.0

void xyl__lsys_resolve_limits(xyl_lsystem_limits *l, const xyl_lsystem_limits *base)
{
    static const xyl_lsystem_limits defaults = {
        LSYS_DEFAULT_MAX_DEPTH, LSYS_DEFAULT_MAX_MODULES, LSYS_DEFAULT_MAX_BYTES,
        LSYS_DEFAULT_MAX_NESTING, LSYS_DEFAULT_MAX_EXPR_DEPTH, LSYS_DEFAULT_MAX_PARAMS,
        LSYS_DEFAULT_MAX_SOURCE};
    const xyl_lsystem_limits *b = base ? base : &defaults;
    for (int pass = 0; pass < 2; ++pass, b = &defaults) {
        if (!l->max_depth) l->max_depth = b->max_depth;
        if (!l->max_modules) l->max_modules = b->max_modules;
        if (!l->max_bytes) l->max_bytes = b->max_bytes;
        if (!l->max_nesting) l->max_nesting = b->max_nesting;
        if (!l->max_expr_depth) l->max_expr_depth = b->max_expr_depth;
        if (!l->max_params) l->max_params = b->max_params;
        if (!l->max_source_bytes) l->max_source_bytes = b->max_source_bytes;
    }
}

xyl_result xyl__lsys_error_at(lsys_parser *p, size_t at, xyl_result code, const char *fmt, ...)
{
    if (!p->diag) return code;
    char msg[XYL_DIAG_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    uint32_t col = at >= p->line_start ? (uint32_t)(at - p->line_start + 1) : 1;
    return xyl__fail(p->diag, code, p->line, col, -1, "%s", msg);
}

/* ---- growable arrays ----------------------------------------------------------------------- */

#define GROW(p, arr, cnt, cap, need)                                                         \
    xyl__grow(&(p)->g->alloc, (void **)&(p)->g->arr, &(p)->cap, (p)->g->cnt, (need),         \
              sizeof *(p)->g->arr)

static xyl_result oom(lsys_parser *p, size_t at)
{
    return xyl__lsys_error_at(p, at, XYL_ERR_OUT_OF_MEMORY, "out of memory");
}

/* ---- small lexing helpers ------------------------------------------------------------------ */

static size_t ident_len(const char *s, size_t pos, size_t end)
{
    size_t n = 0;
    if (pos < end && (lsys_is_alpha(s[pos]) || s[pos] == '_'))
        while (pos + n < end && lsys_is_ident_char(s[pos + n])) ++n;
    return n;
}

static bool word_is(const char *s, size_t pos, size_t n, const char *w)
{
    return strlen(w) == n && memcmp(s + pos, w, n) == 0;
}

/* First occurrence of "->" outside parentheses in [pos, end), or end. */
static size_t find_arrow(const char *s, size_t pos, size_t end)
{
    int depth = 0;
    for (size_t i = pos; i + 1 < end; ++i) {
        if (s[i] == '(') ++depth;
        else if (s[i] == ')') --depth;
        else if (depth == 0 && s[i] == '-' && s[i + 1] == '>') return i;
    }
    return end;
}

static size_t find_top(const char *s, size_t pos, size_t end, char c)
{
    int depth = 0;
    for (size_t i = pos; i < end; ++i) {
        if (s[i] == '(') ++depth;
        else if (s[i] == ')') --depth;
        else if (depth == 0 && s[i] == c) return i;
    }
    return end;
}

/* ---- successors (and the axiom) ------------------------------------------------------------ */

/* Parses "(item, item, ...)" at *pos with one item callback per element; the callback raises
 * *count and checks the parameter limit. */
typedef xyl_result (*list_item_fn)(lsys_parser *p, size_t *pos, size_t end, void *ctx);

static xyl_result parse_list(lsys_parser *p, size_t *pos, size_t end, list_item_fn item, void *ctx)
{
    const char *s = p->src;
    size_t open = (*pos)++;
    for (;;) {
        xyl_result r = item(p, pos, end, ctx);
        if (r) return r;
        lsys_skip_space(s, pos, end);
        if (*pos < end && s[*pos] == ',') {
            ++*pos;
            continue;
        }
        if (*pos < end && s[*pos] == ')') {
            ++*pos;
            return XYL_OK;
        }
        return xyl__lsys_error_at(p, open, XYL_ERR_INVALID_GRAMMAR, "'(' is never closed");
    }
}

static xyl_result check_arity(lsys_parser *p, size_t at, char sym, uint32_t nparam)
{
    if (nparam < p->g->limits.max_params) return XYL_OK;
    return xyl__lsys_error_at(p, at, XYL_ERR_LIMIT_EXCEEDED, "module '%c' has more than %u parameters",
                         sym, p->g->limits.max_params);
}

static xyl_result param_expr_item(lsys_parser *p, size_t *pos, size_t end, void *ctx)
{
    lsys_succ *m = ctx;
    xyl_result r = check_arity(p, *pos, (char)m->sym, m->nparam);
    if (r) return r;
    if (!GROW(p, exprs, expr_count, expr_cap, p->g->expr_count + 1)) return oom(p, *pos);
    lsys_expr e;
    r = xyl__lsys_compile_expr(p, pos, end, &e);
    if (r) return r;
    p->g->exprs[p->g->expr_count++] = e;
    ++m->nparam;
    return XYL_OK;
}

/* Parses modules with parameter expressions from [*pos, end) into succs; brackets must balance. */
static xyl_result parse_successor(lsys_parser *p, size_t pos, size_t end, uint32_t *first,
                                  uint32_t *count)
{
    const char *s = p->src;
    xyl_grammar *g = p->g;
    *first = (uint32_t)g->succ_count;
    size_t open_at[64];
    uint32_t depth = 0;
    for (lsys_skip_space(s, &pos, end); pos < end; lsys_skip_space(s, &pos, end)) {
        char c = s[pos];
        if (!xyl__lsys_is_symbol(c))
            return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "'%c' is not a module symbol",
                                 c >= 32 && c < 127 ? c : '?');
        if (c == ']' && depth == 0)
            return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "']' without a matching '['");
        if (c == '[') {
            if (depth < 64) open_at[depth] = pos;
            ++depth;
        } else if (c == ']') {
            --depth;
        }
        if (!GROW(p, succs, succ_count, succ_cap, g->succ_count + 1)) return oom(p, pos);
        lsys_succ m = {(uint8_t)c, 0, (uint32_t)g->expr_count};
        ++pos;
        lsys_skip_space(s, &pos, end);
        if (pos < end && s[pos] == '(') {
            xyl_result r = parse_list(p, &pos, end, param_expr_item, &m);
            if (r) return r;
        }
        g->succs[g->succ_count++] = m;
    }
    if (depth > 0)
        return xyl__lsys_error_at(p, open_at[depth - 1 < 64 ? depth - 1 : 63], XYL_ERR_INVALID_GRAMMAR,
                             "'[' is never closed");
    *count = (uint32_t)g->succ_count - *first;
    return XYL_OK;
}

static xyl_result parse_axiom(lsys_parser *p, size_t pos, size_t end)
{
    xyl_grammar *g = p->g;
    if (g->axiom) return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "a second axiom");
    p->var_count = 0;
    uint32_t first, count;
    size_t succ_base = g->succ_count, expr_base = g->expr_count;
    xyl_result r = parse_successor(p, pos, end, &first, &count);
    if (r) return r;
    size_t nparams = 0;
    for (uint32_t i = 0; i < count; ++i) nparams += g->succs[first + i].nparam;
    g->axiom = xyl__calloc(&g->alloc, count ? count : 1, sizeof *g->axiom);
    g->axiom_params = xyl__calloc(&g->alloc, nparams ? nparams : 1, sizeof *g->axiom_params);
    if (!g->axiom || !g->axiom_params) return oom(p, pos);
    for (uint32_t i = 0; i < count; ++i) {
        const lsys_succ *m = &g->succs[first + i];
        lsys_module mod = {m->sym, m->nparam, 0, (uint32_t)g->axiom_nparams};
        for (uint32_t k = 0; k < m->nparam; ++k) {
            const lsys_expr *e = &g->exprs[m->expr + k];
            if (!e->constant)
                return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR,
                                     "axiom parameters must be constant");
            g->axiom_params[g->axiom_nparams++] = g->code[e->first].k;
        }
        g->axiom[g->axiom_count++] = mod;
    }
    g->succ_count = succ_base; /* the axiom keeps no successor records */
    g->expr_count = expr_base;
    return XYL_OK;
}

/* ---- patterns (contexts and predecessor) --------------------------------------------------- */

static xyl_result declare_var(lsys_parser *p, size_t at, size_t n)
{
    for (uint32_t v = 0; v < p->var_count; ++v)
        if (p->vars[v].n == n && memcmp(p->vars[v].s, p->src + at, n) == 0)
            return xyl__lsys_error_at(p, at, XYL_ERR_INVALID_GRAMMAR, "parameter '%.*s' is named twice",
                                 (int)n, p->src + at);
    if (p->var_count >= LSYS_MAX_VARS)
        return xyl__lsys_error_at(p, at, XYL_ERR_LIMIT_EXCEEDED, "more than %u parameters in a production",
                             LSYS_MAX_VARS);
    lsys_name nm = {p->src + at, n};
    p->vars[p->var_count++] = nm;
    return XYL_OK;
}

static xyl_result formal_item(lsys_parser *p, size_t *pos, size_t end, void *ctx)
{
    lsys_pat *m = ctx;
    lsys_skip_space(p->src, pos, end);
    size_t n = ident_len(p->src, *pos, end);
    if (n == 0) return xyl__lsys_error_at(p, *pos, XYL_ERR_INVALID_GRAMMAR, "expected a parameter name");
    xyl_result r = check_arity(p, *pos, (char)m->sym, m->nparam);
    if (!r) r = declare_var(p, *pos, n);
    if (r) return r;
    ++m->nparam;
    *pos += n;
    return XYL_OK;
}

/* Parses a run of pattern modules from [*pos, end) up to '<', '>' or end. */
static xyl_result parse_pattern(lsys_parser *p, size_t *pos, size_t end, bool brackets,
                                uint32_t *first, uint32_t *count)
{
    const char *s = p->src;
    xyl_grammar *g = p->g;
    *first = (uint32_t)g->pat_count;
    for (lsys_skip_space(s, pos, end); *pos < end; lsys_skip_space(s, pos, end)) {
        char c = s[*pos];
        if (c == '<' || c == '>') break;
        if (!xyl__lsys_is_symbol(c))
            return xyl__lsys_error_at(p, *pos, XYL_ERR_INVALID_GRAMMAR, "'%c' is not a module symbol",
                                 c >= 32 && c < 127 ? c : '?');
        if (!brackets && (c == '[' || c == ']'))
            return xyl__lsys_error_at(p, *pos, XYL_ERR_INVALID_GRAMMAR,
                                 "brackets are allowed only in a right context");
        if (!GROW(p, pats, pat_count, pat_cap, g->pat_count + 1)) return oom(p, *pos);
        lsys_pat m = {(uint8_t)c, 0, (uint16_t)p->var_count};
        ++*pos;
        lsys_skip_space(s, pos, end);
        if (*pos < end && s[*pos] == '(') {
            xyl_result r = parse_list(p, pos, end, formal_item, &m);
            if (r) return r;
        }
        g->pats[g->pat_count++] = m;
    }
    *count = (uint32_t)g->pat_count - *first;
    return XYL_OK;
}

/* "left < pred(params) > right" */
static xyl_result parse_head(lsys_parser *p, size_t pos, size_t end, lsys_prod *pr)
{
    const char *s = p->src;
    uint32_t first, count;
    size_t start = pos;
    xyl_result r = parse_pattern(p, &pos, end, false, &first, &count);
    if (r) return r;
    if (pos < end && s[pos] == '<') {
        pr->left_first = first;
        pr->left_count = count;
        if (count == 0)
            return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "empty left context before '<'");
        start = ++pos;
        r = parse_pattern(p, &pos, end, false, &first, &count);
        if (r) return r;
    }
    if (count != 1)
        return xyl__lsys_error_at(p, start, XYL_ERR_INVALID_GRAMMAR,
                             count ? "the predecessor must be a single module"
                                   : "missing predecessor");
    const lsys_pat *pred = &p->g->pats[first];
    pr->pred = pred->sym;
    pr->pred_nparam = pred->nparam;
    pr->pred_var = pred->var;
    p->g->pat_count = first; /* the predecessor is kept in the production itself */
    if (pos < end && s[pos] == '>') {
        size_t at = ++pos;
        r = parse_pattern(p, &pos, end, true, &pr->right_first, &pr->right_count);
        if (r) return r;
        if (pr->right_count == 0)
            return xyl__lsys_error_at(p, at, XYL_ERR_INVALID_GRAMMAR, "empty right context after '>'");
        if (pos < end)
            return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c'", s[pos]);
    } else if (pos < end) {
        return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c'", s[pos]);
    }
    return XYL_OK;
}

/* ---- productions --------------------------------------------------------------------------- */

static xyl_result parse_weight(lsys_parser *p, size_t *pos, size_t end, lsys_prod *pr)
{
    const char *s = p->src;
    lsys_skip_space(s, pos, end);
    if (*pos >= end || s[*pos] != '(') return XYL_OK;
    size_t open = (*pos)++;
    if (!GROW(p, exprs, expr_count, expr_cap, p->g->expr_count + 1)) return oom(p, *pos);
    lsys_expr e;
    xyl_result r = xyl__lsys_compile_expr(p, pos, end, &e);
    if (r) return r;
    if (*pos >= end || s[*pos] != ')')
        return xyl__lsys_error_at(p, open, XYL_ERR_INVALID_GRAMMAR, "'(' of the weight is never closed");
    ++*pos;
    pr->weight = (int32_t)p->g->expr_count;
    p->g->exprs[p->g->expr_count++] = e;
    return XYL_OK;
}

/* ABOP writes "pred : * -> succ" for "no condition". */
static bool is_star(const char *s, size_t pos, size_t end)
{
    lsys_skip_space(s, &pos, end);
    while (end > pos && lsys_is_space(s[end - 1])) --end;
    return end == pos + 1 && s[pos] == '*';
}

static xyl_result parse_production(lsys_parser *p, size_t pos, size_t end)
{
    const char *s = p->src;
    xyl_grammar *g = p->g;
    size_t arrow = find_arrow(s, pos, end);
    if (arrow == end)
        return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR,
                             "expected a production 'pred -> successor', an 'axiom:' or a "
                             "'#' directive");
    if (!GROW(p, prods, prod_count, prod_cap, g->prod_count + 1)) return oom(p, pos);
    if (!xyl__grow(&g->alloc, (void **)&p->heads, &p->head_cap, g->prod_count, g->prod_count + 1,
                   sizeof *p->heads))
        return oom(p, pos);
    lsys_name head = {s + pos, arrow - pos};
    p->heads[g->prod_count] = head;
    lsys_prod pr;
    memset(&pr, 0, sizeof pr);
    pr.line = p->line;
    pr.cond = -1;
    pr.weight = -1;
    pr.group_next = UINT32_MAX;
    p->var_count = 0;
    size_t colon = find_top(s, pos, arrow, ':');
    xyl_result r = parse_head(p, pos, colon, &pr);
    if (r) return r;
    if (colon < arrow && !is_star(s, colon + 1, arrow)) {
        size_t cpos = colon + 1;
        if (!GROW(p, exprs, expr_count, expr_cap, g->expr_count + 1)) return oom(p, cpos);
        lsys_expr e;
        r = xyl__lsys_compile_expr(p, &cpos, arrow, &e);
        if (r) return r;
        if (cpos < arrow)
            return xyl__lsys_error_at(p, cpos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c' in condition",
                                 s[cpos]);
        pr.cond = (int32_t)g->expr_count;
        g->exprs[g->expr_count++] = e;
    }
    size_t body = arrow + 2;
    r = parse_weight(p, &body, end, &pr);
    if (r) return r;
    r = parse_successor(p, body, end, &pr.succ_first, &pr.succ_count);
    if (r) return r;
    for (uint32_t i = 0; i < pr.succ_count; ++i) pr.succ_pcount += g->succs[pr.succ_first + i].nparam;
    pr.nvars = p->var_count;
    if (pr.nvars > g->max_vars) g->max_vars = pr.nvars;
    g->prods[g->prod_count++] = pr;
    return XYL_OK;
}

/* ---- directives ---------------------------------------------------------------------------- */

static xyl_result parse_unsigned(lsys_parser *p, size_t pos, size_t end, uint64_t max,
                                 uint64_t *out)
{
    const char *s = p->src;
    lsys_skip_space(s, &pos, end);
    if (pos >= end || !lsys_is_digit(s[pos]))
        return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "expected a whole number");
    uint64_t v = 0;
    size_t at = pos;
    for (; pos < end && lsys_is_digit(s[pos]); ++pos) {
        unsigned d = (unsigned)(s[pos] - '0');
        if (v > (max - d) / 10)
            return xyl__lsys_error_at(p, at, XYL_ERR_LIMIT_EXCEEDED, "number is larger than %llu",
                                 (unsigned long long)max);
        v = v * 10 + d;
    }
    lsys_skip_space(s, &pos, end);
    if (pos < end) return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c'", s[pos]);
    *out = v;
    return XYL_OK;
}

static xyl_result parse_const_line(lsys_parser *p, size_t pos, size_t end, double *out)
{
    xyl_result r = xyl__lsys_const_expr(p, &pos, end, out);
    lsys_skip_space(p->src, &pos, end);
    if (!r && pos < end)
        return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c'", p->src[pos]);
    return r;
}

static xyl_result parse_define(lsys_parser *p, size_t pos, size_t end)
{
    const char *s = p->src;
    lsys_skip_space(s, &pos, end);
    size_t n = ident_len(s, pos, end);
    if (n == 0) return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "#define needs a name");
    lsys_define d = {{s + pos, n}, 0.0};
    xyl_result r = parse_const_line(p, pos + n, end, &d.value);
    if (r) return r;
    if (!xyl__grow(&p->g->alloc, (void **)&p->defines, &p->define_cap, p->define_count,
                   p->define_count + 1, sizeof *p->defines))
        return oom(p, pos);
    p->defines[p->define_count++] = d;
    return XYL_OK;
}

static xyl_result parse_ignore(lsys_parser *p, size_t pos, size_t end)
{
    for (lsys_skip_space(p->src, &pos, end); pos < end; lsys_skip_space(p->src, &pos, end)) {
        char c = p->src[pos];
        if (!xyl__lsys_is_symbol(c) || c == '[' || c == ']')
            return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR,
                                 "#ignore takes module symbols other than brackets");
        p->g->ignore[(uint8_t)c] = 1;
        ++pos;
    }
    return XYL_OK;
}

static xyl_result parse_tropism(lsys_parser *p, size_t pos, size_t end)
{
    double v[4];
    for (int i = 0; i < 4; ++i) {
        lsys_skip_space(p->src, &pos, end);
        size_t stop = pos;
        /* values are separated by spaces or commas; a value may be "-1" */
        while (stop < end && !lsys_is_space(p->src[stop]) && p->src[stop] != ',') ++stop;
        if (stop == pos)
            return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR,
                                 "#tropism takes four numbers: x y z elasticity");
        xyl_result r = parse_const_line(p, pos, stop, &v[i]);
        if (r) return r;
        pos = stop;
        lsys_skip_space(p->src, &pos, end);
        if (pos < end && p->src[pos] == ',') ++pos;
    }
    lsys_skip_space(p->src, &pos, end);
    if (pos < end) return xyl__lsys_error_at(p, pos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c'", p->src[pos]);
    xyl_grammar_info *in = &p->g->info;
    in->tropism[0] = v[0];
    in->tropism[1] = v[1];
    in->tropism[2] = v[2];
    in->elasticity = v[3];
    p->g->has_tropism = true;
    return XYL_OK;
}

static xyl_result parse_directive(lsys_parser *p, size_t pos, size_t end)
{
    const char *s = p->src;
    size_t at = pos++; /* '#' */
    size_t n = ident_len(s, pos, end);
    size_t arg = pos + n;
    lsys_skip_space(s, &arg, end);
    xyl_grammar_info *in = &p->g->info;
    xyl_result r;
    uint64_t u;
    if (word_is(s, pos, n, "define")) return parse_define(p, arg, end);
    if (word_is(s, pos, n, "ignore")) return parse_ignore(p, arg, end);
    if (word_is(s, pos, n, "tropism")) return parse_tropism(p, arg, end);
    if (word_is(s, pos, n, "angle")) {
        double deg;
        r = parse_const_line(p, arg, end, &deg);
        in->angle = deg * (XYL__PI / 180.0);
        return r;
    }
    if (word_is(s, pos, n, "step")) return parse_const_line(p, arg, end, &in->step);
    if (word_is(s, pos, n, "width")) {
        r = parse_const_line(p, arg, end, &in->width);
        if (!r && !(in->width > 0.0))
            return xyl__lsys_error_at(p, arg, XYL_ERR_INVALID_GRAMMAR, "#width must be > 0");
        return r;
    }
    if (word_is(s, pos, n, "depth")) {
        r = parse_unsigned(p, arg, end, UINT32_MAX, &u);
        in->depth = (uint32_t)u;
        return r;
    }
    if (word_is(s, pos, n, "seed")) return parse_unsigned(p, arg, end, UINT64_MAX, &in->seed);
    return xyl__lsys_error_at(p, at, XYL_ERR_INVALID_GRAMMAR, "unknown directive '#%.*s'", (int)n,
                         s + pos);
}

/* ---- lines --------------------------------------------------------------------------------- */

/* End of the line's content: before a comment and the newline. A comment is "//" standing as
 * a word (line start or whitespace before it, whitespace or line end after it), because runs of
 * '/' are rolls in successors ("A -> F/////F"). */
static size_t content_end(const char *s, size_t pos, size_t eol)
{
    for (size_t i = pos; i + 1 < eol; ++i) {
        bool word_start = i == pos || lsys_is_space(s[i - 1]);
        bool word_end = i + 2 == eol || lsys_is_space(s[i + 2]);
        if (s[i] == '/' && s[i + 1] == '/' && word_start && word_end) return i;
    }
    return eol;
}

static xyl_result parse_line(lsys_parser *p, size_t pos, size_t end)
{
    const char *s = p->src;
    lsys_skip_space(s, &pos, end);
    while (end > pos && lsys_is_space(s[end - 1])) --end;
    if (pos == end) return XYL_OK;
    if (s[pos] == '#') return parse_directive(p, pos, end);
    size_t n = ident_len(s, pos, end);
    size_t after = pos + n;
    lsys_skip_space(s, &after, end);
    /* "axiom:" or a label: an identifier of two or more characters followed by ':'. A single
     * character before ':' is a predecessor symbol ("A : x > 1 -> B"). */
    if (n >= 2 && after < end && s[after] == ':') {
        if (word_is(s, pos, n, "axiom")) return parse_axiom(p, after + 1, end);
        pos = after + 1;
    }
    return parse_production(p, pos, end);
}

static xyl_result parse_lines(lsys_parser *p)
{
    const char *s = p->src;
    size_t pos = 0;
    p->line = 1;
    while (pos < p->len) {
        size_t eol = pos;
        while (eol < p->len && s[eol] != '\n') {
            if (s[eol] == '\0') {
                p->line_start = pos;
                return xyl__lsys_error_at(p, eol, XYL_ERR_INVALID_GRAMMAR, "NUL byte in grammar text");
            }
            ++eol;
        }
        p->line_start = pos;
        xyl_result r = parse_line(p, pos, content_end(s, pos, eol));
        if (r) return r;
        pos = eol + 1;
        ++p->line;
    }
    return XYL_OK;
}

/* ---- stochastic groups --------------------------------------------------------------------- */

static uint64_t head_hash(lsys_name h)
{
    uint64_t x = UINT64_C(1469598103934665603);
    for (size_t i = 0; i < h.n; ++i)
        if (!lsys_is_space(h.s[i])) x = (x ^ (uint8_t)h.s[i]) * UINT64_C(1099511628211);
    return x;
}

static bool head_equal(lsys_name a, lsys_name b)
{
    size_t i = 0, j = 0;
    for (;;) {
        while (i < a.n && lsys_is_space(a.s[i])) ++i;
        while (j < b.n && lsys_is_space(b.s[j])) ++j;
        if (i == a.n || j == b.n) return i == a.n && j == b.n;
        if (a.s[i++] != b.s[j++]) return false;
    }
}

/* Productions with the same head (context, predecessor, condition; whitespace ignored) and
 * weights form one stochastic group, chained through group_next from its first member. A head
 * repeated without weights could never apply and is reported. */
static xyl_result build_groups(lsys_parser *p)
{
    xyl_grammar *g = p->g;
    size_t cap = 16;
    while (cap < g->prod_count * 2) cap *= 2;
    uint32_t *tail = xyl__alloc(&g->alloc, cap * sizeof *tail);
    if (!tail) return oom(p, 0);
    memset(tail, 0xff, cap * sizeof *tail);
    xyl_result r = XYL_OK;
    for (uint32_t i = 0; i < g->prod_count && !r; ++i) {
        size_t slot = (size_t)head_hash(p->heads[i]) & (cap - 1);
        while (tail[slot] != UINT32_MAX && !head_equal(p->heads[tail[slot]], p->heads[i]))
            slot = (slot + 1) & (cap - 1);
        uint32_t prev = tail[slot];
        tail[slot] = i;
        if (prev == UINT32_MAX) continue;
        lsys_prod *a = &g->prods[prev], *b = &g->prods[i];
        if (a->weight < 0 || b->weight < 0) {
            p->line = b->line;
            p->line_start = (size_t)(p->heads[i].s - p->src);
            for (size_t k = p->line_start; k > 0 && p->src[k - 1] != '\n'; --k) p->line_start = k - 1;
            r = xyl__lsys_error_at(p, (size_t)(p->heads[i].s - p->src), XYL_ERR_INVALID_GRAMMAR,
                              "same predecessor, context and condition as line %u; weight both "
                              "(stochastic) or remove one",
                              a->line);
            break;
        }
        a->group_next = i;
        b->group_member = true;
    }
    xyl__free(&g->alloc, tail);
    return r;
}

/* ---- lookup tables and precompiled constant successors ------------------------------------- */

static bool successor_constant(const xyl_grammar *g, const lsys_prod *pr)
{
    if (pr->left_count || pr->right_count || pr->cond >= 0 || pr->weight >= 0) return false;
    for (uint32_t i = 0; i < pr->succ_count; ++i) {
        const lsys_succ *m = &g->succs[pr->succ_first + i];
        for (uint32_t k = 0; k < m->nparam; ++k)
            if (!g->exprs[m->expr + k].constant) return false;
    }
    return true;
}

static xyl_result precompile(lsys_parser *p, lsys_prod *pr)
{
    xyl_grammar *g = p->g;
    pr->is_constant = true;
    pr->const_first = (uint32_t)g->cmod_count;
    pr->const_pfirst = (uint32_t)g->cparam_count;
    int32_t depth = 0;
    for (uint32_t i = 0; i < pr->succ_count; ++i) {
        const lsys_succ *m = &g->succs[pr->succ_first + i];
        if (!GROW(p, cmods, cmod_count, cmod_cap, g->cmod_count + 1) ||
            !GROW(p, csyms, cmod_count, csym_cap, g->cmod_count + 1) ||
            !GROW(p, cparams, cparam_count, cparam_cap, g->cparam_count + m->nparam))
            return oom(p, 0);
        lsys_module mod = {m->sym, m->nparam, 0,
                           (uint32_t)(g->cparam_count - pr->const_pfirst)};
        for (uint32_t k = 0; k < m->nparam; ++k)
            g->cparams[g->cparam_count++] = g->code[g->exprs[m->expr + k].first].k;
        g->csyms[g->cmod_count] = m->sym;
        g->cmods[g->cmod_count++] = mod;
        pr->const_cut |= m->sym == '%';
        depth += m->sym == '[' ? 1 : m->sym == ']' ? -1 : 0;
        if (depth > pr->const_depth_max) pr->const_depth_max = depth;
    }
    pr->const_count = pr->succ_count;
    pr->const_pcount = (uint32_t)(g->cparam_count - pr->const_pfirst);
    return XYL_OK;
}

#define BYTE_PAD 32 /* derive.c copies short successors 16 or 32 bytes at a time */

/* The byte path's per-symbol tables (see xyl_grammar): a copied symbol is its own one-byte
 * successor, stored after the precompiled ones. */
static bool build_byte_tables(xyl_grammar *g)
{
    size_t n = g->cmod_count;
    g->byte_table = xyl__calloc(&g->alloc, n + 256 + BYTE_PAD, 1);
    if (!g->byte_table) return false;
    if (n) memcpy(g->byte_table, g->csyms, n);
    g->byte_max_len = 1;
    for (int c = 0; c < 256; ++c) {
        int32_t k = g->constant_prod[c];
        if (k < 0) {
            g->byte_table[n + (size_t)c] = (uint8_t)c;
            g->byte_src[c] = (uint32_t)(n + (size_t)c);
            g->byte_len[c] = 1;
            g->byte_delta[c] = c == '[' ? 1 : c == ']' ? -1 : 0;
            g->byte_dmax[c] = c == '[' ? 1 : 0;
            g->byte_cut[c] = c == '%';
            continue;
        }
        const lsys_prod *pr = &g->prods[k];
        g->byte_src[c] = pr->const_first;
        g->byte_len[c] = pr->const_count;
        g->byte_delta[c] = 0; /* successors are balanced */
        g->byte_dmax[c] = pr->const_depth_max;
        g->byte_cut[c] = pr->const_cut;
        if (pr->const_count > g->byte_max_len) g->byte_max_len = pr->const_count;
    }
    return true;
}

/* Tables derive.c dispatches on: whether any module can carry parameters, and per symbol the one
 * constant production that always rewrites it (or -1). */
static bool classify(xyl_grammar *g)
{
    g->parametric = g->axiom_nparams > 0;
    for (size_t i = 0; i < g->succ_count; ++i) g->parametric |= g->succs[i].nparam > 0;
    g->all_constant = true;
    for (int c = 0; c < 256; ++c) {
        g->constant_prod[c] = -1;
        if (g->sym_count[c] == 0) continue;
        uint32_t k = g->sym_prods[g->sym_first[c]];
        const lsys_prod *pr = &g->prods[k];
        bool always = g->sym_count[c] == 1 && pr->is_constant && pr->pred_nparam == 0;
        if (always) g->constant_prod[c] = (int32_t)k;
        g->all_constant &= always;
    }
    return !g->all_constant || g->parametric || build_byte_tables(g);
}

static xyl_result finalize(lsys_parser *p)
{
    xyl_grammar *g = p->g;
    if (!g->axiom) {
        p->line_start = p->len;
        return xyl__lsys_error_at(p, p->len, XYL_ERR_INVALID_GRAMMAR, "the grammar has no 'axiom:' line");
    }
    xyl_result r = build_groups(p);
    if (r) return r;
    g->sym_prods = xyl__calloc(&g->alloc, g->prod_count ? g->prod_count : 1, sizeof *g->sym_prods);
    if (!g->sym_prods) return oom(p, 0);
    for (uint32_t i = 0; i < g->prod_count; ++i)
        if (!g->prods[i].group_member) ++g->sym_count[g->prods[i].pred];
    uint32_t at = 0;
    for (int c = 0; c < 256; ++c) {
        g->sym_first[c] = at;
        at += g->sym_count[c];
        g->sym_count[c] = 0;
    }
    for (uint32_t i = 0; i < g->prod_count; ++i) {
        lsys_prod *pr = &g->prods[i];
        if (pr->group_member) continue;
        g->sym_prods[g->sym_first[pr->pred] + g->sym_count[pr->pred]++] = i;
        if (successor_constant(g, pr) && pr->group_next == UINT32_MAX) {
            r = precompile(p, pr);
            if (r) return r;
        }
    }
    if (!classify(g)) return oom(p, 0);
    g->info.production_count = g->prod_count;
    return XYL_OK;
}

/* ---- public API ---------------------------------------------------------------------------- */

void xyl_grammar_destroy(xyl_grammar *g)
{
    if (!g) return;
    xyl_allocator a = g->alloc;
    void *arrays[] = {g->axiom, g->axiom_params, g->prods, g->pats, g->succs, g->exprs,
                      g->code, g->cmods, g->csyms, g->cparams, g->sym_prods, g->byte_table};
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; ++i) xyl__free(&a, arrays[i]);
    xyl__free(&a, g);
}

static xyl_result check_desc(const xyl_grammar_desc *desc, xyl_grammar **out, xyl_diag *diag,
                             size_t *len, xyl_lsystem_limits *limits)
{
    if (!desc || !out || !desc->source)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc, desc->source and out must not be NULL");
    *limits = desc->limits;
    xyl__lsys_resolve_limits(limits, NULL);
    if (limits->max_expr_depth > HARD_MAX_EXPR_DEPTH || limits->max_params > LSYS_HARD_MAX_PARAMS)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "max_expr_depth must be <= %u and max_params <= %u", HARD_MAX_EXPR_DEPTH,
                         LSYS_HARD_MAX_PARAMS);
    *len = desc->length ? desc->length : strlen(desc->source);
    if ((uint64_t)*len > limits->max_source_bytes)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "grammar text of %zu bytes exceeds the limit of %llu", *len,
                         (unsigned long long)limits->max_source_bytes);
    return XYL_OK;
}

xyl_result xyl_grammar_parse(const xyl_grammar_desc *desc, xyl_grammar **out, xyl_diag *diag)
{
    size_t len = 0;
    xyl_lsystem_limits limits;
    xyl_result r = check_desc(desc, out, diag, &len, &limits);
    if (r) return r;
    xyl_grammar *g = xyl__calloc(&desc->alloc, 1, sizeof *g);
    if (!g) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    g->alloc = desc->alloc;
    g->limits = limits;
    g->info.depth = DEFAULT_DEPTH;
    g->info.seed = 1;
    g->info.angle = DEFAULT_ANGLE_DEG * (XYL__PI / 180.0);
    g->info.step = 1.0;
    g->info.width = 0.1;
    g->max_stack = 1;
    lsys_parser *p = xyl__calloc(&desc->alloc, 1, sizeof *p);
    if (!p) {
        xyl_grammar_destroy(g);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory");
    }
    p->g = g;
    p->diag = diag;
    p->src = desc->source;
    p->len = len;
    r = parse_lines(p);
    if (!r) r = finalize(p);
    xyl__free(&g->alloc, p->defines);
    xyl__free(&g->alloc, p->heads);
    xyl__free(&desc->alloc, p);
    if (r) {
        xyl_grammar_destroy(g);
        return r;
    }
    *out = g;
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_grammar_get_info(const xyl_grammar *grammar, xyl_grammar_info *info)
{
    if (!info) return;
    if (!grammar) {
        memset(info, 0, sizeof *info);
        return;
    }
    *info = grammar->info;
}
