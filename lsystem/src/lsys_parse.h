/* Grammar parser state shared by grammar.c (lines, modules) and expr.c (expressions, numbers). */
#ifndef XYL_LSYS_PARSE_H
#define XYL_LSYS_PARSE_H

#include "lsys_internal.h"

#define LSYS_MAX_VARS 1024u       /* variable slots of one production */
#define LSYS_MAX_NUMBER_CHARS 400 /* longest numeric literal */

typedef struct lsys_name {
    const char *s;
    size_t n;
} lsys_name;

typedef struct lsys_define {
    lsys_name name;
    double value;
} lsys_define;

struct lsys_parser {
    xyl_grammar *g;
    xyl_diag *diag;
    const char *src;
    size_t len;
    size_t line_start;   /* offset of the current line's first byte */
    uint32_t line;       /* 1-based */

    lsys_define *defines;
    size_t define_count, define_cap;

    lsys_name vars[LSYS_MAX_VARS]; /* variable names of the production being parsed */
    uint32_t var_count;

    /* growable arrays of the grammar being built */
    size_t prod_cap, pat_cap, succ_cap, expr_cap, code_cap, cmod_cap, csym_cap, cparam_cap;
    size_t axiom_cap, axiom_pcap;

    lsys_name *heads; /* per production: its head text (contexts, predecessor, condition) */
    size_t head_cap;
};

/* Reports an error at byte offset at of the source (line/column from the current line). */
xyl_result xyl__lsys_error_at(lsys_parser *p, size_t at, xyl_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static inline bool lsys_is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}
static inline bool lsys_is_alpha(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}
static inline bool lsys_is_digit(char c)
{
    return c >= '0' && c <= '9';
}
static inline bool lsys_is_ident_char(char c)
{
    return lsys_is_alpha(c) || lsys_is_digit(c) || c == '_';
}
/* Module symbols: letters, digits (ABOP 1.31 uses 0 and 1) and the ABOP punctuation.
 * Parentheses, ',', ':', ';', '#', '<', '>' and whitespace are syntax. */
bool xyl__lsys_is_symbol(char c);

/* Skips spaces and tabs in [*pos, end). */
static inline void lsys_skip_space(const char *s, size_t *pos, size_t end)
{
    while (*pos < end && lsys_is_space(s[*pos])) ++*pos;
}

/* Parses a decimal literal (no sign) at *pos; locale-independent and correctly rounded. */
xyl_result xyl__lsys_parse_number(lsys_parser *p, size_t *pos, size_t end, double *out);

/* Compiles an expression from [*pos, end) into the grammar's code array, stopping at a top-level
 * ',' or ')' (or end). Variables are looked up in p->vars, then the #defines. */
xyl_result xyl__lsys_compile_expr(lsys_parser *p, size_t *pos, size_t end, lsys_expr *out);

/* Evaluates a constant expression (used for #define and header values). */
xyl_result xyl__lsys_const_expr(lsys_parser *p, size_t *pos, size_t end, double *out);

#endif
