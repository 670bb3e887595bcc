/* lsystem internals: the module string layout, the compiled grammar, the PRNG. Not installed. */
#ifndef XYL_LSYS_INTERNAL_H
#define XYL_LSYS_INTERNAL_H

#include "xyl_internal.h"
#include "xylem/xyl_lsystem.h"

#define LSYS_DEFAULT_MAX_DEPTH 64u
#define LSYS_DEFAULT_MAX_MODULES (UINT64_C(1) << 27)
#define LSYS_DEFAULT_MAX_BYTES (UINT64_C(4) << 30)
#define LSYS_DEFAULT_MAX_NESTING 4096u
#define LSYS_DEFAULT_MAX_EXPR_DEPTH 64u
#define LSYS_DEFAULT_MAX_PARAMS 16u
#define LSYS_HARD_MAX_PARAMS 255u
#define LSYS_DEFAULT_MAX_SOURCE (UINT64_C(1) << 20)

/* ---- module strings ------------------------------------------------------------------------ */

/* A module record of the grammar (axiom, precompiled successors): symbol, arity, parameters at
 * param in the owning array. */
typedef struct lsys_module {
    uint8_t sym;
    uint8_t nparam;
    uint16_t reserved;
    uint32_t param;
} lsys_module;

/* Structure of arrays: one byte per module for its symbol; grammars that can produce parameters
 * also keep a parameter count and the offset of the first parameter per module. A grammar
 * without parameters thus derives one byte per module, which is what makes large derivations
 * memory-bound no earlier than they must be. */
struct xyl_lstring {
    xyl_allocator alloc;
    uint8_t *sym;      /* count symbols */
    uint8_t *np;       /* parameters per module; NULL when the string holds none */
    uint32_t *poff;    /* index of each module's first parameter in params; NULL with np */
    size_t count, cap; /* modules, and the capacity of sym (and np, poff) */
    double *params;
    size_t nparams, pcap;
};

static inline uint32_t lsys_np(const xyl_lstring *s, size_t i)
{
    return s->np ? s->np[i] : 0u;
}
/* Module i's parameters; only meaningful when lsys_np(s, i) > 0. */
static inline const double *lsys_par(const xyl_lstring *s, size_t i)
{
    return s->params + s->poff[i];
}

/* Fills limits' zero fields from base, then from the built-in defaults. */
void xyl__lsys_resolve_limits(xyl_lsystem_limits *limits, const xyl_lsystem_limits *base);

/* ---- expressions --------------------------------------------------------------------------- */

typedef enum lsys_opcode {
    OP_CONST, OP_VAR, OP_NEG, OP_NOT, OP_ADD, OP_SUB, OP_MUL, OP_DIV, OP_POW,
    OP_LT, OP_LE, OP_GT, OP_GE, OP_EQ, OP_NE, OP_AND, OP_OR,
    OP_SIN, OP_COS, OP_TAN, OP_ASIN, OP_ACOS, OP_ATAN, OP_ATAN2, OP_SQRT, OP_ABS, OP_MIN, OP_MAX,
    OP_FLOOR, OP_CEIL, OP_EXP, OP_LOG, OP_RAND
} lsys_opcode;

typedef struct lsys_insn {
    uint32_t op;
    uint32_t arg;  /* OP_VAR: variable slot */
    double k;      /* OP_CONST: value */
} lsys_insn;

/* A compiled expression: code[first .. first + count) of the grammar's code array. */
typedef struct lsys_expr {
    uint32_t first, count;
    uint32_t stack;    /* stack slots it needs */
    bool constant;     /* no variables, no rand(): folded to code[first].k */
} lsys_expr;

/* ---- grammar ------------------------------------------------------------------------------- */

/* A module of a pattern (context or predecessor): symbol, arity, first variable slot. */
typedef struct lsys_pat {
    uint8_t sym;
    uint8_t nparam;
    uint16_t var;
} lsys_pat;

