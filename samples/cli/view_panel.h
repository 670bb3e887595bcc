/* The tuning viewer's Dear ImGui panel (view_panel.cpp, the one C++ file of the viewer): the
 * parameters grouped as a user thinks of them, the stages' times and counts, the last error, and
 * the export buttons. It edits a view_params in place and says what changed; the C side does the
 * rest (view_tuner.c). */
#ifndef XYL_SAMPLES_VIEW_PANEL_H
#define XYL_SAMPLES_VIEW_PANEL_H

#include <stdbool.h>
#include <stdint.h>

#include "view_params.h"
#include "view_regrow.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct GLFWwindow GLFWwindow;

/* What the panel shows besides the parameters; read only. */
typedef struct view_panel_info {
    const view_tree *tree;        /* NULL before the first good tree */
    view_regrow_status status;
    uint64_t triangles, vertices; /* drawn in the last frame */
    uint32_t level_lo, level_hi;
    float error_coefficient;      /* the largest patch error coefficient of the tree: a patch at
                                     level L lies within coefficient / L^2 of its PN surface */
    double select_ms, gpu_ms;
    bool has_leaf_pick;           /* the leaves' LODs for the current camera and budget */
    bool leaves_drawn;            /* and they were drawn this frame */
    uint64_t leaves_picked;       /* leaves of those LODs */
    float leaf_error;             /* world units, the worst sector's */
    uint32_t leaf_lod_lo, leaf_lod_hi, leaf_lod_top;
    const char *leaf_note;        /* why leaves that are on are not drawn, or NULL */
    const char *renderer;
    const char *note;             /* the last export's outcome, or NULL */
    float width;                  /* the panel's width in pixels */
} view_panel_info;

typedef enum view_export_kind { VIEW_EXPORT_NONE, VIEW_EXPORT_LSYS, VIEW_EXPORT_SKEL,
                                VIEW_EXPORT_GLB, VIEW_EXPORT_PNG } view_export_kind;

typedef struct view_panel_result {
    bool regrow;                  /* a parameter that shapes the tree changed */
    view_export_kind export_kind; /* a button asked for an export to export_path */
    char export_path[512];
} view_panel_result;

/* After the window's own callbacks are set (the backend chains them). Returns false on failure. */
bool view_panel_init(GLFWwindow *window);
void view_panel_shutdown(void);
/* True when the panel uses the mouse / keyboard this frame (the window's callbacks then leave
 * the camera and the keys alone). */
bool view_panel_wants_mouse(void);
bool view_panel_wants_keyboard(void);
/* Builds the panel for this frame (p edited in place) and draws it over the bound framebuffer. */
void view_panel_frame(view_params *p, const view_panel_info *info, view_panel_result *out);

#ifdef __cplusplus
}
#endif

#endif
