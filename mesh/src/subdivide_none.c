/* Subdivision in a build without OpenSubdiv (-DXYL_WITH_OPENSUBDIV=OFF): every entry point
 * answers XYL_ERR_UNSUPPORTED and says why. */
#include <string.h>

#include "subdivide.h"

static xyl_result not_built(xyl_diag *diag)
{
    return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                     "subdivision is not built: xylem was configured with "
                     "XYL_WITH_OPENSUBDIV=OFF");
}

xyl_result xyl__subdivide(const xyl__mesh_arrays *in, xyl_subdivision scheme, bool limit,
                          const xyl_mesh_limits *limits, const xyl_allocator *alloc,
                          xyl__mesh_arrays *out, xyl_diag *diag)
{
    (void)scheme, (void)limit, (void)limits, (void)alloc;
    if (!out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out must not be NULL");
    memset(out, 0, sizeof *out);
    if (!in) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "in must not be NULL");
    return not_built(diag);
}

xyl_result xyl__subdivide_by(const xyl__mesh_arrays *in, xyl_subdivision scheme, bool limit,
                             const xyl_mesh_limits *limits, xyl__subdivide_path path,
                             const xyl_allocator *alloc, xyl__mesh_arrays *out, xyl_diag *diag)
{
    (void)path;
    return xyl__subdivide(in, scheme, limit, limits, alloc, out, diag);
}

xyl_result xyl__subdivide_creased(const xyl__mesh_arrays *in, const xyl__creases *creases,
                                  xyl_subdivision scheme, bool limit,
                                  const xyl_mesh_limits *limits, xyl__subdivide_path path,
                                  const xyl_allocator *alloc, xyl__mesh_arrays *out,
                                  xyl_diag *diag)
{
    (void)creases, (void)path;
    return xyl__subdivide(in, scheme, limit, limits, alloc, out, diag);
}

xyl_result xyl__subdivide_limit_radius_factor(uint32_t k, double *factor)
{
    if (!factor || k < 3 || k > 32) return XYL_ERR_INVALID_ARGUMENT;
    return XYL_ERR_UNSUPPORTED;
}

xyl_result xyl__subdivide_refined_radius_factor(uint32_t k, uint32_t levels, double *factor)
{
    if (!factor || k < 3 || k > 32 || levels > 6) return XYL_ERR_INVALID_ARGUMENT;
    return XYL_ERR_UNSUPPORTED;
}

xyl_result xyl__subdivide_mean_limit_radius(xyl_subdivision scheme, uint32_t k, double *mean)
{
    if (!mean || k < 3 || k > 32 ||
        (scheme != XYL_SUBDIVIDE_CATMARK && scheme != XYL_SUBDIVIDE_LOOP))
        return XYL_ERR_INVALID_ARGUMENT;
    return XYL_ERR_UNSUPPORTED;
}

xyl_result xyl_mesh_subdivide(const xyl_mesh *mesh, const xyl_subdivide_desc *desc,
                              xyl_mesh **out, xyl_diag *diag)
{
    (void)desc;
    if (!mesh || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "mesh and out must not be NULL");
    return not_built(diag);
}
