/* Parallel rewriting: context matching (ABOP bracket rules), conditions, stochastic choice,
 * parametric successors, the cut symbol, and every bound checked on the way.
 *
 * Two paths share the string layout of lsys_internal.h. Grammars without parameters whose every
 * production is constant (the classic bracketed plants) take the byte path: one counting pass
 * gives the exact size of the next string, limits are checked before anything is allocated, and
 * the write pass copies bytes. Everything else takes the general path, module by module. */
#include <stdio.h>
#include <string.h>

#include "lsys_internal.h"

typedef struct deriver {
    const xyl_grammar *g;
    xyl_lsystem_limits limits;
    const xyl_lstring *cur;
    xyl_lstring *next;
    double *vars;
    double *stack;
    double *weights;     /* one per production: a stochastic group's evaluated weights */
    lsys_rng rng;
    uint32_t depth;      /* bracket depth in next */
    bool has_cut;        /* next holds a '%' */
    uint32_t step;       /* 1-based derivation step, for messages */
    xyl_diag *diag;
    bool bytes;          /* byte path (see step_bytes) */
    uint64_t hist[256];  /* byte path: how often each symbol occurs in the current string */
    int64_t depth_bound; /* byte path: an upper bound of the current string's bracket depth */
} deriver;

/* ---- strings ------------------------------------------------------------------------------- */

/* sym, np and poff share one capacity: each grows by doubling from the same start, so all reach
 * the same size. On failure the old arrays stay valid. */
static bool reserve_slow(xyl_lstring *s, size_t mods, size_t params)
{
    const xyl_allocator *a = &s->alloc;
    if (mods > s->cap) {
        size_t c0 = s->cap, c1 = s->cap, c2 = s->cap;
        if (!xyl__grow(a, (void **)&s->sym, &c0, s->count, mods, 1)) return false;
        if (s->np && (!xyl__grow(a, (void **)&s->np, &c1, s->count, mods, 1) ||
                      !xyl__grow(a, (void **)&s->poff, &c2, s->count, mods, sizeof *s->poff)))
            return false;
        s->cap = c0;
    }
    return xyl__grow(a, (void **)&s->params, &s->pcap, s->nparams, params, sizeof *s->params);
}

static inline bool reserve(xyl_lstring *s, size_t mods, size_t params)
{
    return (mods <= s->cap && params <= s->pcap) || reserve_slow(s, mods, params);
}

static xyl_lstring *new_string(const xyl_allocator *a, bool parametric)
{
    xyl_lstring *s = xyl__calloc(a, 1, sizeof *s);
    if (!s) return NULL;
    if (a) s->alloc = *a;
    s->cap = s->pcap = 16;
    s->sym = xyl__alloc(a, s->cap);
    s->params = xyl__alloc(a, s->pcap * sizeof *s->params);
    bool ok = s->sym && s->params;
    if (parametric) {
        s->np = xyl__alloc(a, s->cap);
        s->poff = xyl__alloc(a, s->cap * sizeof *s->poff);
        ok = ok && s->np && s->poff;
    }
    if (!ok) {
        xyl_lstring_destroy(s);
        return NULL;
    }
    return s;
}

void xyl_lstring_destroy(xyl_lstring *s)
{
    if (!s) return;
    xyl_allocator a = s->alloc;
    xyl__free(&a, s->sym);
    xyl__free(&a, s->np);
    xyl__free(&a, s->poff);
    xyl__free(&a, s->params);
    xyl__free(&a, s);
}

size_t xyl_lstring_count(const xyl_lstring *s)
{
    return s ? s->count : 0;
}

xyl_result xyl_lstring_module(const xyl_lstring *s, size_t index, xyl_module_view *out)
{
    if (!s || !out || index >= s->count) return XYL_ERR_INVALID_ARGUMENT;
    out->symbol = (char)s->sym[index];
    out->param_count = lsys_np(s, index);
    out->params = out->param_count ? lsys_par(s, index) : NULL;
    return XYL_OK;
}

