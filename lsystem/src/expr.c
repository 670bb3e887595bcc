/* Expressions: numeric literals, a precedence-climbing compiler to postfix code, and the
 * evaluator the derivation runs for every parameter. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lsys_parse.h"

bool xyl__lsys_is_symbol(char c)
{
    if (lsys_is_alpha(c) || lsys_is_digit(c)) return true;
    return c != '\0' && strchr("+-&^\\/|[]!$%'\".~?*@_={}`", c) != NULL;
}

/* ---- numbers ------------------------------------------------------------------------------- */

/* Rewrites the literal as "<digits>e<exp>" without a radix character, so strtod gives the
 * correctly rounded value whatever the process locale is. */
xyl_result xyl__lsys_parse_number(lsys_parser *p, size_t *pos, size_t end, double *out)
{
    const char *s = p->src;
    size_t start = *pos, i = *pos;
    char buf[LSYS_MAX_NUMBER_CHARS + 32];
    size_t n = 0;
    long exp10 = 0;
    bool any = false;
    for (; i < end && lsys_is_digit(s[i]); ++i, any = true)
        if (n < LSYS_MAX_NUMBER_CHARS) buf[n++] = s[i];
        else ++exp10; /* drop digits past the buffer: only the exponent matters then */
    if (i < end && s[i] == '.') {
        for (++i; i < end && lsys_is_digit(s[i]); ++i, any = true)
            if (n < LSYS_MAX_NUMBER_CHARS) {
                buf[n++] = s[i];
                --exp10;
            }
    }
    if (!any) return xyl__lsys_error_at(p, start, XYL_ERR_INVALID_GRAMMAR, "expected a number");
    if (i < end && (s[i] == 'e' || s[i] == 'E')) {
        size_t j = i + 1;
        bool neg = false;
        if (j < end && (s[j] == '+' || s[j] == '-')) neg = s[j++] == '-';
        if (j >= end || !lsys_is_digit(s[j]))
            return xyl__lsys_error_at(p, j, XYL_ERR_INVALID_GRAMMAR, "expected digits after the exponent");
        long e = 0;
        for (; j < end && lsys_is_digit(s[j]); ++j)
            if (e < 100000) e = e * 10 + (s[j] - '0');
        exp10 += neg ? -e : e;
        i = j;
    }
    if (i - start > LSYS_MAX_NUMBER_CHARS)
        return xyl__lsys_error_at(p, start, XYL_ERR_INVALID_GRAMMAR, "number literal is too long");
    snprintf(buf + n, sizeof buf - n, "e%ld", exp10);
    double v = strtod(buf, NULL);
    if (!isfinite(v))
        return xyl__lsys_error_at(p, start, XYL_ERR_NON_FINITE, "number '%.*s' is out of range",
                             (int)(i - start), s + start);
    *pos = i;
    *out = v;
    return XYL_OK;
}

/* ---- compiler ------------------------------------------------------------------------------ */

typedef struct compiler {
    lsys_parser *p;
    size_t pos, end;
    uint32_t height, max_height; /* evaluation stack */
    uint32_t max_depth;
    bool has_var;
} compiler;

static xyl_result emit(compiler *c, uint32_t op, uint32_t arg, double k, int push)
{
    xyl_grammar *g = c->p->g;
    if (!xyl__grow(&g->alloc, (void **)&g->code, &c->p->code_cap, g->code_count,
                   g->code_count + 1, sizeof *g->code))
        return xyl__lsys_error_at(c->p, c->pos, XYL_ERR_OUT_OF_MEMORY, "out of memory");
    lsys_insn in = {op, arg, k};
    g->code[g->code_count++] = in;
    c->height = (uint32_t)((int)c->height + push);
    if (c->height > c->max_height) c->max_height = c->height;
    return XYL_OK;
}

static void skip(compiler *c)
{
    lsys_skip_space(c->p->src, &c->pos, c->end);
}

static bool accept(compiler *c, const char *tok)
{
    skip(c);
    size_t n = strlen(tok);
    if (c->pos + n > c->end || memcmp(c->p->src + c->pos, tok, n) != 0) return false;
    c->pos += n;
    return true;
}

typedef struct func_def {
    const char *name;
    lsys_opcode op;
    uint32_t arity;
} func_def;

