/* Radius rules: the pipe model r_parent^n = sum r_child^n from equal tips (da Vinci n = 2,
 * Murray n = 3), or the widths the grammar set with '!'. */
#include "turtle_internal.h"

/* With every tip at radius t, r^n of a node is t^n times the number of tips above it, so the
 * pipe rule needs only an exact integer count per node (held in radius[] during the pass) and
 * one pow per node: no long sums of powers that could overflow or lose small branches. */
static void count_tips(const lsys_tnode *nodes, size_t count, double *tips)
{
    for (size_t i = 0; i < count; ++i) tips[i] = 0.0;
    for (size_t i = count; i-- > 0;) {
        if (tips[i] == 0.0) tips[i] = 1.0; /* children come after their parent: a tip */
        if (nodes[i].parent >= 0) tips[nodes[i].parent] += tips[i];
    }
}

static void pipe_radii(const lsys_tnode *nodes, size_t count, double exponent, double tip,
                       double *radius)
{
    count_tips(nodes, count, radius);
    double inv = 1.0 / exponent;
    for (size_t i = 0; i < count; ++i)
        radius[i] = radius[i] == 1.0 ? tip : tip * pow(radius[i], inv);
}

void xyl__lsys_turtle_radii(const lsys_tnode *nodes, size_t count, const lsys_turtle_opts *o,
                       double *radius)
{
    if (o->radius_mode == XYL_RADIUS_PIPE) {
        pipe_radii(nodes, count, o->exponent, o->tip_radius, radius);
        return;
    }
    for (size_t i = 0; i < count; ++i) radius[i] = 0.5 * nodes[i].width;
}
