/* `xylem view` with the tuning panel: the tree regrows in a worker thread as parameters change
 * (view_regrow.h), the panel is Dear ImGui (view_panel.h), the upload and drawing stay on the
 * main thread. Built only with libimgui-dev; without it `xylem view` shows the fixed mesh
 * (view_glfw.h). docs/cli.md describes the panel and the --set names. */
#ifndef XYL_SAMPLES_VIEW_TUNER_H
#define XYL_SAMPLES_VIEW_TUNER_H

#include <stdint.h>

#include "view_params.h"

typedef struct xyl_tune_request {
    const view_params *start;    /* the tree and picture from the command line's options */
    const char *const *sets;     /* "NAME=VALUE" steps, applied in order before the first frame */
    uint32_t set_count;
    uint32_t width, height;      /* window size in pixels */
    uint32_t samples;            /* MSAA samples asked of the window (1: none) */
    uint32_t frames;             /* 0: until the window is closed; else close after N frames */
    const char *screenshot;      /* PNG of the last frame's window contents, or NULL */
} xyl_tune_request;

/* Runs the window. Returns 0; 64 for a bad --set; 65 when the last regeneration failed (the
 * panel showed why, the last good tree stayed); 69 without a window or GL 4.5 core context;
 * 71 out of memory; 73 when a screenshot or export cannot be written. */
int xyl_view_tune(const xyl_tune_request *req);

/* Checks the --set steps on a copy of start, as the window would take them (names, values, a
 * grammar file read, export types), so that a bad one is refused before any window opens:
 * 0, 64, 66 or 71 (message on stderr). */
int xyl_view_check_sets(const view_params *start, const char *const *sets, uint32_t count);

#endif