static size_t format_module(const xyl_lstring *s, size_t i, char *out, size_t cap)
{
    char tmp[48];
    size_t n = 0;
    if (n < cap) out[n] = (char)s->sym[i];
    ++n;
    uint32_t np = lsys_np(s, i);
    for (uint32_t k = 0; k < np; ++k) {
        int w = snprintf(tmp, sizeof tmp, "%c%.9g", k ? ',' : '(', lsys_par(s, i)[k]);
        /* snprintf prints the locale's decimal point ("1,5" would read as two parameters);
         * %g prints nothing else outside [0-9+-e], so any such run after the lead is one '.' */
        bool in_point = false;
        for (int j = 0; j < w && j < (int)sizeof tmp - 1; ++j) {
            char c = tmp[j];
            bool number = j == 0 || (c >= '0' && c <= '9') || c == '-' || c == '+' || c == 'e';
            if (!number && in_point) continue;
            in_point = !number;
            if (n < cap) out[n] = number ? c : '.';
            ++n;
        }
    }
    if (np) {
        if (n < cap) out[n] = ')';
        ++n;
    }
    return n;
}

xyl_result xyl_lstring_format(const xyl_lstring *s, char *buffer, size_t capacity, size_t *needed)
{
    if (!s || !needed) return XYL_ERR_INVALID_ARGUMENT;
    size_t n = 0;
    for (size_t i = 0; i < s->count; ++i) {
        size_t room = buffer && n < capacity ? capacity - n : 0;
        n += format_module(s, i, buffer ? buffer + n : NULL, room);
    }
    *needed = n;
    if (!buffer) return XYL_OK;
    if (capacity < n + 1) return XYL_ERR_INVALID_ARGUMENT;
    buffer[n] = '\0';
    return XYL_OK;
}

/* ---- context matching ---------------------------------------------------------------------- */

/* Modules carry a handful of parameters: a plain loop beats the block copy a memcpy of unknown
 * size becomes. */
static inline void copy_params(double *to, const double *from, uint32_t n)
{
    for (uint32_t k = 0; k < n; ++k) to[k] = from[k];
}

static void bind(const xyl_lstring *s, size_t i, uint16_t var, double *vars)
{
    uint32_t np = lsys_np(s, i);
    if (np) copy_params(vars + var, lsys_par(s, i), np);
}

static bool same_module(const xyl_lstring *s, size_t i, const lsys_pat *pat)
{
    return s->sym[i] == pat->sym && lsys_np(s, i) == pat->nparam;
}

/* Index just before the '[' that opens the branch whose ']' is at i, or SIZE_MAX. */
static size_t skip_branch_left(const xyl_lstring *s, size_t i)
{
    uint32_t depth = 0;
    for (;; --i) {
        uint8_t c = s->sym[i];
        if (c == ']') ++depth;
        else if (c == '[' && --depth == 0) return i == 0 ? SIZE_MAX : i - 1;
        if (i == 0) return SIZE_MAX;
    }
}

/* Left context: walk back over ignored symbols, whole sub-branches "[...]" and the '[' of the
 * branch we are in (its parent's symbols come next). */
static bool match_left(const deriver *d, const lsys_prod *pr, size_t pos, double *vars)
{
    const xyl_lstring *s = d->cur;
    size_t i = pos;
    for (uint32_t j = pr->left_count; j-- > 0;) {
        const lsys_pat *pat = &d->g->pats[pr->left_first + j];
        for (;;) {
            if (i == 0) return false;
            --i;
            uint8_t c = s->sym[i];
            if (c == ']') {
                i = skip_branch_left(s, i);
                if (i == SIZE_MAX) return false;
                ++i; /* the loop's decrement lands on the symbol before '[' */
                continue;
            }
            if (c == '[' || d->g->ignore[c]) continue;
            break;
        }
        if (!same_module(s, i, pat)) return false;
        bind(s, i, pat->var, vars);
    }
    return true;
}

