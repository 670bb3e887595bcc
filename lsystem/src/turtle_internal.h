/* Turtle internals shared by turtle.c (interpretation), radii.c (radius rules) and murray.c
 * (fork angles), and exposed to tests/test_turtle.c. docs/turtle.md describes the behaviour. */
#ifndef LSYS_TURTLE_INTERNAL_H
#define LSYS_TURTLE_INTERNAL_H

#include "lsys_internal.h"

#include "skeleton_internal.h"

/* A node while the turtle grows the tree: double position, the turtle width that made it, and
 * what merge_collinear needs to know. */
typedef struct lsys_tnode {
    xyl__dvec3 pos;
    double width;      /* turtle width (diameter) when the node was made */
    size_t module;     /* module that made or last moved the node, for diagnostics */
    int32_t parent;    /* < own index, or -1 for a root */
    uint32_t children;
    bool pinned;       /* saved on the bracket stack: a branch may start here, never move it */
    bool has_leaf;
} lsys_tnode;

typedef struct lsys_tleaf {
    xyl__dvec3 pos;
    xyl__frame frame;
    double size;
    size_t module;
    int32_t node;
} lsys_tleaf;

/* xyl_turtle_desc with every default resolved and every range checked. */
typedef struct lsys_turtle_opts {
    xyl_radius_mode radius_mode;
    xyl_angle_mode angle_mode;
    double exponent;    /* n of the pipe rule */
    double tip_radius;
    double min_angle, max_angle;
    bool merge;
    uint64_t max_nodes, max_leaves;
    uint32_t max_nesting;
    xyl_allocator alloc;
    double origin[3];   /* the skeleton's origin */
} lsys_turtle_opts;

/* Applies one turtle rotation symbol (+ - & ^ \ / | $) to f by angle radians (ignored by '|'
 * and '$') and re-orthonormalises it. Returns false, leaving f alone, for any other symbol. */
bool xyl__lsys_turtle_rotate(xyl__frame *f, char symbol, double angle);

/* radius[i] for every node under o's radius rule (pipe model or grammar widths). */
void xyl__lsys_turtle_radii(const lsys_tnode *nodes, size_t count, const lsys_turtle_opts *o,
                       double *radius);

/* Murray fork angles: rotates every child subtree (nodes and the leaves hanging from them)
 * rigidly about its fork. *forks receives the number of forks, *clamped those where a child's
 * angle was clamped to [min_angle, max_angle]. Fails only with XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl__lsys_turtle_murray(lsys_tnode *nodes, size_t count, lsys_tleaf *leaves,
                              size_t leaf_count, const double *radius, const lsys_turtle_opts *o,
                              uint32_t *forks, uint32_t *clamped);

#endif /* LSYS_TURTLE_INTERNAL_H */