/* A module of a successor: symbol, arity, and its parameter expressions exprs[expr ..). */
typedef struct lsys_succ {
    uint8_t sym;
    uint8_t nparam;
    uint32_t expr;
} lsys_succ;

typedef struct lsys_prod {
    uint32_t line;
    uint8_t pred, pred_nparam;
    uint16_t pred_var;
    uint32_t left_first, left_count;   /* pats[] */
    uint32_t right_first, right_count; /* pats[], may hold '[' and ']' */
    int32_t cond;                      /* exprs[] index or -1 */
    int32_t weight;                    /* exprs[] index or -1 (deterministic) */
    uint32_t succ_first, succ_count;   /* succs[] */
    uint32_t succ_pcount;              /* parameters of the whole successor */
    uint32_t nvars;
    uint32_t group_next;               /* next member of its stochastic group, or UINT32_MAX */
    bool group_member;                 /* not the group's first production */
    bool is_constant;                  /* successor fully constant, no ctx/cond/weight/params */
    uint32_t const_first, const_count; /* precompiled successor: cmods[] */
    uint32_t const_pfirst, const_pcount; /* its parameters: cparams[] */
    int32_t const_depth_max;           /* highest bracket depth inside, relative */
    bool const_cut;                    /* the precompiled successor holds a '%' */
} lsys_prod;

struct xyl_grammar {
    xyl_allocator alloc;
    xyl_lsystem_limits limits;
    xyl_grammar_info info;
    bool has_tropism;

    lsys_module *axiom;
    size_t axiom_count;
    double *axiom_params;
    size_t axiom_nparams;

    lsys_prod *prods;
    size_t prod_count;
    lsys_pat *pats;
    size_t pat_count;
    lsys_succ *succs;
    size_t succ_count;
    lsys_expr *exprs;
    size_t expr_count;
    lsys_insn *code;
    size_t code_count;
    lsys_module *cmods;
    uint8_t *csyms;             /* cmods' symbols alone, for byte strings */
    size_t cmod_count;
    double *cparams;
    size_t cparam_count;
    uint32_t max_stack;
    uint32_t max_vars;
    bool parametric;            /* some module of the axiom or a successor has parameters */
    bool all_constant;          /* every symbol is copied or rewritten by one constant production */
    int32_t constant_prod[256]; /* that production per symbol, or -1 (copy or general) */

    /* Byte path tables (all_constant && !parametric): what symbol c becomes is
     * byte_table[byte_src[c] .. + byte_len[c]); the table is padded so 32 bytes can always be
     * read. Nesting: a copy of c goes byte_dmax[c] deeper at most and ends byte_delta[c] deeper. */
    uint8_t *byte_table;
    uint32_t byte_src[256];
    uint32_t byte_len[256];
    int32_t byte_dmax[256];
    int32_t byte_delta[256];
    uint8_t byte_cut[256];
    uint32_t byte_max_len;

    /* Productions by predecessor symbol in file order, group members excluded. */
    uint32_t sym_first[256];
    uint32_t sym_count[256];
    uint32_t *sym_prods;
    uint8_t ignore[256];        /* #ignore set, for context matching */
};

/* ---- PRNG: splitmix64, fixed across platforms ---------------------------------------------- */

typedef struct lsys_rng {
    uint64_t state;
} lsys_rng;

static inline uint64_t lsys_rng_next(lsys_rng *r)
{
    uint64_t z = (r->state += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}
/* Uniform in [0, 1) with 53 random bits. */
static inline double lsys_rng_unit(lsys_rng *r)
{
    return (double)(lsys_rng_next(r) >> 11) * (1.0 / 9007199254740992.0);
}

/* Evaluates e with variables vars and a stack of at least e->stack doubles. rng may be NULL
 * when the expression has no rand(). */
double xyl__lsys_eval(const xyl_grammar *g, const lsys_expr *e, const double *vars, double *stack,
                 lsys_rng *rng);

/* The grammar parser's state (lsys_parse.h). */
typedef struct lsys_parser lsys_parser;

#endif /* XYL_LSYS_INTERNAL_H */