/* Index of the ']' closing the branch that contains i (i inside it), or SIZE_MAX at top level. */
static size_t find_close(const uint8_t *sym, size_t count, size_t i)
{
    uint32_t depth = 0;
    for (; i < count; ++i) {
        if (sym[i] == '[') ++depth;
        else if (sym[i] == ']' && depth-- == 0) return i;
    }
    return SIZE_MAX;
}

/* Right context: a pattern symbol skips ignored symbols and whole sub-branches it does not name;
 * '[' in the pattern enters a branch; ']' in the pattern skips to the end of the current one. */
static bool match_right(const deriver *d, const lsys_prod *pr, size_t pos, double *vars)
{
    const xyl_lstring *s = d->cur;
    size_t i = pos + 1;
    for (uint32_t j = 0; j < pr->right_count; ++j) {
        const lsys_pat *pat = &d->g->pats[pr->right_first + j];
        if (pat->sym == ']') {
            i = find_close(s->sym, s->count, i);
            if (i == SIZE_MAX) return false;
            ++i;
            continue;
        }
        for (; i < s->count; ++i) {
            uint8_t c = s->sym[i];
            if (d->g->ignore[c]) continue;
            if (c == '[' && pat->sym != '[') {
                i = find_close(s->sym, s->count, i + 1);
                if (i == SIZE_MAX) return false;
                continue;
            }
            break;
        }
        if (i >= s->count || !same_module(s, i, pat)) return false;
        bind(s, i, pat->var, vars);
        ++i;
    }
    return true;
}

/* ---- emission ------------------------------------------------------------------------------ */

static xyl_result fail_limit(deriver *d, const char *what, unsigned long long limit)
{
    return xyl__fail(d->diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                     "derivation step %u exceeds the %s limit of %llu", d->step, what, limit);
}

static xyl_result oom(deriver *d)
{
    return xyl__fail(d->diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                     "out of memory at derivation step %u", d->step);
}

/* Bookkeeping for a module just written to next: bracket depth and the cut flag. */
static xyl_result track(deriver *d, uint8_t sym)
{
    d->has_cut |= sym == '%';
    if (sym == ']') --d->depth;
    if (sym == '[' && ++d->depth > d->limits.max_nesting)
        return fail_limit(d, "bracket nesting", d->limits.max_nesting);
    return XYL_OK;
}

/* Appends a module header; the caller writes np parameters at params[nparams ...). */
static void push_module(xyl_lstring *n, uint8_t sym, uint32_t np)
{
    n->sym[n->count] = sym;
    if (n->np) {
        n->np[n->count] = (uint8_t)np;
        n->poff[n->count] = (uint32_t)n->nparams;
    }
    ++n->count;
}

static xyl_result emit_copy(deriver *d, size_t i)
{
    const xyl_lstring *c = d->cur;
    xyl_lstring *n = d->next;
    uint32_t np = lsys_np(c, i);
    if (!reserve(n, n->count + 1, n->nparams + np)) return oom(d);
    if (np) copy_params(n->params + n->nparams, lsys_par(c, i), np);
    push_module(n, c->sym[i], np);
    n->nparams += np;
    return track(d, c->sym[i]);
}

static xyl_result emit_constant(deriver *d, const lsys_prod *pr)
{
    const xyl_grammar *g = d->g;
    xyl_lstring *n = d->next;
    size_t np = pr->const_pcount;
    if (!reserve(n, n->count + pr->const_count, n->nparams + np)) return oom(d);
    if (d->depth + (uint32_t)pr->const_depth_max > d->limits.max_nesting)
        return fail_limit(d, "bracket nesting", d->limits.max_nesting);
    if (pr->const_count == 0) return XYL_OK; /* an erasing production */
    memcpy(n->sym + n->count, g->csyms + pr->const_first, pr->const_count);
    if (n->np) {
        const lsys_module *m = g->cmods + pr->const_first;
        uint32_t base = (uint32_t)n->nparams;
        for (uint32_t i = 0; i < pr->const_count; ++i) {
            n->np[n->count + i] = m[i].nparam;
            n->poff[n->count + i] = base + m[i].param;
        }
        if (np) memcpy(n->params + n->nparams, g->cparams + pr->const_pfirst, np * sizeof(double));
    }
    n->count += pr->const_count;
    n->nparams += np;
    d->has_cut |= pr->const_cut;
    return XYL_OK;
}

