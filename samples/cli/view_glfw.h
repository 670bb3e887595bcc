/* The windowed path of the GL backend: a GLFW window with a GL 4.5 core context, drawing a stem
 * mesh through xyl_tess_gl_draw every frame with levels chosen for the current camera
 * (`xylem view`, docs/cli.md). */
#ifndef XYL_SAMPLES_VIEW_GLFW_H
#define XYL_SAMPLES_VIEW_GLFW_H

#include <stdbool.h>
#include <stdint.h>

#include <xylem/xyl_tessellate.h>

typedef struct xyl_view_request {
    const xyl_mesh *mesh;          /* refined with PN patches of `variant` */
    xyl_tess_variant variant;
    xyl_tess_path path;
    uint32_t fixed_level;          /* 0: adaptive from error_px */
    float error_px;                /* 0: the library default (0.5 px) */
    float azimuth, elevation;      /* radians, around the mesh's bounding box */
    uint32_t width, height;        /* window size in pixels */
    bool wireframe;
    uint32_t samples;              /* MSAA samples asked of the window (1: none) */
    uint32_t frames;               /* 0: until the window is closed; else close after N frames */
    const char *screenshot;        /* PNG of the last frame's window contents, or NULL */
    const float *background;       /* RGBA */
    const xyl_tess_frame *look;    /* light and colours; view_proj and variant are set here */
} xyl_view_request;

/* Runs the window. Returns 0, or an exit code (sysexits) after printing why: 69 when no window
 * or GL 4.5 core context can be had (no display), 65 / 71 for library errors, 73 when the
 * screenshot cannot be written. */
int xyl_view_run(const xyl_view_request *req);

/* The current GL context's back buffer, top row first, as PNG: 0, 71 (out of memory) or 73 (not
 * written), after printing why. */
int xyl_view_write_screenshot(const char *path, int width, int height);

#endif