static const func_def funcs[] = {
    {"sin", OP_SIN, 1},     {"cos", OP_COS, 1},     {"tan", OP_TAN, 1},
    {"asin", OP_ASIN, 1},   {"acos", OP_ACOS, 1},   {"atan", OP_ATAN, 1},
    {"atan2", OP_ATAN2, 2}, {"sqrt", OP_SQRT, 1},   {"abs", OP_ABS, 1},
    {"min", OP_MIN, 2},     {"max", OP_MAX, 2},     {"floor", OP_FLOOR, 1},
    {"ceil", OP_CEIL, 1},   {"exp", OP_EXP, 1},     {"log", OP_LOG, 1},
    {"rand", OP_RAND, 0},
};

static xyl_result parse_binary(compiler *c, int min_prec, uint32_t depth);

static xyl_result parse_call(compiler *c, const func_def *f, size_t at, uint32_t depth)
{
    if (!accept(c, "("))
        return xyl__lsys_error_at(c->p, c->pos, XYL_ERR_INVALID_GRAMMAR, "expected '(' after %s",
                             f->name);
    for (uint32_t i = 0; i < f->arity; ++i) {
        if (i > 0 && !accept(c, ","))
            return xyl__lsys_error_at(c->p, c->pos, XYL_ERR_INVALID_GRAMMAR,
                                 "%s takes %u arguments", f->name, f->arity);
        xyl_result r = parse_binary(c, 1, depth + 1);
        if (r) return r;
    }
    if (!accept(c, ")"))
        return xyl__lsys_error_at(c->p, at, XYL_ERR_INVALID_GRAMMAR, "%s takes %u argument%s", f->name,
                             f->arity, f->arity == 1 ? "" : "s");
    if (f->op == OP_RAND) c->has_var = true; /* never folded */
    return emit(c, f->op, 0, 0.0, 1 - (int)f->arity);
}

static xyl_result parse_name(compiler *c, uint32_t depth)
{
    const char *s = c->p->src;
    size_t at = c->pos, n = 0;
    while (at + n < c->end && lsys_is_ident_char(s[at + n])) ++n;
    c->pos = at + n;
    for (uint32_t v = 0; v < c->p->var_count; ++v) {
        if (c->p->vars[v].n == n && memcmp(c->p->vars[v].s, s + at, n) == 0) {
            c->has_var = true;
            return emit(c, OP_VAR, v, 0.0, 1);
        }
    }
    for (size_t d = c->p->define_count; d-- > 0;) {
        const lsys_define *def = &c->p->defines[d];
        if (def->name.n == n && memcmp(def->name.s, s + at, n) == 0)
            return emit(c, OP_CONST, 0, def->value, 1);
    }
    for (size_t f = 0; f < sizeof funcs / sizeof funcs[0]; ++f)
        if (strlen(funcs[f].name) == n && memcmp(funcs[f].name, s + at, n) == 0)
            return parse_call(c, &funcs[f], at, depth);
    return xyl__lsys_error_at(c->p, at, XYL_ERR_INVALID_GRAMMAR,
                         "unknown name '%.*s' (not a parameter, #define or function)", (int)n,
                         s + at);
}

static xyl_result parse_primary(compiler *c, uint32_t depth)
{
    if (depth > c->max_depth)
        return xyl__lsys_error_at(c->p, c->pos, XYL_ERR_LIMIT_EXCEEDED,
                             "expression nests deeper than the limit of %u", c->max_depth);
    skip(c);
    if (c->pos >= c->end)
        return xyl__lsys_error_at(c->p, c->pos, XYL_ERR_INVALID_GRAMMAR, "expected a value");
    char ch = c->p->src[c->pos];
    if (lsys_is_digit(ch) || ch == '.') {
        double v;
        xyl_result r = xyl__lsys_parse_number(c->p, &c->pos, c->end, &v);
        return r ? r : emit(c, OP_CONST, 0, v, 1);
    }
    if (lsys_is_alpha(ch) || ch == '_') return parse_name(c, depth);
    if (ch == '(') {
        size_t at = c->pos++;
        xyl_result r = parse_binary(c, 1, depth + 1);
        if (r) return r;
        if (!accept(c, ")"))
            return xyl__lsys_error_at(c->p, at, XYL_ERR_INVALID_GRAMMAR, "'(' is never closed");
        return XYL_OK;
    }
    return xyl__lsys_error_at(c->p, c->pos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c' in expression",
                         ch);
}

static xyl_result parse_unary(compiler *c, uint32_t depth);