static xyl_result emit_successor(deriver *d, const lsys_prod *pr)
{
    const xyl_grammar *g = d->g;
    xyl_lstring *n = d->next;
    if (!reserve(n, n->count + pr->succ_count, n->nparams + pr->succ_pcount)) return oom(d);
    for (uint32_t i = 0; i < pr->succ_count; ++i) {
        const lsys_succ *m = &g->succs[pr->succ_first + i];
        double *out = n->params + n->nparams;
        for (uint32_t k = 0; k < m->nparam; ++k) {
            const lsys_expr *e = &g->exprs[m->expr + k];
            double v = e->constant ? g->code[e->first].k
                                   : xyl__lsys_eval(g, e, d->vars, d->stack, &d->rng);
            if (!isfinite(v))
                return xyl__fail(d->diag, XYL_ERR_NON_FINITE, pr->line, 0, -1,
                                 "production on line %u gave parameter %u of '%c' the value %g at "
                                 "step %u",
                                 pr->line, k + 1, m->sym, v, d->step);
            out[k] = v;
        }
        push_module(n, m->sym, m->nparam);
        n->nparams += m->nparam;
        xyl_result r = track(d, m->sym);
        if (r) return r;
    }
    return XYL_OK;
}

/* ---- production choice --------------------------------------------------------------------- */

/* Evaluates the weights of pr's group and picks one member; *chosen = NULL when all are 0. */
static xyl_result choose(deriver *d, const lsys_prod *pr, const lsys_prod **chosen)
{
    const xyl_grammar *g = d->g;
    double total = 0.0;
    size_t n = 0;
    for (const lsys_prod *q = pr;; q = &g->prods[q->group_next]) {
        double w = xyl__lsys_eval(g, &g->exprs[q->weight], d->vars, d->stack, &d->rng);
        d->weights[n++] = w;
        if (!isfinite(w))
            return xyl__fail(d->diag, XYL_ERR_NON_FINITE, q->line, 0, -1,
                             "weight of the production on line %u is %g", q->line, w);
        if (w < 0.0)
            return xyl__fail(d->diag, XYL_ERR_INVALID_GRAMMAR, q->line, 0, -1,
                             "weight of the production on line %u is negative (%g)", q->line, w);
        total += w;
        if (q->group_next == UINT32_MAX) break;
    }
    *chosen = NULL;
    if (!(total > 0.0)) return XYL_OK;
    double u = lsys_rng_unit(&d->rng) * total, acc = 0.0;
    n = 0;
    for (const lsys_prod *q = pr;; q = &g->prods[q->group_next]) {
        acc += d->weights[n++];
        *chosen = q;
        if (u < acc || q->group_next == UINT32_MAX) return XYL_OK;
    }
}

/* Finds the first production (file order) that applies to module i and emits its successor;
 * *done = false when none applies. */
