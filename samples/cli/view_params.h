/* The tuning viewer's parameters: everything that shapes the tree or the picture, their names for
 * `xylem view --set NAME=VALUE` (docs/cli.md lists them), and the grammar text with the tuned
 * values written into it. Plain data, no GL: the regeneration worker gets a copy. */
#ifndef XYL_SAMPLES_VIEW_PARAMS_H
#define XYL_SAMPLES_VIEW_PARAMS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <xylem/xyl_lsystem.h>
#include <xylem/xyl_stems.h>
#include <xylem/xyl_tessellate.h>

#ifdef __cplusplus
extern "C" {
#endif

#define VIEW_MAX_DEFINES 64
#define VIEW_NAME_CAP 48

/* A tuned `#define NAME value`: written over the grammar's own value. */
typedef struct view_define {
    char name[VIEW_NAME_CAP];
    double value;
} view_define;

/* How the window draws the leaves (per frame, no regeneration): the LOD per sector that the pixel
 * budget allows for the camera (xyl_foliage_pick with error_px, as `render --foliage lod`), every
 * leaf, or none. The order is the --set value's: lod is the zero default. */
typedef enum view_leaf_draw { VIEW_LEAVES_LOD, VIEW_LEAVES_FULL, VIEW_LEAVES_NONE } view_leaf_draw;

typedef struct view_params {
    /* grammar */
    char *text;                  /* the grammar as typed (malloc'd, NUL-terminated) */
    char source[256];            /* preset name or file it came from, for messages */
    bool has_depth, has_seed;    /* false: the grammar's #depth / #seed */
    uint32_t depth;
    uint64_t seed;
    bool has_angle, has_step;    /* false: the grammar's #angle / #step */
    double angle_deg, step;
    bool has_tropism;            /* false: the grammar's #tropism (none by default) */
    double tropism[4];           /* x y z elasticity */
    uint32_t define_count;
    view_define defines[VIEW_MAX_DEFINES];
    /* skeleton, stems, patches */
    xyl_turtle_desc turtle;
    xyl_stems_desc stems;
    xyl_tess_variant variant;
    /* foliage (built on the CPU: counts, LODs, export; drawn per leaf_draw) */
    bool leaves;
    float leaf_aspect;           /* 0: the library's 0.5 */
    float leaf_jitter;           /* size jitter, [0, 1) */
    uint32_t leaf_sectors;       /* 0: one */
    /* per frame: no regeneration */
    xyl_tess_path path;
    uint32_t level;              /* 0: adaptive from error_px */
    float error_px;              /* > 0 */
    bool wireframe;              /* the stems' edges; leaves stay solid */
    view_leaf_draw leaf_draw;    /* --set foliage=lod|full|none */
    bool panel;                  /* the panel is shown */
    float azimuth, elevation;    /* radians */
    float zoom;                  /* 1: the tree fills the view */
    float background[4];
    float light[3];
} view_params;

/* Default picture settings; text NULL. */
void view_params_init(view_params *p);
/* Deep copy (dst's old text is freed); returns false when out of memory (dst unchanged). */
bool view_params_copy(view_params *dst, const view_params *src);
void view_params_free(view_params *p);
/* Replaces the grammar text (copied); clears the tuned #defines; false when out of memory. */
bool view_params_set_text(view_params *p, const char *text, const char *source);

/* Sets one parameter by its documented name. Returns 0, or a sysexits code with a message in
 * err: 64 for an unknown name or a bad value, 66 for an unreadable grammar file. */
int view_params_set(view_params *p, const char *name, const char *value, char *err, size_t cap);

/* A `#define NAME number` of the text. */
typedef struct view_text_define {
    char name[VIEW_NAME_CAP];
    double value;     /* the grammar's own value */
    uint32_t line;    /* 1-based */
} view_text_define;

/* The defines of the text whose value is a plain number (those a slider can tune), at most cap;
 * returns how many. */
uint32_t view_text_defines(const char *text, view_text_define *out, uint32_t cap);

/* The tuned value of a define, or NULL. */
const view_define *view_params_define(const view_params *p, const char *name);
/* Tunes a define (adds or replaces); false when the table is full. */
bool view_params_tune_define(view_params *p, const char *name, double value);

/* The grammar with every tuned value written in: #define values, #angle, #step and, when
 * with_derive, #depth and #seed (the worker passes those to the derivation instead, so a new
 * depth does not parse again). Lines that are missing are added at the top. Returns a malloc'd
 * NUL-terminated text, or NULL when out of memory. #tropism counts with #angle and #step. */
char *view_params_tuned_text(const view_params *p, bool with_derive);

/* The line `line` (1-based) of text, at most cap - 1 bytes, for showing a parse error. */
void view_text_line(const char *text, uint32_t line, char *out, size_t cap);

#ifdef __cplusplus
}
#endif

#endif