/* '^' binds tighter than unary minus (-2^2 = -4) and is right-associative (2^3^2 = 512). */
static xyl_result parse_power(compiler *c, uint32_t depth)
{
    xyl_result r = parse_primary(c, depth);
    if (r) return r;
    if (!accept(c, "^")) return XYL_OK;
    r = parse_unary(c, depth + 1);
    return r ? r : emit(c, OP_POW, 0, 0.0, -1);
}

static xyl_result parse_unary(compiler *c, uint32_t depth)
{
    if (depth > c->max_depth)
        return xyl__lsys_error_at(c->p, c->pos, XYL_ERR_LIMIT_EXCEEDED,
                             "expression nests deeper than the limit of %u", c->max_depth);
    skip(c);
    if (c->pos < c->end) {
        char ch = c->p->src[c->pos];
        bool not_eq = ch == '!' && c->pos + 1 < c->end && c->p->src[c->pos + 1] == '=';
        if (ch == '-' || ch == '+' || (ch == '!' && !not_eq)) {
            ++c->pos;
            xyl_result r = parse_unary(c, depth + 1);
            if (r || ch == '+') return r;
            return emit(c, ch == '-' ? OP_NEG : OP_NOT, 0, 0.0, 0);
        }
    }
    return parse_power(c, depth);
}

typedef struct binop {
    const char *tok;
    int prec;
    lsys_opcode op;
} binop;

/* Two-character operators first so "<=" is not read as "<". */
static const binop binops[] = {
    {"||", 1, OP_OR}, {"&&", 2, OP_AND}, {"==", 3, OP_EQ}, {"!=", 3, OP_NE},
    {"<=", 4, OP_LE}, {">=", 4, OP_GE},  {"<", 4, OP_LT},  {">", 4, OP_GT},
    {"+", 5, OP_ADD}, {"-", 5, OP_SUB},  {"*", 6, OP_MUL}, {"/", 6, OP_DIV},
};

static const binop *peek_binop(compiler *c)
{
    skip(c);
    for (size_t i = 0; i < sizeof binops / sizeof binops[0]; ++i) {
        size_t n = strlen(binops[i].tok);
        if (c->pos + n <= c->end && memcmp(c->p->src + c->pos, binops[i].tok, n) == 0) {
            /* "->" ends a condition; it is not a minus. */
            if (binops[i].op == OP_SUB && c->pos + 1 < c->end && c->p->src[c->pos + 1] == '>')
                return NULL;
            return &binops[i];
        }
    }
    return NULL;
}

static xyl_result parse_binary(compiler *c, int min_prec, uint32_t depth)
{
    xyl_result r = parse_unary(c, depth);
    if (r) return r;
    for (;;) {
        const binop *b = peek_binop(c);
        if (!b || b->prec < min_prec) return XYL_OK;
        c->pos += strlen(b->tok);
        r = parse_binary(c, b->prec + 1, depth + 1);
        if (r) return r;
        r = emit(c, b->op, 0, 0.0, -1);
        if (r) return r;
    }
}

xyl_result xyl__lsys_compile_expr(lsys_parser *p, size_t *pos, size_t end, lsys_expr *out)
{
    xyl_grammar *g = p->g;
    compiler c = {p, *pos, end, 0, 0, g->limits.max_expr_depth, false};
    uint32_t first = (uint32_t)g->code_count;
    xyl_result r = parse_binary(&c, 1, 1);
    if (r) return r;
    skip(&c);
    if (c.pos < end && p->src[c.pos] != ',' && p->src[c.pos] != ')')
        return xyl__lsys_error_at(p, c.pos, XYL_ERR_INVALID_GRAMMAR, "unexpected '%c' in expression",
                             p->src[c.pos]);
    lsys_expr e = {first, (uint32_t)g->code_count - first, c.max_height, !c.has_var};
    if (e.constant) {
        double stack[LSYS_DEFAULT_MAX_EXPR_DEPTH * 2 + 8];
        double *st = stack;
        double *heap = NULL;
        if (e.stack > sizeof stack / sizeof stack[0]) {
            heap = xyl__calloc(&g->alloc, e.stack, sizeof *heap);
            if (!heap) return xyl__lsys_error_at(p, *pos, XYL_ERR_OUT_OF_MEMORY, "out of memory");
            st = heap;
        }
        double v = xyl__lsys_eval(g, &e, NULL, st, NULL);
        xyl__free(&g->alloc, heap);
        g->code_count = first + 1;
        g->code[first].op = OP_CONST;
        g->code[first].k = v;
        e.count = 1;
        e.stack = 1;
    }
    if (e.stack > g->max_stack) g->max_stack = e.stack;
    *out = e;
    *pos = c.pos;
    return XYL_OK;
}