static xyl_result rewrite_general(deriver *d, size_t i, bool *done)
{
    const xyl_grammar *g = d->g;
    uint8_t sym = d->cur->sym[i];
    uint32_t np = lsys_np(d->cur, i);
    *done = false;
    for (uint32_t k = 0; k < g->sym_count[sym]; ++k) {
        const lsys_prod *pr = &g->prods[g->sym_prods[g->sym_first[sym] + k]];
        if (pr->pred_nparam != np) continue;
        if (pr->left_count && !match_left(d, pr, i, d->vars)) continue;
        if (pr->right_count && !match_right(d, pr, i, d->vars)) continue;
        bind(d->cur, i, pr->pred_var, d->vars);
        if (pr->cond >= 0 && xyl__lsys_eval(g, &g->exprs[pr->cond], d->vars, d->stack, &d->rng) == 0.0)
            continue;
        if (pr->is_constant) {
            *done = true;
            return emit_constant(d, pr);
        }
        if (pr->weight >= 0) {
            const lsys_prod *chosen = NULL;
            xyl_result r = choose(d, pr, &chosen);
            if (r) return r;
            if (!chosen) continue;
            pr = chosen;
        }
        *done = true;
        return emit_successor(d, pr);
    }
    return XYL_OK;
}

/* ---- cut ----------------------------------------------------------------------------------- */

/* '%' erases itself and the rest of its branch up to (not including) the closing ']'. */
static void apply_cut(xyl_lstring *s)
{
    size_t w = 0, wp = 0;
    for (size_t i = 0; i < s->count;) {
        if (s->sym[i] == '%') {
            size_t close = find_close(s->sym, s->count, i + 1);
            i = close == SIZE_MAX ? s->count : close;
            continue;
        }
        uint32_t np = lsys_np(s, i);
        s->sym[w] = s->sym[i];
        if (s->np) {
            memmove(s->params + wp, s->params + s->poff[i], np * sizeof(double));
            s->np[w] = (uint8_t)np;
            s->poff[w] = (uint32_t)wp;
            wp += np;
        }
        ++w;
        ++i;
    }
    s->count = w;
    s->nparams = wp;
}

/* ---- the derivation loop ------------------------------------------------------------------- */

static xyl_result check_size(deriver *d, uint64_t count, uint64_t nparams)
{
    if (count > d->limits.max_modules)
        return fail_limit(d, "module count", (unsigned long long)d->limits.max_modules);
    uint64_t per_module = d->next->np ? 1 + 1 + sizeof(uint32_t) : 1;
    uint64_t bytes = count * per_module + nparams * sizeof(double);
    if (bytes > d->limits.max_bytes || nparams > UINT32_MAX)
        return fail_limit(d, "byte", (unsigned long long)d->limits.max_bytes);
    return XYL_OK;
}

/* General path: module by module, any production kind. */
static xyl_result step_general(deriver *d)
{
    const xyl_grammar *g = d->g;
    const xyl_lstring *cur = d->cur;
    xyl_lstring *n = d->next;
    if (!reserve(n, cur->count + cur->count / 2, cur->nparams + cur->nparams / 2)) return oom(d);
    for (size_t i = 0; i < cur->count; ++i) {
        uint8_t sym = cur->sym[i];
        xyl_result r = XYL_OK;
        bool done = false;
        int32_t k = g->constant_prod[sym];
        if (k >= 0 && lsys_np(cur, i) == 0) {
            r = emit_constant(d, &g->prods[k]);
            done = true;
        }
        if (!done && !r && g->sym_count[sym]) r = rewrite_general(d, i, &done);
        if (!done && !r) r = emit_copy(d, i);
        if (!r) r = check_size(d, n->count, n->nparams);
        if (r) return r;
    }
    return XYL_OK;
}

/* ---- byte path ----------------------------------------------------------------------------- */

/* Symbol counts and deepest bracket nesting of s, by one pass. */
static int64_t measure_bytes(const xyl_grammar *g, const xyl_lstring *s, uint64_t *hist,
                             bool rewrite)
{
    int64_t depth = 0, deepest = 0;
    if (hist) memset(hist, 0, 256 * sizeof *hist);
    for (size_t i = 0; i < s->count; ++i) {
        uint8_t c = s->sym[i];
        if (hist) ++hist[c];
        int64_t top = depth + (rewrite ? g->byte_dmax[c] : c == '[');
        if (top > deepest) deepest = top;
        depth += rewrite ? g->byte_delta[c] : (c == '[') - (c == ']');
    }
    return deepest;
}

