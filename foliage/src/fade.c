/* Cross-fades between two levels of detail over a band of distances, with hysteresis, as the
 * keep ranges of the screen-door dither (shaders/xyl_dither.h): docs/foliage.md,
 * "Transitions". */
#include <math.h>
#include <string.h>

#include "xyl_internal.h"
#include "xylem/xyl_foliage.h"

#define LEVELS 64.0 /* the dither's thresholds: (k + 0.5) / 64 */

static double share(const xyl_fade_desc *d, double distance)
{
    double t = (distance - d->start) / (d->end - d->start);
    return t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
}

xyl_result xyl_fade_update(const xyl_fade_desc *desc, double distance, xyl_fade_state *state,
                           xyl_fade_draws *out, xyl_diag *diag)
{
    if (!desc || !state || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "desc, state and out are required");
    if (!isfinite(desc->start) || !isfinite(desc->end) || !isfinite(desc->hysteresis) ||
        !isfinite(distance) || !isfinite(state->t))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1,
                         "a band bound, the hysteresis, the distance or the state is not finite");
    if (!(desc->start >= 0.0 && desc->start < desc->end) || desc->hysteresis < 0.0 ||
        distance < 0.0)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the band [%g, %g] must have 0 <= start < end, the hysteresis %g and "
                         "the distance %g must not be negative",
                         desc->start, desc->end, desc->hysteresis, distance);
    double lo = share(desc, distance - desc->hysteresis);
    double hi = share(desc, distance + desc->hysteresis);
    double t = state->primed ? state->t : share(desc, distance);
    t = t < lo ? lo : t > hi ? hi : t;
    /* the dither's levels (a share below half a level keeps no pixel); the last frame's level
     * stays until the share is three quarters of a level away from it, so a camera on the
     * rounding edge between two levels does not toggle between them */
    float q = (float)(nearbyint(t * LEVELS) / LEVELS);
    if (state->primed && fabs((double)state->t - t) < 0.75 / LEVELS) q = state->t;
    memset(out, 0, sizeof *out);
    out->t = q;
    out->near = q < 1.0f;
    out->far = q > 0.0f;
    if (out->near && out->far) {
        out->near_keep[0] = q, out->near_keep[1] = 1.0f;
        out->far_keep[0] = 0.0f, out->far_keep[1] = q;
    }
    state->t = q;
    state->primed = true;
    xyl__diag_ok(diag);
    return XYL_OK;
}