xyl_result xyl__lsys_const_expr(lsys_parser *p, size_t *pos, size_t end, double *out)
{
    uint32_t saved_vars = p->var_count;
    lsys_skip_space(p->src, pos, end);
    size_t at = *pos;
    p->var_count = 0;
    lsys_expr e;
    xyl_result r = xyl__lsys_compile_expr(p, pos, end, &e);
    p->var_count = saved_vars;
    if (r) return r;
    if (!e.constant)
        return xyl__lsys_error_at(p, at, XYL_ERR_INVALID_GRAMMAR, "expected a constant expression");
    *out = p->g->code[e.first].k;
    p->g->code_count = e.first; /* constants need no code */
    if (!isfinite(*out))
        return xyl__lsys_error_at(p, at, XYL_ERR_NON_FINITE, "expression evaluates to %g", *out);
    return XYL_OK;
}

/* ---- evaluator ----------------------------------------------------------------------------- */

static inline double truth(bool b)
{
    return b ? 1.0 : 0.0;
}

double xyl__lsys_eval(const xyl_grammar *g, const lsys_expr *e, const double *vars, double *stack,
                 lsys_rng *rng)
{
    const lsys_insn *in = g->code + e->first;
    const lsys_insn *stop = in + e->count;
    double *sp = stack; /* next free slot */
    for (; in < stop; ++in) {
        double b;
        switch ((lsys_opcode)in->op) {
        case OP_CONST: *sp++ = in->k; break;
        case OP_VAR: *sp++ = vars[in->arg]; break;
        case OP_NEG: sp[-1] = -sp[-1]; break;
        case OP_NOT: sp[-1] = truth(sp[-1] == 0.0); break;
        case OP_SIN: sp[-1] = sin(sp[-1] * (XYL__PI / 180.0)); break;
        case OP_COS: sp[-1] = cos(sp[-1] * (XYL__PI / 180.0)); break;
        case OP_TAN: sp[-1] = tan(sp[-1] * (XYL__PI / 180.0)); break;
        case OP_ASIN: sp[-1] = asin(sp[-1]) * (180.0 / XYL__PI); break;
        case OP_ACOS: sp[-1] = acos(sp[-1]) * (180.0 / XYL__PI); break;
        case OP_ATAN: sp[-1] = atan(sp[-1]) * (180.0 / XYL__PI); break;
        case OP_SQRT: sp[-1] = sqrt(sp[-1]); break;
        case OP_ABS: sp[-1] = fabs(sp[-1]); break;
        case OP_FLOOR: sp[-1] = floor(sp[-1]); break;
        case OP_CEIL: sp[-1] = ceil(sp[-1]); break;
        case OP_EXP: sp[-1] = exp(sp[-1]); break;
        case OP_LOG: sp[-1] = log(sp[-1]); break;
        case OP_RAND: *sp++ = rng ? lsys_rng_unit(rng) : 0.0; break;
        default:
            b = *--sp;
            switch ((lsys_opcode)in->op) {
            case OP_ADD: sp[-1] += b; break;
            case OP_SUB: sp[-1] -= b; break;
            case OP_MUL: sp[-1] *= b; break;
            case OP_DIV: sp[-1] /= b; break;
            case OP_POW: sp[-1] = pow(sp[-1], b); break;
            case OP_LT: sp[-1] = truth(sp[-1] < b); break;
            case OP_LE: sp[-1] = truth(sp[-1] <= b); break;
            case OP_GT: sp[-1] = truth(sp[-1] > b); break;
            case OP_GE: sp[-1] = truth(sp[-1] >= b); break;
            case OP_EQ: sp[-1] = truth(sp[-1] == b); break;
            case OP_NE: sp[-1] = truth(sp[-1] != b); break;
            case OP_AND: sp[-1] = truth(sp[-1] != 0.0 && b != 0.0); break;
            case OP_OR: sp[-1] = truth(sp[-1] != 0.0 || b != 0.0); break;
            case OP_ATAN2: sp[-1] = atan2(sp[-1], b) * (180.0 / XYL__PI); break;
            case OP_MIN: sp[-1] = sp[-1] < b ? sp[-1] : b; break;
            case OP_MAX: sp[-1] = sp[-1] > b ? sp[-1] : b; break;
            default: break;
            }
        }
    }
    return sp[-1];
}