/* The next string's symbol counts follow from the current ones through the successors. */
static void next_histogram(const xyl_grammar *g, const uint64_t *cur, uint64_t *next)
{
    memset(next, 0, 256 * sizeof *next);
    for (int c = 0; c < 256; ++c) {
        if (!cur[c]) continue;
        const uint8_t *succ = g->byte_table + g->byte_src[c];
        for (uint32_t j = 0; j < g->byte_len[c]; ++j) next[succ[j]] += cur[c];
    }
}

/* Byte path: every symbol is copied or rewritten by one constant production without parameters.
 * The next string's exact size comes from the symbol counts and its nesting from a bound (an
 * exact pass runs only when the bound could reach the limit), so limits are checked before
 * anything is allocated; the write pass copies each successor with one fixed 16- or 32-byte
 * move when all successors are that short. */
static xyl_result step_bytes(deriver *d)
{
    const xyl_grammar *g = d->g;
    const xyl_lstring *cur = d->cur;
    uint64_t hist[256], total = 0;
    int32_t grow = 0;
    next_histogram(g, d->hist, hist);
    for (int c = 0; c < 256; ++c) {
        total += hist[c];
        if (d->hist[c] && g->byte_dmax[c] > grow) grow = g->byte_dmax[c];
    }
    int64_t bound = d->depth_bound + grow;
    if (bound > (int64_t)d->limits.max_nesting) bound = measure_bytes(g, cur, NULL, true);
    if (bound > (int64_t)d->limits.max_nesting)
        return fail_limit(d, "bracket nesting", d->limits.max_nesting);
    xyl_result r = check_size(d, total, 0);
    if (r) return r;
    xyl_lstring *n = d->next;
    if (!reserve(n, (size_t)total + 32, 0)) return oom(d);
    uint8_t *out = n->sym;
    const uint8_t *table = g->byte_table, *in = cur->sym, *end = cur->sym + cur->count;
    if (g->byte_max_len <= 16) {
        for (const uint8_t *p = in; p < end; ++p) {
            memcpy(out, table + g->byte_src[*p], 16);
            out += g->byte_len[*p];
        }
    } else if (g->byte_max_len <= 32) {
        for (const uint8_t *p = in; p < end; ++p) {
            memcpy(out, table + g->byte_src[*p], 32);
            out += g->byte_len[*p];
        }
    } else {
        for (const uint8_t *p = in; p < end; ++p) {
            memcpy(out, table + g->byte_src[*p], g->byte_len[*p]);
            out += g->byte_len[*p];
        }
    }
    n->count = (size_t)total;
    memcpy(d->hist, hist, sizeof hist);
    d->depth_bound = bound;
    d->has_cut = hist['%'] != 0;
    return XYL_OK;
}

/* After the axiom is loaded or a cut changed the string: exact counts and depth again. */
static void remeasure(deriver *d, const xyl_lstring *s)
{
    if (d->bytes) d->depth_bound = measure_bytes(d->g, s, d->hist, false);
}

static xyl_result step(deriver *d)
{
    d->next->count = 0;
    d->next->nparams = 0;
    d->depth = 0;
    d->has_cut = false;
    xyl_result r = d->bytes ? step_bytes(d) : step_general(d);
    if (!r && d->has_cut) {
        apply_cut(d->next);
        remeasure(d, d->next);
    }
    return r;
}

static xyl_result load_axiom(deriver *d, xyl_lstring *s)
{
    const xyl_grammar *g = d->g;
    d->next = s;
    xyl_result r = check_size(d, g->axiom_count, g->axiom_nparams);
    if (r) return r;
    if (!reserve(s, g->axiom_count, g->axiom_nparams)) return oom(d);
    for (size_t i = 0; i < g->axiom_count; ++i) {
        const lsys_module *m = &g->axiom[i];
        push_module(s, m->sym, m->nparam);
        if (m->nparam)
            memcpy(s->params + s->nparams, g->axiom_params + m->param, m->nparam * sizeof(double));
        s->nparams += m->nparam;
        r = track(d, m->sym);
        if (r) return r;
    }
    if (d->has_cut) apply_cut(s);
    remeasure(d, s);
    return XYL_OK;
}

