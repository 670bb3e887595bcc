/* xyl_lsystem.h: parametric, stochastic, context-sensitive L-systems and a 3D turtle that grows
 * branch skeletons (docs/lsystem.md describes the grammar language).
 *
 * How to use
 *     xyl_diag diag = {0};
 *     xyl_grammar *g = NULL;
 *     xyl_grammar_desc gd = {0};
 *     gd.source = xyl_lsystem_preset_source("abop-1.24d");   // or your own text
 *     if (xyl_grammar_parse(&gd, &g, &diag)) { fprintf(stderr, "%u:%u: %s\n",
 *                                                diag.line, diag.column, diag.message); }
 *
 *     xyl_derive_desc dd = {0};                 // zero = the grammar's #depth and #seed
 *     xyl_lstring *s = NULL;
 *     xyl_lsystem_derive(g, &dd, &s, &diag);
 *
 *     xyl_turtle_desc td = {0};                 // zero = pipe-rule radii (n = 2), grammar angles
 *     xyl_skeleton *sk = NULL;
 *     xyl_lsystem_interpret(g, s, &td, &sk, &diag);
 *     ...
 *     xyl_skeleton_destroy(sk); xyl_lstring_destroy(s); xyl_grammar_destroy(g);
 *
 * A parsed grammar is immutable and may be shared by threads; each derivation and interpretation
 * only reads it. The same grammar text, depth and seed give bit-identical strings and skeletons.
 *
 * Copyright (c) xylem authors. MIT licence, see LICENSE.
 */
#ifndef XYL_LSYSTEM_H
#define XYL_LSYSTEM_H

#include <stdbool.h>

#include <xylem/xyl_core.h>
#include <xylem/xyl_skeleton.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct xyl_grammar xyl_grammar;
typedef struct xyl_lstring xyl_lstring;

/* Every bound is explicit; reaching one is XYL_ERR_LIMIT_EXCEEDED, never a silent cut. */
typedef struct xyl_lsystem_limits {
    uint32_t max_depth;        /* derivation steps; default (0): 64 */
    uint64_t max_modules;      /* modules in any derived string; default (0): 1 << 27 */
    uint64_t max_bytes;        /* bytes of one derived string (modules + parameters);
                                  default (0): 4 GiB */
    uint32_t max_nesting;      /* bracket depth in any string; default (0): 4096 */
    uint32_t max_expr_depth;   /* nesting of one expression; default (0): 64 */
    uint32_t max_params;       /* parameters of one module; default (0): 16, at most 255 */
    uint64_t max_source_bytes; /* grammar text; default (0): 1 MiB */
} xyl_lsystem_limits;

typedef struct xyl_grammar_desc {
    const char *source;  /* grammar text; need not be NUL-terminated when length > 0 */
    size_t length;       /* default (0): strlen(source) */
    xyl_lsystem_limits limits;
    xyl_allocator alloc;
} xyl_grammar_desc;

/* Errors: XYL_ERR_INVALID_GRAMMAR (line, column and message in diag),
 * XYL_ERR_LIMIT_EXCEEDED (source size, expression depth, parameter count),
 * XYL_ERR_NON_FINITE (a constant such as #angle that is NaN/inf), XYL_ERR_INVALID_ARGUMENT,
 * XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_grammar_parse(const xyl_grammar_desc *desc, xyl_grammar **out,
                                     xyl_diag *diag);
XYL_API void xyl_grammar_destroy(xyl_grammar *grammar);

/* The grammar's header values (defaults in docs/lsystem.md). */
typedef struct xyl_grammar_info {
    uint32_t depth;           /* #depth, default 4 */
    uint64_t seed;            /* #seed, default 1 */
    double angle;             /* #angle in RADIANS, default 25 degrees */
    double step;              /* #step, default 1 */
    double width;             /* #width (diameter), default 0.1 */
    double tropism[3];        /* #tropism vector, default 0 0 0 */
    double elasticity;        /* #tropism e, default 0 */
    size_t production_count;
} xyl_grammar_info;
XYL_API void xyl_grammar_get_info(const xyl_grammar *grammar, xyl_grammar_info *info);

typedef struct xyl_derive_desc {
    bool has_depth;     /* false: the grammar's #depth */
    uint32_t depth;
    bool has_seed;      /* false: the grammar's #seed */
    uint64_t seed;
    xyl_lsystem_limits limits; /* zero fields: the grammar's limits (its desc's, or defaults) */
    xyl_allocator alloc;
} xyl_derive_desc;

