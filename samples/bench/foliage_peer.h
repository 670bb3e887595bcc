/* bench_foliage's comparison with meshoptimizer: leaf-collapse LODs and meshopt_simplify /
 * meshopt_simplifySloppy on the same leaves as triangles, judged by the same image error. */
#ifndef XYL_BENCH_FOLIAGE_PEER_H
#define XYL_BENCH_FOLIAGE_PEER_H

#include <stdbool.h>
#include <stdio.h>

#include <xylem/xyl_foliage.h>

/* What the comparison of one leaf set found, for the targets block. */
typedef struct peer_summary {
    bool measured;      /* false when meshoptimizer is not built in or a call failed */
    int rows;           /* LODs compared (50 % down to 1 % of the leaves) */
    int rows_met;       /* of them, where xylem's RMSE is at most half of meshoptimizer's best */
    double worst_ratio; /* the largest and smallest xylem RMSE / best meshoptimizer RMSE */
    double best_ratio;
    int in_range;       /* rows whose LOD the pick uses 2 to 64 crown radii away */
} peer_summary;

/* Builds the leaf-collapse chain of leaves[0 .. n), picks the LODs that keep the fractions of
 * the leaves the table lists, and measures each, and meshoptimizer's two simplifiers at the same
 * triangle count, with xyl_foliage_image_error_of / _triangles at the resolution at which
 * xyl_foliage_pick uses that LOD. Prints the table; rows also go to dat when not NULL. Returns 0,
 * or 1 when a call fails. */
int bench_foliage_peer(const char *name, const xyl_leaf *leaves, size_t n, bool quick, FILE *dat,
                       peer_summary *summary);

#endif