/* Byte path without cuts: the symbol counts predict every step's size, so both strings are
 * allocated once, and a string that would pass the module or byte limit is refused before any
 * rewriting. (A cut shrinks strings unpredictably; then sizes are found step by step.) */
static xyl_result presize(deriver *d, uint32_t depth, xyl_lstring *a, xyl_lstring *b)
{
    const xyl_grammar *g = d->g;
    for (int c = 0; c < 256; ++c)
        if (g->byte_cut[c]) return XYL_OK;
    uint64_t hist[256], next[256], largest = a->count;
    memcpy(hist, d->hist, sizeof hist);
    for (uint32_t k = 0; k < depth; ++k) {
        next_histogram(g, hist, next);
        uint64_t total = 0;
        for (int c = 0; c < 256; ++c) total += next[c];
        d->step = k + 1;
        xyl_result r = check_size(d, total, 0);
        if (r) return r;
        if (total > largest) largest = total;
        memcpy(hist, next, sizeof hist);
    }
    size_t cap = (size_t)largest + 32;
    return reserve(a, cap, 0) && reserve(b, cap, 0) ? XYL_OK : oom(d);
}

static xyl_result run(deriver *d, uint32_t depth, xyl_lstring **a, xyl_lstring **b)
{
    xyl_result r = load_axiom(d, *a);
    if (!r && d->bytes) r = presize(d, depth, *a, *b);
    for (uint32_t k = 0; k < depth && !r; ++k) {
        d->step = k + 1;
        d->cur = *a;
        d->next = *b;
        r = step(d);
        xyl_lstring *t = *a;
        *a = *b;
        *b = t;
    }
    return r;
}

xyl_result xyl_lsystem_derive(const xyl_grammar *g, const xyl_derive_desc *desc,
                              xyl_lstring **out, xyl_diag *diag)
{
    static const xyl_derive_desc zero;
    if (!g || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "grammar and out must not be NULL");
    if (!desc) desc = &zero;
    deriver d;
    memset(&d, 0, sizeof d);
    d.g = g;
    d.diag = diag;
    d.limits = desc->limits;
    xyl__lsys_resolve_limits(&d.limits, &g->limits);
    uint32_t depth = desc->has_depth ? desc->depth : g->info.depth;
    if (depth > d.limits.max_depth)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "derivation depth %u exceeds the limit of %u", depth, d.limits.max_depth);
    d.rng.state = desc->has_seed ? desc->seed : g->info.seed;
    const xyl_allocator *a = &desc->alloc;
    d.bytes = g->all_constant && !g->parametric;
    xyl_lstring *sa = new_string(a, g->parametric), *sb = new_string(a, g->parametric);
    bool ok = sa && sb;
    if (!d.bytes) { /* scratch for expressions and stochastic choice */
        d.vars = xyl__calloc(a, g->max_vars + 1, sizeof(double));
        d.stack = xyl__calloc(a, g->max_stack + 1, sizeof(double));
        d.weights = xyl__calloc(a, g->prod_count + 1, sizeof(double));
        ok = ok && d.vars && d.stack && d.weights;
    }
    xyl_result r = ok ? run(&d, depth, &sa, &sb) : oom(&d);
    xyl__free(a, d.weights);
    xyl__free(a, d.vars);
    xyl__free(a, d.stack);
    xyl_lstring_destroy(sb);
    if (r) {
        xyl_lstring_destroy(sa);
        return r;
    }
    *out = sa;
    xyl__diag_ok(diag);
    return XYL_OK;
}
