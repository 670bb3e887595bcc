/* Parallel rewriting: context matching (ABOP bracket rules), conditions, stochastic choice,
 * parametric successors, the cut symbol, and every bound checked on the way. */
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
} deriver;

/* ---- strings ------------------------------------------------------------------------------- */

static bool reserve(xyl_lstring *s, size_t mods, size_t params)
{
    return xyl__grow(&s->alloc, (void **)&s->mods, &s->cap, s->count, mods, sizeof *s->mods) &&
           xyl__grow(&s->alloc, (void **)&s->params, &s->pcap, s->nparams, params,
                     sizeof *s->params);
}

void xyl_lstring_destroy(xyl_lstring *s)
{
    if (!s) return;
    xyl_allocator a = s->alloc;
    xyl__free(&a, s->mods);
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
    const lsys_module *m = &s->mods[index];
    out->symbol = (char)m->sym;
    out->param_count = m->nparam;
    out->params = m->nparam ? s->params + m->param : NULL;
    return XYL_OK;
}

static size_t format_module(const xyl_lstring *s, const lsys_module *m, char *out, size_t cap)
{
    char tmp[32];
    size_t n = 0;
    if (n < cap) out[n] = (char)m->sym;
    ++n;
    for (uint32_t k = 0; k < m->nparam; ++k) {
        int w = snprintf(tmp, sizeof tmp, "%c%.9g", k ? ',' : '(', s->params[m->param + k]);
        for (int i = 0; i < w; ++i, ++n)
            if (n < cap) out[n] = tmp[i];
    }
    if (m->nparam) {
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
        n += format_module(s, &s->mods[i], buffer ? buffer + n : NULL, room);
    }
    *needed = n;
    if (!buffer) return XYL_OK;
    if (capacity < n + 1) return XYL_ERR_INVALID_ARGUMENT;
    buffer[n] = '\0';
    return XYL_OK;
}

/* ---- context matching ---------------------------------------------------------------------- */

static void bind(const xyl_lstring *s, size_t i, uint16_t var, double *vars)
{
    const lsys_module *m = &s->mods[i];
    for (uint32_t k = 0; k < m->nparam; ++k) vars[var + k] = s->params[m->param + k];
}

/* Index just before the '[' that opens the branch whose ']' is at i, or SIZE_MAX. */
static size_t skip_branch_left(const xyl_lstring *s, size_t i)
{
    uint32_t depth = 0;
    for (;; --i) {
        uint8_t c = s->mods[i].sym;
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
            uint8_t c = s->mods[i].sym;
            if (c == ']') {
                i = skip_branch_left(s, i);
                if (i == SIZE_MAX) return false;
                ++i; /* the loop's decrement lands on the symbol before '[' */
                continue;
            }
            if (c == '[' || d->g->ignore[c]) continue;
            break;
        }
        if (s->mods[i].sym != pat->sym || s->mods[i].nparam != pat->nparam) return false;
        bind(s, i, pat->var, vars);
    }
    return true;
}