/* Rewrites the axiom depth times in parallel. Errors: XYL_ERR_LIMIT_EXCEEDED (diag.message
 * names the limit and the step), XYL_ERR_NON_FINITE (an expression produced NaN/inf; diag.line
 * is the production's line), XYL_ERR_INVALID_GRAMMAR (unbalanced ']' produced at run time, a
 * negative stochastic weight), XYL_ERR_OUT_OF_MEMORY, XYL_ERR_INVALID_ARGUMENT. */
XYL_API xyl_result xyl_lsystem_derive(const xyl_grammar *grammar, const xyl_derive_desc *desc,
                                      xyl_lstring **out, xyl_diag *diag);
XYL_API void xyl_lstring_destroy(xyl_lstring *string);

typedef struct xyl_module_view {
    char symbol;
    uint32_t param_count;
    const double *params;  /* valid until the string is destroyed */
} xyl_module_view;

XYL_API size_t xyl_lstring_count(const xyl_lstring *string);
/* Errors: XYL_ERR_INVALID_ARGUMENT when index >= count. */
XYL_API xyl_result xyl_lstring_module(const xyl_lstring *string, size_t index,
                                      xyl_module_view *out);
/* The string as text, "F(1.5)[+(25)F]": count-then-fill like xyl_skeleton_write_text.
 * Parameters are printed with %.9g, with '.' as decimal point whatever the C locale. */
XYL_API xyl_result xyl_lstring_format(const xyl_lstring *string, char *buffer, size_t capacity,
                                      size_t *needed);

typedef enum xyl_radius_mode {
    XYL_RADIUS_PIPE = 0,    /* r_parent^n = sum r_child^n from the tips down (default) */
    XYL_RADIUS_GRAMMAR = 1  /* radius = width / 2 from #width and ! in the string */
} xyl_radius_mode;

typedef enum xyl_angle_mode {
    XYL_ANGLES_GRAMMAR = 0, /* directions exactly as the turtle drew them (default) */
    XYL_ANGLES_MURRAY = 1   /* fork angles from the force balance w0 d0 = sum wi di, w = r^2 */
} xyl_angle_mode;

typedef struct xyl_turtle_desc {
    xyl_radius_mode radius_mode;
    double radius_exponent;   /* n of the pipe rule; default (0): 2 (da Vinci). Range (0.5, 8] */
    double tip_radius;        /* pipe rule: radius of every tip; default (0): #width / 2 */
    xyl_angle_mode angle_mode;
    double murray_min_angle;  /* radians; default (0): 10 degrees. A fork whose balanced angle
                                 falls below is clamped up and counted in clamped_forks */
    double murray_max_angle;  /* radians; default (0): 90 degrees, the upper clamp */
    bool merge_collinear;     /* merge successive collinear F's into one segment (default off:
                                 one node per F, the positions the grammar implies) */
    xyl_skeleton_limits limits;
    xyl_allocator alloc;
    double origin[3];         /* default (0): world position where the turtle starts; becomes
                                 the skeleton's origin, the nodes stay relative to it (so a
                                 tree planted far from (0, 0, 0) has the bits of one at it) */
} xyl_turtle_desc;

/* Interprets the string with the ABOP turtle and builds a skeleton. desc may be NULL. Where a
 * node lies so far from the start that its float position is coarser than 1/128 of its radius,
 * diag gets a warning with the figures (plant the tree with desc.origin instead of moving it).
 * Errors: XYL_ERR_NON_FINITE (a parameter or the geometry became NaN/inf, or an origin that is
 * not finite; diag.index is the module, -1 for the origin), XYL_ERR_INVALID_GRAMMAR (unbalanced brackets), XYL_ERR_LIMIT_EXCEEDED (nodes, leaves,
 * nesting), XYL_ERR_INVALID_ARGUMENT (an option out of range), XYL_ERR_OUT_OF_MEMORY. */
XYL_API xyl_result xyl_lsystem_interpret(const xyl_grammar *grammar, const xyl_lstring *string,
                                         const xyl_turtle_desc *desc, xyl_skeleton **out,
                                         xyl_diag *diag);

/* Built-in grammars. Index order is stable; names are lower-case ("abop-1.24a"). */
XYL_API size_t xyl_lsystem_preset_count(void);
XYL_API const char *xyl_lsystem_preset_name(size_t index);        /* NULL past the end */
XYL_API const char *xyl_lsystem_preset_summary(size_t index);     /* one line, NULL past end */
XYL_API const char *xyl_lsystem_preset_source(const char *name);  /* NULL if unknown */
XYL_API const char *xyl_lsystem_default_preset(void);             /* the default tree's name */

#ifdef __cplusplus
}
#endif

#endif /* XYL_LSYSTEM_H */
