#include "leaf_texture.h"

#include <math.h>

static double clamp01(double x)
{
    return x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x;
}

/* The blade's half-width at height t (0 stalk end, 1 tip), as a fraction of the image's
 * half-width: an ovate outline, widest a little below the middle, closing to a point. */
static double half_width(double t)
{
    if (t <= 0.0 || t >= 1.0) return 0.0;
    return 0.96 * pow(sin(3.14159265358979323846 * pow(t, 0.8)), 0.9);
}

void xyl_leaf_texture(uint8_t *rgba, uint32_t width, uint32_t height)
{
    for (uint32_t y = 0; y < height; ++y) {
        double t = 1.0 - ((double)y + 0.5) / height; /* row 0 is the tip */
        double w = half_width(t);
        for (uint32_t x = 0; x < width; ++x) {
            double s = (((double)x + 0.5) / width) * 2.0 - 1.0; /* -1 .. 1 across */
            /* signed distance to the outline in pixels, along the row: one pixel of edge */
            double inside = (w - fabs(s)) * 0.5 * width;
            double a = clamp01(inside + 0.5);
            /* midrib and side veins running up and out at about 45 degrees */
            double rib = clamp01(1.0 - fabs(s) * width / 3.0);
            double vein = pow(fabs(cos(3.14159265358979323846 * 9.0 * (t - 0.6 * fabs(s)))), 40.0) *
                          clamp01(1.0 - fabs(s) / (w + 1e-9));
            double light = 0.55 * rib + 0.25 * vein + 0.12 * t;
            uint8_t *p = rgba + ((size_t)y * width + x) * 4;
            p[0] = (uint8_t)lround(255.0 * clamp01(0.16 + 0.30 * light));
            p[1] = (uint8_t)lround(255.0 * clamp01(0.38 + 0.35 * light));
            p[2] = (uint8_t)lround(255.0 * clamp01(0.09 + 0.15 * light));
            p[3] = (uint8_t)lround(255.0 * a);
        }
    }
}