/* Index of the ']' closing the branch that contains i (i inside it), or SIZE_MAX at top level. */
static size_t find_close(const xyl_lstring *s, size_t i)
{
    uint32_t depth = 0;
    for (; i < s->count; ++i) {
        uint8_t c = s->mods[i].sym;
        if (c == '[') ++depth;
        else if (c == ']' && depth-- == 0) return i;
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
            i = find_close(s, i);
            if (i == SIZE_MAX) return false;
            ++i;
            continue;
        }
        for (; i < s->count; ++i) {
            uint8_t c = s->mods[i].sym;
            if (d->g->ignore[c]) continue;
            if (c == '[' && pat->sym != '[') {
                i = find_close(s, i + 1);
                if (i == SIZE_MAX) return false;
                continue;
            }
            break;
        }
        if (i >= s->count) return false;
        if (s->mods[i].sym != pat->sym || s->mods[i].nparam != pat->nparam) return false;
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

static xyl_result emit_copy(deriver *d, size_t i)
{
    const lsys_module *m = &d->cur->mods[i];
    xyl_lstring *n = d->next;
    if (!reserve(n, n->count + 1, n->nparams + m->nparam)) return oom(d);
    lsys_module out = *m;
    out.param = (uint32_t)n->nparams;
    memcpy(n->params + n->nparams, d->cur->params + m->param, m->nparam * sizeof(double));
    n->nparams += m->nparam;
    n->mods[n->count++] = out;
    return track(d, m->sym);
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
    lsys_module *out = n->mods + n->count;
    memcpy(out, g->cmods + pr->const_first, pr->const_count * sizeof *out);
    uint32_t base = (uint32_t)n->nparams;
    for (uint32_t i = 0; i < pr->const_count; ++i) {
        out[i].param += base;
        d->has_cut |= out[i].sym == '%';
    }
    if (np) memcpy(n->params + n->nparams, g->cparams + pr->const_pfirst, np * sizeof(double));
    n->nparams += np;
    n->count += pr->const_count;
    return XYL_OK;
}

static xyl_result emit_successor(deriver *d, const lsys_prod *pr)
{
    const xyl_grammar *g = d->g;
    xyl_lstring *n = d->next;
    for (uint32_t i = 0; i < pr->succ_count; ++i) {
        const lsys_succ *m = &g->succs[pr->succ_first + i];
        if (!reserve(n, n->count + 1, n->nparams + m->nparam)) return oom(d);
        lsys_module out = {m->sym, m->nparam, 0, (uint32_t)n->nparams};
        for (uint32_t k = 0; k < m->nparam; ++k) {
            const lsys_expr *e = &g->exprs[m->expr + k];
            double v = e->constant ? g->code[e->first].k
                                   : lsys_eval(g, e, d->vars, d->stack, &d->rng);
            if (!isfinite(v))
                return xyl__fail(d->diag, XYL_ERR_NON_FINITE, pr->line, 0, -1,
                                 "production on line %u gave parameter %u of '%c' the value %g at "
                                 "step %u",
                                 pr->line, k + 1, m->sym, v, d->step);
            n->params[n->nparams++] = v;
        }
        n->mods[n->count++] = out;
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
        double w = lsys_eval(g, &g->exprs[q->weight], d->vars, d->stack, &d->rng);
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
    const lsys_module *m = &d->cur->mods[i];
    *done = false;
    for (uint32_t k = 0; k < g->sym_count[m->sym]; ++k) {
        const lsys_prod *pr = &g->prods[g->sym_prods[g->sym_first[m->sym] + k]];
        if (pr->pred_nparam != m->nparam) continue;
        if (pr->left_count && !match_left(d, pr, i, d->vars)) continue;
        if (pr->right_count && !match_right(d, pr, i, d->vars)) continue;
        bind(d->cur, i, pr->pred_var, d->vars);
        if (pr->cond >= 0 && lsys_eval(g, &g->exprs[pr->cond], d->vars, d->stack, &d->rng) == 0.0)
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
        if (s->mods[i].sym == '%') {
            size_t close = find_close(s, i + 1);
            i = close == SIZE_MAX ? s->count : close;
            continue;
        }
        lsys_module m = s->mods[i++];
        memmove(s->params + wp, s->params + m.param, m.nparam * sizeof(double));
        m.param = (uint32_t)wp;
        wp += m.nparam;
        s->mods[w++] = m;
    }
    s->count = w;
    s->nparams = wp;
}

/* ---- the derivation loop ------------------------------------------------------------------- */

static xyl_result check_size(deriver *d, const xyl_lstring *s)
{
    if ((uint64_t)s->count > d->limits.max_modules)
        return fail_limit(d, "module count", (unsigned long long)d->limits.max_modules);
    uint64_t bytes = (uint64_t)s->count * sizeof(lsys_module) + (uint64_t)s->nparams * sizeof(double);
    if (bytes > d->limits.max_bytes || s->nparams > UINT32_MAX)
        return fail_limit(d, "byte", (unsigned long long)d->limits.max_bytes);
    return XYL_OK;
}

static xyl_result step(deriver *d)
{
    const xyl_grammar *g = d->g;
    const xyl_lstring *cur = d->cur;
    xyl_lstring *n = d->next;
    n->count = 0;
    n->nparams = 0;
    d->depth = 0;
    d->has_cut = false;
    if (!reserve(n, cur->count + cur->count / 2, cur->nparams + cur->nparams / 2)) return oom(d);
    for (size_t i = 0; i < cur->count; ++i) {
        const lsys_module *m = &cur->mods[i];
        xyl_result r = XYL_OK;
        bool done = false;
        if (g->sym_count[m->sym] == 1) {
            const lsys_prod *pr = &g->prods[g->sym_prods[g->sym_first[m->sym]]];
            if (pr->is_constant && pr->pred_nparam == m->nparam) {
                r = emit_constant(d, pr);
                done = true;
            }
        }
        if (!done && g->sym_count[m->sym] && !r) r = rewrite_general(d, i, &done);
        if (!done && !r) r = emit_copy(d, i);
        if (!r) r = check_size(d, n);
        if (r) return r;
    }
    if (d->has_cut) apply_cut(n);
    return XYL_OK;
}

static xyl_result load_axiom(deriver *d, xyl_lstring *s)
{
    const xyl_grammar *g = d->g;
    if (!reserve(s, g->axiom_count, g->axiom_nparams)) return oom(d);
    memcpy(s->mods, g->axiom, g->axiom_count * sizeof *s->mods);
    memcpy(s->params, g->axiom_params, g->axiom_nparams * sizeof *s->params);
    s->count = g->axiom_count;
    s->nparams = g->axiom_nparams;
    bool cut = false;
    uint32_t depth = 0;
    for (size_t i = 0; i < s->count; ++i) {
        cut |= s->mods[i].sym == '%';
        if (s->mods[i].sym == '[' && ++depth > d->limits.max_nesting)
            return fail_limit(d, "bracket nesting", d->limits.max_nesting);
        if (s->mods[i].sym == ']') --depth;
    }
    if (cut) apply_cut(s);
    return check_size(d, s);
}

static xyl_lstring *new_string(const xyl_allocator *a)
{
    xyl_lstring *s = xyl__calloc(a, 1, sizeof *s);
    if (s && a) s->alloc = *a;
    return s;
}

static xyl_result run(deriver *d, uint32_t depth, xyl_lstring **a, xyl_lstring **b)
{
    xyl_result r = load_axiom(d, *a);
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
    lsys_resolve_limits(&d.limits, &g->limits);
    uint32_t depth = desc->has_depth ? desc->depth : g->info.depth;
    if (depth > d.limits.max_depth)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "derivation depth %u exceeds the limit of %u", depth, d.limits.max_depth);
    d.rng.state = desc->has_seed ? desc->seed : g->info.seed;
    const xyl_allocator *a = &desc->alloc;
    xyl_lstring *sa = new_string(a), *sb = new_string(a);
    d.vars = xyl__calloc(a, g->max_vars + 1, sizeof(double));
    d.stack = xyl__calloc(a, g->max_stack + 1, sizeof(double));
    d.weights = xyl__calloc(a, g->prod_count + 1, sizeof(double));
    bool ok = sa && sb && d.vars && d.stack && d.weights;
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
