/* Internal to tessellate/: float vector helpers that mirror GLSL's vec3 operations one for one,
 * so the CPU reference performs the shader's operations in the shader's order. Not installed. */
#ifndef XYL_TESS_INTERNAL_H
#define XYL_TESS_INTERNAL_H

#include <math.h>

#include "xylem/xyl_tessellate.h"

typedef struct tv3 {
    float x, y, z;
} tv3;

static inline tv3 tv3_make(float x, float y, float z) { tv3 r = {x, y, z}; return r; }
static inline tv3 tv3_load(const float *p) { return tv3_make(p[0], p[1], p[2]); }
static inline tv3 tv3_add(tv3 a, tv3 b) { return tv3_make(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline tv3 tv3_sub(tv3 a, tv3 b) { return tv3_make(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline tv3 tv3_mul(tv3 a, float s) { return tv3_make(a.x * s, a.y * s, a.z * s); }
static inline tv3 tv3_div(tv3 a, float s) { return tv3_make(a.x / s, a.y / s, a.z / s); }
static inline float tv3_dot(tv3 a, tv3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline float tv3_len(tv3 a) { return sqrtf(tv3_dot(a, a)); }

/* Internal view of xyl_tess_patches: what level selection needs per patch and per edge. */
typedef struct xyl__tess_bound {
    float center[3];
    float radius;
    float coef; /* error bound at level L is coef / L^2 (world units) */
} xyl__tess_bound;

typedef struct xyl__tess_patches {
    xyl_tess_patches pub; /* first: the public view is a prefix */
    xyl__tess_bound *patch_bounds;
    xyl__tess_bound *edge_bounds;
    xyl_allocator alloc;
} xyl__tess_patches;

/* Control net of a patch for a variant: quads 16 points b[i + 4j], triangles 10 points in the
 * order b300 b030 b003 b210 b120 b021 b012 b102 b201 b111. Returns the point count. */
/* The arc variant's stored axis (n[c].w) of a corner with unit normal n: the angle of axis
 * (projected into n's tangent plane) plus XYL_TESS_AXIS_BIAS; 0 when it has no direction there. */
float xyl__tess_encode_axis(const float n[3], const double axis[3]);
int xyl__tess_control_net(const xyl_tess_patch *patch, xyl_tess_variant variant, tv3 out[16]);
/* The two inner control points of edge e, in canonical order (first, second) as the edge
 * evaluation uses them, with the canonical end points. */
void xyl__tess_edge_net(const xyl_tess_patch *patch, xyl_tess_variant variant, uint32_t e,
                        tv3 out[4]);

#endif /* XYL_TESS_INTERNAL_H */
