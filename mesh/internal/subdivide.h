/* One uniform level of subdivision through OpenSubdiv Far (mesh/src/subdivide.cpp, one of two C++
 * files of the library). Not installed. See docs/subdivision.md. */
#ifndef XYL_SUBDIVIDE_H
#define XYL_SUBDIVIDE_H

#ifdef __cplusplus
/* The internal C headers are not C++-aware: the standard headers they use come first, outside
 * the block (C++ wrappers of them hold templates), then every declaration gets C linkage. */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
extern "C" {
#endif

#include "mesh_internal.h"

/* Refines in once with scheme into out (arrays from alloc). With limit, the refined vertices are
 * then moved to their limit positions (Far::PrimvarRefiner::Limit) and out->normals holds the
 * limit normals (the cross product of the limit tangents, oriented like the faces); without,
 * they stay control points and out->normals stays NULL, so the caller computes the normals it
 * wants. Catmark gives quads only, Loop
 * triangles only (quads (a, b, c, d) are split into (a, b, c), (a, c, d) first); faces keep the
 * input's orientation. Positions are interpolated in double (vertex rule), UVs linearly
 * (varying), face branch ids are inherited from the parent face, vertex branch ids by the rules
 * in docs/subdivision.md. XYL_SUBDIVIDE_NONE copies every array, normals included. Missing
 * uvs / branch_ids / face_branches in the input read as zeros; out's arrays are never NULL.
 * The input is validated as xyl_mesh_create validates a desc (xyl__mesh_validate: NULL arrays
 * with counts, indices out of range or repeated within a face, wrap bits beyond a face's
 * corners: XYL_ERR_INVALID_ARGUMENT; a non-finite position, normal or UV: XYL_ERR_NON_FINITE,
 * diag.index = the vertex); the refined counts
 * are checked against limits (NULL = defaults) before anything large is allocated
 * (XYL_ERR_LIMIT_EXCEEDED). Other errors: XYL_ERR_UNSUPPORTED (OpenSubdiv refuses the topology,
 * or counts beyond its int indices), XYL_ERR_OUT_OF_MEMORY. On failure *out is zeroed and
 * nothing is left allocated. No C++ exception leaves this function. */
xyl_result xyl__subdivide(const xyl__mesh_arrays *in, xyl_subdivision scheme, bool limit,
                          const xyl_mesh_limits *limits, const xyl_allocator *alloc,
                          xyl__mesh_arrays *out, xyl_diag *diag);

/* How xyl__subdivide_by refines. ANY (what xyl__subdivide does): the direct path where it
 * applies, else Far. FAR: Far's TopologyRefiner and PrimvarRefiner, for any mesh. DIRECT: the
 * one level built from the mesh's own half-edges with OpenSubdiv's Sdc masks, for a closed
 * oriented manifold whose every vertex lies in one fan of 3 to 64 faces (the stem mesher's
 * meshes); its output is bit-identical to Far's (docs/subdivision.md, "Two paths"), and on any
 * other mesh it fails with XYL_ERR_UNSUPPORTED. */
typedef enum xyl__subdivide_path {
    XYL__SUBDIVIDE_ANY = 0,
    XYL__SUBDIVIDE_FAR,
    XYL__SUBDIVIDE_DIRECT
} xyl__subdivide_path;

/* xyl__subdivide by the given path (the tests compare the two). */
xyl_result xyl__subdivide_by(const xyl__mesh_arrays *in, xyl_subdivision scheme, bool limit,
                             const xyl_mesh_limits *limits, xyl__subdivide_path path,
                             const xyl_allocator *alloc, xyl__mesh_arrays *out, xyl_diag *diag);

/* Edges that subdivision keeps infinitely sharp (OpenSubdiv's semi-sharp creases with infinite
 * sharpness): count vertex pairs, pairs[2 i] and pairs[2 i + 1], each the two ends of an edge of
 * the mesh as refined (a side of a face; for Loop also the diagonal (a, c) each quad
 * (a, b, c, d) is split along), in either order. An edge point of such an edge is its midpoint;
 * a vertex with two of them follows the crease rule (1/8, 6/8, 1/8) and the crease limit mask
 * (1/6, 4/6, 1/6) along them; one with three or more stays where it is (a corner); one with a
 * single crease (a dart) is smooth. The stem mesher creases each root ring of a closed base,
 * so the ring and the cap inside it stay in the root's plane (docs/stems.md, "The base"). */
typedef struct xyl__creases {
    const uint32_t *pairs;
    size_t count;
} xyl__creases;

/* xyl__subdivide_by with creases (NULL or count 0: none, exactly as xyl__subdivide_by). Both
 * paths take them, Far through its topology descriptor's creases, the direct one with Sdc's
 * crease, corner and dart masks in the same order of sums, so their outputs stay bit-identical.
 * Errors besides those of xyl__subdivide: XYL_ERR_INVALID_ARGUMENT for pairs NULL with a
 * count, or a pair whose ends are out of range or equal (checked for XYL_SUBDIVIDE_NONE too),
 * or that is not an edge (diag.index: the pair). */
xyl_result xyl__subdivide_creased(const xyl__mesh_arrays *in, const xyl__creases *creases,
                                  xyl_subdivision scheme, bool limit,
                                  const xyl_mesh_limits *limits, xyl__subdivide_path path,
                                  const xyl_allocator *alloc, xyl__mesh_arrays *out,
                                  xyl_diag *diag);

/* Measures, with OpenSubdiv's own limit evaluation (Far::PrimvarRefiner::Limit after one
 * Catmark level), the limit radius of a mid-section ring vertex of a long capped prism whose
 * k-gon rings have radius 1, and writes it to *factor. The cubic B-spline limit rule predicts
 * (4 + 2 cos(2π/k)) / 6 (docs/subdivision.md); the mesher inflates rings by the inverse of the
 * MEAN limit radius (xyl__subdivide_mean_limit_radius), not of this vertex factor. k in 3..32, else
 * XYL_ERR_INVALID_ARGUMENT; XYL_ERR_OUT_OF_MEMORY, XYL_ERR_UNSUPPORTED as above. */
xyl_result xyl__subdivide_limit_radius_factor(uint32_t k, double *factor);

/* The same probe's radius after `levels` (0..6) uniform Catmark levels without the limit
 * evaluation: (3 + cos(2π/k)) / 4 after one, converging to the limit factor. A check on the
 * above that does not trust PrimvarRefiner::Limit. */
xyl_result xyl__subdivide_refined_radius_factor(uint32_t k, uint32_t levels, double *factor);

/* Mean radius of the limit surface of a long prism of unit k-gon rings (k in 3..32) refined by
 * scheme (CATMARK, or LOOP on the quads split as the mesher's are), measured with OpenSubdiv's
 * limit evaluation over one band in its middle: the check on the closed form the mesher
 * inflates rings by (stems_build.c, limit_mean_radius). Errors: XYL_ERR_INVALID_ARGUMENT, XYL_ERR_OUT_OF_MEMORY,
 * XYL_ERR_UNSUPPORTED. */
xyl_result xyl__subdivide_mean_limit_radius(xyl_subdivision scheme, uint32_t k, double *mean);

#ifdef __cplusplus
}
#endif

#endif /* XYL_SUBDIVIDE_H */
