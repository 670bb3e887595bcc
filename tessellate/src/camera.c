/* Cameras: look-at + perspective in either API's clip convention. */
#include <math.h>
#include <string.h>

#include "tess_internal.h"
#include "xyl_internal.h"

static xyl__dvec3 d3f(const float *v) { return xyl__d3(v[0], v[1], v[2]); }

static bool finite_camera(const xyl_tess_camera *c)
{
    for (int k = 0; k < 3; ++k)
        if (!isfinite(c->eye[k]) || !isfinite(c->target[k]) || !isfinite(c->up[k])) return false;
    return isfinite(c->fovy) && isfinite(c->aspect) && isfinite(c->near_plane) &&
           isfinite(c->far_plane);
}

xyl_result xyl_tess_camera_matrix(const xyl_tess_camera *camera, xyl_tess_clip clip,
                                  float view_proj[16], xyl_diag *diag)
{
    if (!camera || !view_proj)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "camera and matrix required");
    if (!finite_camera(camera))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "camera has a non-finite field");
    xyl__dvec3 eye = d3f(camera->eye), fwd = xyl__d3_sub(d3f(camera->target), eye);
    double dist = xyl__d3_len(fwd);
    bool up_zero = camera->up[0] == 0.0f && camera->up[1] == 0.0f && camera->up[2] == 0.0f;
    xyl__dvec3 up = up_zero ? xyl__d3(0, 1, 0) : d3f(camera->up);
    double fovy = camera->fovy > 0.0f ? camera->fovy : 0.8;
    double aspect = camera->aspect > 0.0f ? camera->aspect : 1.0;
    double n = camera->near_plane > 0.0f ? camera->near_plane : 1e-3 * dist;
    double f = camera->far_plane > 0.0f ? camera->far_plane : 1e3 * dist;
    if (!(dist > 0.0) || !(fovy < XYL__PI) || !(n > 0.0) || !(f > n))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "camera: eye equals target, fovy >= pi or near/far out of order");
    fwd = xyl__d3_scale(fwd, 1.0 / dist);
    xyl__dvec3 side = xyl__d3_cross(fwd, up);
    double sl = xyl__d3_len(side);
    if (!(sl > 1e-9 * xyl__d3_len(up)))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "camera: up is parallel to the view direction");
    side = xyl__d3_scale(side, 1.0 / sl);
    xyl__dvec3 u = xyl__d3_cross(side, fwd);
    /* view rows: side, u, -fwd; translation -R eye */
    double view[4][4] = {{side.x, side.y, side.z, -xyl__d3_dot(side, eye)},
                         {u.x, u.y, u.z, -xyl__d3_dot(u, eye)},
                         {-fwd.x, -fwd.y, -fwd.z, xyl__d3_dot(fwd, eye)},
                         {0, 0, 0, 1}};
    double t = 1.0 / tan(0.5 * fovy);
    double proj[4][4] = {{t / aspect, 0, 0, 0}, {0, t, 0, 0}, {0, 0, 0, 0}, {0, 0, -1, 0}};
    if (clip == XYL_TESS_CLIP_VULKAN) {
        proj[1][1] = -t; /* y down */
        proj[2][2] = f / (n - f);
        proj[2][3] = n * f / (n - f);
    } else {
        proj[2][2] = (f + n) / (n - f);
        proj[2][3] = 2.0 * f * n / (n - f);
    }
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            double acc = 0.0;
            for (int k = 0; k < 4; ++k) acc += proj[r][k] * view[k][c];
            view_proj[4 * c + r] = (float)acc;
        }
    xyl__diag_ok(diag);
    return XYL_OK;
}

void xyl_tess_camera_frame(const float lo[3], const float hi[3], float azimuth, float elevation,
                           float fovy, float aspect, xyl_tess_camera *camera)
{
    memset(camera, 0, sizeof *camera);
    double c[3], r = 0.0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)lo[k] + hi[k]);
        double h = 0.5 * ((double)hi[k] - lo[k]);
        r += h * h;
    }
    r = r > 0.0 ? sqrt(r) : 1.0;
    double fy = fovy > 0.0f ? fovy : 0.8;
    double as = aspect > 0.0f ? aspect : 1.0;
    double half = 0.5 * (as < 1.0 ? 2.0 * atan(tan(0.5 * fy) * as) : fy); /* narrower angle */
    double d = r / sin(half);
    double dir[3] = {cos(elevation) * sin(azimuth), sin(elevation), cos(elevation) * cos(azimuth)};
    for (int k = 0; k < 3; ++k) {
        camera->target[k] = (float)c[k];
        camera->eye[k] = (float)(c[k] + d * dir[k]);
    }
    camera->up[1] = 1.0f;
    camera->fovy = (float)fy;
    camera->aspect = (float)as;
    camera->near_plane = (float)(0.01 * d);
    camera->far_plane = (float)(d + 2.0 * r);
}

void xyl_tess_camera_zoom(xyl_tess_camera *camera, float factor)
{
    if (!camera || !(factor > 0.0f) || !isfinite(factor)) return;
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double e = (double)camera->eye[k] - camera->target[k];
        d2 += e * e;
        camera->eye[k] = (float)((double)camera->target[k] + factor * e);
    }
    camera->near_plane *= factor;
    camera->far_plane = (float)((double)camera->far_plane + ((double)factor - 1.0) * sqrt(d2));
}

static uint32_t unorm16(float x)
{
    if (!(x > 0.0f)) return 0; /* NaN too */
    if (x >= 1.0f) return 65535u;
    return (uint32_t)lrintf(x * 65535.0f);
}

uint32_t xyl_tess_dither(float lo, float hi)
{
    return unorm16(lo) | unorm16(hi) << 16;
}
