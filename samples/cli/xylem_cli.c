/* xylem: command-line front end for tools and scripts (docs/cli.md).
 *
 * Exit codes (sysexits): 0 success, 64 usage (bad option, unknown preset), 65 bad input data
 * (grammar, skeleton, non-finite numbers, a limit reached), 66 input file unreadable,
 * 71 out of memory, 73 output file not writable. Errors go to stderr as
 * "xylem: <source>:<line>:<column>: <message>". */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <xylem/xyl_foliage.h>
#include <xylem/xyl_lsystem.h>
#include <xylem/xyl_stems.h>
#include <xylem/xyl_tess_gl.h>
#ifdef XYL_HAVE_GL
#include <epoxy/gl.h>
#include <xylem/xyl_billboard_gl.h>
#include <xylem/xyl_foliage_gl.h>
#include <xylem/xyl_forest_gl.h>
#endif
#ifdef XYL_HAVE_VULKAN
#include <xylem/xyl_tess_vk.h> /* needs <vulkan/vulkan.h> */

#include "render_vk.h"
#endif
#include <xylem/xyl_tessellate.h>

#include "glb_read.h"
#include "leaf_texture.h"
#include "png_write.h"
#ifdef XYL_HAVE_GLFW
#include "view_glfw.h"
#endif
#ifdef XYL_HAVE_IMGUI
#include "view_tuner.h"
#endif

enum {
    EXIT_USAGE = 64, EXIT_DATA = 65, EXIT_NOINPUT = 66, EXIT_UNAVAILABLE = 69, EXIT_OSERR = 71,
    EXIT_CANTCREAT = 73
};

typedef enum tess_mode { TESS_INSTANCED, TESS_HARDWARE, TESS_CPU } tess_mode;
/* render --foliage: the LOD the pixel budget picks (default), the finest, none, per leaf (the
 * GPU's cut of the collapse forest), or the tree's billboard. */
typedef enum leaf_mode {
    LEAVES_LOD, LEAVES_FULL, LEAVES_NONE, LEAVES_ADAPTIVE, LEAVES_BILLBOARD
} leaf_mode;

typedef struct render_options {
    bool vulkan;
    tess_mode tess;
    xyl_tess_variant variant;
    uint32_t level;          /* 0: adaptive from error_px */
    double error_px;         /* 0: the library default (0.5 px) */
    double azimuth, elevation; /* degrees */
    double zoom;               /* render: the eye at this times the framing distance */
    bool has_camera;
    uint32_t width, height;
    bool wireframe;
    uint32_t samples;        /* MSAA samples; 0: 4 */
    uint32_t frames;         /* view: close after N frames (0: when the window closes) */
    const char *screenshot;  /* view: PNG of the last frame */
    leaf_mode leaves;        /* render --foliage full|lod|adaptive|none|billboard|impostor */
    bool impostor;           /* --foliage impostor: billboard, octahedral */
    int billboard_kind;      /* --billboard: 1 + an xyl_billboard_kind; 0: cross */
    uint32_t planes;         /* --planes: the cross's, 0: 4 */
    uint32_t grid;           /* --grid: the octahedral's views per side, 0: 8 */
    uint32_t billboard_size; /* --billboard-size: texels per baked view, 0: 512 */
    bool billboard_error;    /* --billboard-error: the 20-view image error table */
    uint64_t forest;         /* --forest N: N instances of the tree on a grid (0: one tree) */
    double fade;             /* --fade F: the forest's cross-fade band (has_fade false: 0.1) */
    bool has_fade;
} render_options;

/* The leaves of 'foliage' and 'mesh --foliage'. */
typedef struct foliage_options {
    bool enabled;             /* 'foliage', or 'mesh --foliage' */
    bool given;               /* an option below appeared (only those commands take them) */
    uint32_t sectors;         /* 0: one */
    double aspect;            /* 0: the library's 0.5 */
    const char *table;        /* --table FILE.csv */
    const char *leaf_texture; /* --leaf-texture FILE.png; NULL: the procedural leaf */
    const char *leaf_mesh;    /* --leaf-mesh FILE.obj: the leaves are its components */
    const char *leaf_template;/* --leaf-template FILE.obj: its one leaf at every attachment */
    xyl_foliage_cost cost;    /* --cost hidalgo|viewpoint */
} foliage_options;

typedef struct options {
    const char *preset;
    const char *grammar_path;
    const char *skeleton_path;
    const char *mesh_path;
    xyl_stems_desc stems;
    uint32_t lods;           /* mesh --lods N: a chain of stem LODs (0: one mesh) */
    float lod_error;         /* mesh --lod-error E0: the finest LOD's prune width */
    bool has_lod_error;
    const char *out;
    bool has_seed, has_depth, merge;
    uint64_t seed;
    uint32_t depth;
    xyl_turtle_desc turtle;
    render_options render;
    foliage_options foliage;
    const char *sets[256];   /* view --set NAME=VALUE, in order */
    uint32_t set_count;
} options;

static const char usage_text[] =
    "usage: xylem <command> [options]\n"
    "\n"
    "commands:\n"
    "  presets                      list the built-in grammars and their leaf counts\n"
    "  preset NAME                  print a built-in grammar's text\n"
    "  derive   [source] [--seed N] [--depth N]\n"
    "                               print the derived module string\n"
    "  skeleton [source] [--seed N] [--depth N] [--radius pipe|grammar]\n"
    "           [--radius-exponent X] [--tip-radius R] [--angles grammar|murray]\n"
    "           [--merge-collinear] [--origin X,Y,Z] --out FILE.skel|FILE.obj\n"
    "                               grow the branch skeleton and write it\n"
    "  mesh     [source | --skeleton FILE.skel] [skeleton options] [--sides K]\n"
    "           [--subdivide none|catmark|loop] [--normals branch|smooth]\n"
    "           [--joints checked|unchecked] [--base closed|open] [--root-flare F]\n"
    "           [--error-world E [--sides-refined]]\n"
    "           [--foliage [foliage options]] [--lods N [--lod-error E0]]\n"
    "           --out FILE.glb|FILE.obj\n"
    "                               wrap the skeleton in one closed quad mesh and write it;\n"
    "                               checked (default): laterals whose joints intersect\n"
    "                               start later or are hidden (not what grows from them);\n"
    "                               --base open: no cap at the\n"
    "                               root (one boundary loop per root, for trees sunk into\n"
    "                               terrain); --error-world E: each branch gets the\n"
    "                               fewest sides (3..K) whose radial error is at most E\n"
    "                               (skeleton units); --foliage (.glb only): the\n"
    "                               leaves of 'foliage' too, in the same file; --lods N:\n"
    "                               up to N stem LODs, twigs thinner than E0 (default 0),\n"
    "                               2 E0, 4 E0 ... pruned (one .glb with MSFT_lod, or\n"
    "                               FILE-lodI.obj each)\n"
    "  foliage  [source | --skeleton FILE.skel | --leaf-mesh FILE.obj] [--seed N] [--sectors N]\n"
    "           [--aspect A | --leaf-template FILE.obj] [--cost hidalgo|viewpoint]\n"
    "           [--leaf-texture FILE.png] [--table FILE.csv] --out FILE.glb\n"
    "                               quads for the skeleton's leaves (or the components of a\n"
    "                               leaf mesh), their leaf-collapse LODs (per sector) and a\n"
    "                               .glb of them; --table: the LOD table\n"
    "  render   [source | --skeleton FILE.skel | --mesh FILE.glb] [mesh options]\n"
    "           [--backend gl|vulkan]\n"
    "           [--tess instanced|hardware|cpu] [--variant pn|rounded|circle|arc]\n"
    "           [--level N | --error-px E] [--camera AZIMUTH,ELEVATION[,DISTANCE]]\n"
    "           [--size WxH] [--wireframe] [--samples N]\n"
    "           [--foliage full|lod|adaptive|none|billboard|impostor]\n"
    "           [--billboard spherical|cylindrical|cross|octahedral] [--planes N] [--grid N]\n"
    "           [--billboard-size N] [--billboard-error] [--forest N [--fade F]]\n"
    "           --out FILE.png\n"
    "                               refine the stem mesh (PN patches) and render it headless,\n"
    "                               with the source's leaves (GL): lod (default) the leaf LOD\n"
    "                               within the pixel budget, adaptive the coarsest leaf within\n"
    "                               it per cluster (chosen on the GPU, GL only), full all of\n"
    "                               them, none bare stems, billboard the tree as a billboard\n"
    "                               baked from it (GL and Vulkan; --billboard kind, default\n"
    "                               cross; --planes of a cross, 2..8, default 4;\n"
    "                               --billboard-size texels per baked view, default 512;\n"
    "                               --billboard-error: its image error over 20 views, GL\n"
    "                               only); impostor the octahedral\n"
    "                               billboard (--grid views per side, 2..32, default 8);\n"
    "                               --forest N: N instances of the tree on a jittered grid,\n"
    "                               each at the leaf level its distance allows (lod; with\n"
    "                               billboard or impostor, those far away; adaptive: the 16\n"
    "                               nearest with a per-leaf cut each; full: every leaf),\n"
    "                               framed as a whole or by --camera; --fade F cross-fades\n"
    "                               two levels over F times each switch distance, 0..4,\n"
    "                               default 0.1 (0: hard switches); --error-px E given\n"
    "                               with a grammar or .skel: E px also prune the twigs and\n"
    "                               choose each branch's ring sides (docs/cli.md)\n"
    "  view     [source | --skeleton FILE.skel | --mesh FILE.glb] [mesh options]\n"
    "           [--tess instanced|hardware] [--variant pn|rounded|circle|arc]\n"
    "           [--level N | --error-px E] [--camera AZIMUTH,ELEVATION] [--size WxH]\n"
    "           [--wireframe] [--samples N] [--frames N] [--screenshot FILE.png]\n"
    "           [--set NAME=VALUE ...]\n"
    "                               the same in a window (GLFW, OpenGL); levels follow the\n"
    "                               camera: drag to orbit, scroll to zoom, H hardware path,\n"
    "                               V handle rule, L fixed level, +/- budget, W wireframe;\n"
    "                               from a grammar, a panel tunes the tree and regrows it\n"
    "                               (P hides it); --set: a panel parameter, steps in order\n"
    "\n"
    "source: --preset NAME (default: the default tree) or --grammar FILE\n"
    "exit codes: 0 ok, 64 usage, 65 bad input, 66 unreadable input, 69 no usable GPU\n"
    "            backend, 71 out of memory, 73 output not writable\n";

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "xylem: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n(run 'xylem --help' for usage)\n");
    return EXIT_USAGE;
}

/* XYL_ERR_UNSUPPORTED means "this input asks for what the library does not do" (a .skel format
 * version it does not know, a subdivision this build lacks): bad input, 65. Only the GPU and
 * window paths map it to 69 (report_backend). */
static int exit_code_for(xyl_result r)
{
    switch (r) {
    case XYL_OK: return 0;
    case XYL_ERR_OUT_OF_MEMORY: return EXIT_OSERR;
    case XYL_ERR_IO: return EXIT_NOINPUT;
    case XYL_ERR_INVALID_ARGUMENT:
    case XYL_ERR_NOT_FOUND: return EXIT_USAGE;
    default: return EXIT_DATA;
    }
}

static int report(const char *source, xyl_result r, const xyl_diag *d)
{
    if (d->line)
        fprintf(stderr, "xylem: %s:%u:%u: %s: %s\n", source, d->line, d->column,
                xyl_result_string(r), d->message);
    else
        fprintf(stderr, "xylem: %s: %s: %s\n", source, xyl_result_string(r), d->message);
    return exit_code_for(r);
}

/* A failure of the GPU backend or its context: XYL_ERR_UNSUPPORTED there is a missing backend,
 * driver feature or window system. */
static int report_backend(const char *source, xyl_result r, const xyl_diag *d)
{
    int rc = report(source, r, d);
    return r == XYL_ERR_UNSUPPORTED ? EXIT_UNAVAILABLE : rc;
}

/* ---- options ------------------------------------------------------------------------------- */

static bool parse_u64(const char *s, uint64_t max, uint64_t *out)
{
    if (!s || !*s || *s == '-') return false;
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno || *end || v > max) return false;
    *out = v;
    return true;
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

static int parse_turtle_option(options *o, const char *opt, const char *val);

static bool parse_double(const char *s, double *out)
{
    if (!s || !*s) return false;
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || *end || v != v) return false;
    *out = v;
    return true;
}

/* "X,Y,Z": three finite numbers, where a grown tree is planted (the skeleton's origin). */
static bool parse_origin(const char *s, double out[3])
{
    for (int k = 0; k < 3; ++k) {
        char *end = NULL;
        errno = 0;
        double v = s && *s ? strtod(s, &end) : NAN;
        if (errno || !end || end == s || !isfinite(v) || *end != (k < 2 ? ',' : '\0'))
            return false;
        out[k] = v;
        s = end + 1;
    }
    return true;
}

static int parse_render_option(render_options *r, const char *opt, const char *val)
{
    uint64_t u;
    if (strcmp(opt, "--backend") == 0) {
        if (strcmp(val, "gl") == 0) r->vulkan = false;
        else if (strcmp(val, "vulkan") == 0) r->vulkan = true;
        else return usage_error("--backend takes gl or vulkan, not '%s'", val);
    } else if (strcmp(opt, "--tess") == 0) {
        if (strcmp(val, "instanced") == 0) r->tess = TESS_INSTANCED;
        else if (strcmp(val, "hardware") == 0) r->tess = TESS_HARDWARE;
        else if (strcmp(val, "cpu") == 0) r->tess = TESS_CPU;
        else return usage_error("--tess takes instanced, hardware or cpu, not '%s'", val);
    } else if (strcmp(opt, "--variant") == 0) {
        if (strcmp(val, "pn") == 0) r->variant = XYL_TESS_PN;
        else if (strcmp(val, "rounded") == 0) r->variant = XYL_TESS_ROUNDED;
        else if (strcmp(val, "circle") == 0) r->variant = XYL_TESS_CIRCLE;
        else if (strcmp(val, "arc") == 0) r->variant = XYL_TESS_ARC;
        else return usage_error("--variant takes pn, rounded, circle or arc, not '%s'", val);
    } else if (strcmp(opt, "--level") == 0) {
        if (!parse_u64(val, XYL_TESS_MAX_LEVEL, &u) || u < 1)
            return usage_error("--level takes a whole number from 1 to 64, not '%s'", val);
        r->level = (uint32_t)u;
    } else if (strcmp(opt, "--error-px") == 0) {
        if (!parse_double(val, &r->error_px) || !(r->error_px > 0.0) || r->error_px > 1e6)
            return usage_error("--error-px takes a positive number of pixels, not '%s'", val);
    } else if (strcmp(opt, "--camera") == 0) {
        char extra;
        r->zoom = 1.0;
        int n = sscanf(val, "%lf,%lf,%lf%c", &r->azimuth, &r->elevation, &r->zoom, &extra);
        if ((n != 2 && n != 3) || !(fabs(r->azimuth) <= 3600.0) || !(fabs(r->elevation) < 90.0) ||
            !(r->zoom > 0.0 && r->zoom <= 100.0))
            return usage_error("--camera takes AZIMUTH,ELEVATION[,DISTANCE] in degrees "
                               "(|elevation| < 90) and a distance factor in (0, 100], not '%s'",
                               val);
        r->has_camera = true;
    } else if (strcmp(opt, "--frames") == 0) {
        if (!parse_u64(val, UINT32_MAX, &u) || u < 1)
            return usage_error("--frames takes a whole number >= 1, not '%s'", val);
        r->frames = (uint32_t)u;
    } else if (strcmp(opt, "--samples") == 0) {
        if (!parse_u64(val, 16, &u) || u < 1 || (u & (u - 1)))
            return usage_error("--samples takes 1, 2, 4, 8 or 16, not '%s'", val);
        r->samples = (uint32_t)u;
    } else if (strcmp(opt, "--billboard") == 0) {
        if (strcmp(val, "spherical") == 0) r->billboard_kind = 1;
        else if (strcmp(val, "cylindrical") == 0) r->billboard_kind = 2;
        else if (strcmp(val, "cross") == 0) r->billboard_kind = 3;
        else if (strcmp(val, "octahedral") == 0) r->billboard_kind = 4;
        else return usage_error("--billboard takes spherical, cylindrical, cross or octahedral, "
                                "not '%s'", val);
    } else if (strcmp(opt, "--grid") == 0) {
        if (!parse_u64(val, 32, &u) || u < 2)
            return usage_error("--grid takes a whole number from 2 to 32, not '%s'", val);
        r->grid = (uint32_t)u;
    } else if (strcmp(opt, "--planes") == 0) {
        if (!parse_u64(val, 8, &u) || u < 2)
            return usage_error("--planes takes a whole number from 2 to 8, not '%s'", val);
        r->planes = (uint32_t)u;
    } else if (strcmp(opt, "--billboard-size") == 0) {
        if (!parse_u64(val, 4096, &u) || u < 8)
            return usage_error("--billboard-size takes a whole number from 8 to 4096, not '%s'",
                               val);
        r->billboard_size = (uint32_t)u;
    } else if (strcmp(opt, "--forest") == 0) {
        if (!parse_u64(val, XYL_FOREST_DEFAULT_MAX_INSTANCES, &u) || u < 1)
            return usage_error("--forest takes a whole number of trees from 1 to 4194304, not "
                               "'%s'", val);
        r->forest = u;
    } else if (strcmp(opt, "--fade") == 0) {
        /* 4: XYL_FOREST_MAX_FADE, whose header needs the GL backend */
        if (!parse_double(val, &r->fade) || !(r->fade >= 0.0) || r->fade > 4.0)
            return usage_error("--fade takes a share of the switch distance from 0 to 4, not "
                               "'%s'", val);
        r->has_fade = true;
    } else if (strcmp(opt, "--screenshot") == 0) {
        r->screenshot = val;
    } else if (strcmp(opt, "--size") == 0) {
        unsigned w, h;
        char extra;
        if (sscanf(val, "%ux%u%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > 8192 || h > 8192)
            return usage_error("--size takes WIDTHxHEIGHT, each 1..8192, not '%s'", val);
        r->width = w;
        r->height = h;
    } else {
        return usage_error("unknown option '%s'", opt);
    }
    return 0;
}

static int parse_mesh_option(options *o, const char *opt, const char *val)
{
    xyl_stems_desc *m = &o->stems;
    uint64_t u;
    if (strcmp(opt, "--sides") == 0) {
        if (!parse_u64(val, 32, &u) || u < 3)
            return usage_error("--sides takes a whole number from 3 to 32, not '%s'", val);
        m->sides = (uint32_t)u;
    } else if (strcmp(opt, "--subdivide") == 0) {
        if (strcmp(val, "none") == 0) m->subdivision = XYL_SUBDIVIDE_NONE;
        else if (strcmp(val, "catmark") == 0) m->subdivision = XYL_SUBDIVIDE_CATMARK;
        else if (strcmp(val, "loop") == 0) m->subdivision = XYL_SUBDIVIDE_LOOP;
        else return usage_error("--subdivide takes none, catmark or loop, not '%s'", val);
    } else if (strcmp(opt, "--normals") == 0) {
        if (strcmp(val, "branch") == 0) m->normals = XYL_NORMALS_BRANCH;
        else if (strcmp(val, "smooth") == 0) m->normals = XYL_NORMALS_SMOOTH;
        else return usage_error("--normals takes branch or smooth, not '%s'", val);
    } else if (strcmp(opt, "--joints") == 0) {
        if (strcmp(val, "checked") == 0) m->joints = XYL_JOINTS_CHECKED;
        else if (strcmp(val, "unchecked") == 0) m->joints = XYL_JOINTS_UNCHECKED;
        else return usage_error("--joints takes checked or unchecked, not '%s'", val);
    } else if (strcmp(opt, "--base") == 0) {
        if (strcmp(val, "closed") == 0) m->base = XYL_STEMS_BASE_CLOSED;
        else if (strcmp(val, "open") == 0) m->base = XYL_STEMS_BASE_OPEN;
        else return usage_error("--base takes closed or open, not '%s'", val);
    } else if (strcmp(opt, "--root-flare") == 0) {
        double f;
        if (!parse_double(val, &f) || !(f >= 0.0) || f > XYL_STEMS_MAX_ROOT_FLARE)
            return usage_error("--root-flare takes a number from 0 to 8, not '%s'", val);
        m->root_flare = (float)f;
    } else if (strcmp(opt, "--lods") == 0) {
        if (!parse_u64(val, XYL_STEMS_LOD_MAX, &u) || u < 1)
            return usage_error("--lods takes a whole number from 1 to 12, not '%s'", val);
        o->lods = (uint32_t)u;
    } else if (strcmp(opt, "--lod-error") == 0) {
        double e;
        if (!parse_double(val, &e) || !(e >= 0.0) || e > 1e30)
            return usage_error("--lod-error takes a width in world units >= 0, not '%s'", val);
        o->lod_error = (float)e;
        o->has_lod_error = true;
    } else if (strcmp(opt, "--error-world") == 0) {
        double e;
        if (!parse_double(val, &e) || !(e >= 0.0) || !(e <= FLT_MAX))
            return usage_error("--error-world takes a finite number, 0 or above, not '%s'", val);
        m->error_world = (float)e;
    } else if (strcmp(opt, "--skeleton") == 0) {
        o->skeleton_path = val;
    } else if (strcmp(opt, "--mesh") == 0) {
        o->mesh_path = val;
    } else {
        return parse_render_option(&o->render, opt, val);
    }
    return 0;
}

/* Options of 'foliage' and 'mesh --foliage'; the rest go on down the chain. */
static int parse_foliage_option(options *o, const char *opt, const char *val)
{
    foliage_options *f = &o->foliage;
    uint64_t u;
    if (strcmp(opt, "--sectors") == 0) {
        if (!parse_u64(val, 256, &u) || u < 1)
            return usage_error("--sectors takes a whole number from 1 to 256, not '%s'", val);
        f->sectors = (uint32_t)u;
    } else if (strcmp(opt, "--aspect") == 0) {
        if (!parse_double(val, &f->aspect) || !(f->aspect > 0.0) || f->aspect > 100.0)
            return usage_error("--aspect takes a width / length in (0, 100], not '%s'", val);
    } else if (strcmp(opt, "--table") == 0) {
        if (!ends_with(val, ".csv")) return usage_error("--table takes FILE.csv, not '%s'", val);
        f->table = val;
    } else if (strcmp(opt, "--leaf-texture") == 0) {
        if (!ends_with(val, ".png"))
            return usage_error("--leaf-texture takes FILE.png, not '%s'", val);
        f->leaf_texture = val;
    } else if (strcmp(opt, "--leaf-mesh") == 0 || strcmp(opt, "--leaf-template") == 0) {
        bool mesh = strcmp(opt, "--leaf-mesh") == 0;
        if (!ends_with(val, ".obj"))
            return usage_error(mesh ? "--leaf-mesh takes FILE.obj, not '%s'"
                                    : "--leaf-template takes FILE.obj, not '%s'", val);
        if (mesh) f->leaf_mesh = val;
        else f->leaf_template = val;
    } else if (strcmp(opt, "--cost") == 0) {
        if (strcmp(val, "hidalgo") == 0) f->cost = XYL_FOLIAGE_COST_HIDALGO;
        else if (strcmp(val, "viewpoint") == 0) f->cost = XYL_FOLIAGE_COST_VIEWPOINT;
        else return usage_error("--cost takes hidalgo or viewpoint, not '%s'", val);
    } else {
        return parse_turtle_option(o, opt, val);
    }
    f->given = true;
    return 0;
}

static int parse_turtle_option(options *o, const char *opt, const char *val)
{
    xyl_turtle_desc *t = &o->turtle;
    if (strcmp(opt, "--radius") == 0) {
        if (strcmp(val, "pipe") == 0) t->radius_mode = XYL_RADIUS_PIPE;
        else if (strcmp(val, "grammar") == 0) t->radius_mode = XYL_RADIUS_GRAMMAR;
        else return usage_error("--radius takes 'pipe' or 'grammar', not '%s'", val);
    } else if (strcmp(opt, "--angles") == 0) {
        if (strcmp(val, "grammar") == 0) t->angle_mode = XYL_ANGLES_GRAMMAR;
        else if (strcmp(val, "murray") == 0) t->angle_mode = XYL_ANGLES_MURRAY;
        else return usage_error("--angles takes 'grammar' or 'murray', not '%s'", val);
    } else if (strcmp(opt, "--radius-exponent") == 0) {
        if (!parse_double(val, &t->radius_exponent) || !(t->radius_exponent > 0.5) ||
            t->radius_exponent > 8.0)
            return usage_error("--radius-exponent takes a number in (0.5, 8], not '%s'", val);
    } else if (strcmp(opt, "--tip-radius") == 0) {
        if (!parse_double(val, &t->tip_radius) || !(t->tip_radius > 0.0) || t->tip_radius > 1e30)
            return usage_error("--tip-radius takes a positive number, not '%s'", val);
    } else if (strcmp(opt, "--origin") == 0) {
        if (!parse_origin(val, t->origin))
            return usage_error("--origin takes three finite numbers X,Y,Z, not '%s'", val);
    } else {
        return parse_mesh_option(o, opt, val);
    }
    return 0;
}

static int parse_options(int argc, char **argv, options *o)
{
    for (int i = 2; i < argc; ++i) {
        const char *opt = argv[i];
        if (strcmp(opt, "--merge-collinear") == 0) {
            o->turtle.merge_collinear = true;
            continue;
        }
        if (strcmp(opt, "--wireframe") == 0) {
            o->render.wireframe = true;
            continue;
        }
        if (strcmp(opt, "--sides-refined") == 0) {
            o->stems.sides_refined = true;
            continue;
        }
        if (strcmp(opt, "--foliage") == 0 && strcmp(argv[1], "render") == 0) {
            const char *val = i + 1 < argc ? argv[++i] : "";
            if (strcmp(val, "lod") == 0) o->render.leaves = LEAVES_LOD;
            else if (strcmp(val, "full") == 0) o->render.leaves = LEAVES_FULL;
            else if (strcmp(val, "none") == 0) o->render.leaves = LEAVES_NONE;
            else if (strcmp(val, "adaptive") == 0) o->render.leaves = LEAVES_ADAPTIVE;
            else if (strcmp(val, "billboard") == 0) o->render.leaves = LEAVES_BILLBOARD;
            else if (strcmp(val, "impostor") == 0)
                o->render.leaves = LEAVES_BILLBOARD, o->render.impostor = true;
            else return usage_error("render --foliage takes full, lod, adaptive, none, "
                                    "billboard or impostor, not '%s'", val);
            continue;
        }
        if (strcmp(opt, "--billboard-error") == 0) {
            o->render.billboard_error = true;
            continue;
        }
        if (strcmp(opt, "--foliage") == 0) {
            o->foliage.enabled = true;
            continue;
        }
        if (strncmp(opt, "--", 2) != 0) return usage_error("unexpected argument '%s'", opt);
        if (i + 1 >= argc) return usage_error("option '%s' needs a value", opt);
        const char *val = argv[++i];
        uint64_t u;
        if (strcmp(opt, "--preset") == 0) o->preset = val;
        else if (strcmp(opt, "--grammar") == 0) o->grammar_path = val;
        else if (strcmp(opt, "--out") == 0) o->out = val;
        else if (strcmp(opt, "--set") == 0) {
            if (o->set_count == sizeof o->sets / sizeof *o->sets)
                return usage_error("%s", "at most 256 --set options");
            o->sets[o->set_count++] = val;
        }
        else if (strcmp(opt, "--seed") == 0) {
            if (!parse_u64(val, UINT64_MAX, &o->seed))
                return usage_error("--seed takes a whole number >= 0, not '%s'", val);
            o->has_seed = true;
        } else if (strcmp(opt, "--depth") == 0) {
            if (!parse_u64(val, UINT32_MAX, &u))
                return usage_error("--depth takes a whole number >= 0, not '%s'", val);
            o->depth = (uint32_t)u;
            o->has_depth = true;
        } else {
            int rc = parse_foliage_option(o, opt, val);
            if (rc) return rc;
        }
    }
    if (o->preset && o->grammar_path) return usage_error("%s", "give --preset or --grammar, not both");
    const double *at = o->turtle.origin;
    if ((o->skeleton_path || o->mesh_path) && (at[0] != 0.0 || at[1] != 0.0 || at[2] != 0.0))
        return usage_error("%s", "--origin plants a grown tree; a .skel or .glb file holds its own "
                                 "place");
    return 0;
}

/* ---- grammar loading ----------------------------------------------------------------------- */

static char *read_all(const char *path, size_t *size, int *rc)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "xylem: %s: cannot open: %s\n", path, strerror(errno));
        *rc = EXIT_NOINPUT;
        return NULL;
    }
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    for (size_t got = 1; buf && got > 0;) {
        if (n == cap) {
            char *nb = cap < ((size_t)1 << 30) ? realloc(buf, cap *= 2) : NULL;
            if (!nb) free(buf);
            buf = nb;
            if (!buf) break;
        }
        got = fread(buf + n, 1, cap - n, f);
        n += got;
    }
    bool bad = !buf || ferror(f);
    fclose(f);
    if (bad) {
        fprintf(stderr, "xylem: %s: cannot read (or larger than 1 GiB)\n", path);
        free(buf);
        *rc = buf ? EXIT_NOINPUT : EXIT_OSERR;
        return NULL;
    }
    *size = n;
    return buf;
}

/* Parses the grammar the options name; returns 0 or an exit code. *source names it for errors. */
static int load_grammar(const options *o, xyl_grammar **g, const char **source)
{
    xyl_grammar_desc gd = {0};
    char *text = NULL;
    int rc = 0;
    if (o->grammar_path) {
        *source = o->grammar_path;
        text = read_all(o->grammar_path, &gd.length, &rc);
        if (!text) return rc;
        if (gd.length == 0) {
            free(text);
            fprintf(stderr, "xylem: %s: the file is empty\n", o->grammar_path);
            return EXIT_DATA;
        }
        gd.source = text;
    } else {
        *source = o->preset ? o->preset : xyl_lsystem_default_preset();
        gd.source = xyl_lsystem_preset_source(*source);
        if (!gd.source)
            return usage_error("unknown preset '%s' (run 'xylem presets' for the list)", *source);
    }
    xyl_diag d = {0};
    xyl_result r = xyl_grammar_parse(&gd, g, &d);
    free(text);
    return r ? report(*source, r, &d) : 0;
}

static int derive_string(const options *o, const xyl_grammar *g, const char *source,
                         xyl_lstring **s)
{
    xyl_derive_desc dd = {0};
    dd.has_depth = o->has_depth;
    dd.depth = o->depth;
    dd.has_seed = o->has_seed;
    dd.seed = o->seed;
    xyl_diag d = {0};
    xyl_result r = xyl_lsystem_derive(g, &dd, s, &d);
    return r ? report(source, r, &d) : 0;
}

/* ---- commands ------------------------------------------------------------------------------ */

static int cmd_preset(int argc, char **argv)
{
    if (argc != 3) return usage_error("%s", "'preset' takes one preset name");
    const char *src = xyl_lsystem_preset_source(argv[2]);
    if (!src) return usage_error("unknown preset '%s' (run 'xylem presets' for the list)", argv[2]);
    fputs(src, stdout);
    return 0;
}

static int cmd_derive(const options *o)
{
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    const char *source = NULL;
    int rc = load_grammar(o, &g, &source);
    if (!rc) rc = derive_string(o, g, source, &s);
    if (!rc) {
        size_t need = 0;
        xyl_lstring_format(s, NULL, 0, &need);
        char *buf = malloc(need + 1);
        if (!buf) {
            fprintf(stderr, "xylem: out of memory formatting %zu bytes\n", need);
            rc = EXIT_OSERR;
        } else {
            xyl_lstring_format(s, buf, need + 1, &need);
            fwrite(buf, 1, need, stdout);
            putchar('\n');
            free(buf);
        }
    }
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return rc;
}

/* The exit code of writing path: an output the system refuses is 73, other errors as usual. */
static int written(const char *path, xyl_result r, const xyl_diag *d)
{
    if (r == XYL_ERR_IO) {
        fprintf(stderr, "xylem: %s: %s\n", path, d->message);
        return EXIT_CANTCREAT;
    }
    return r ? report(path, r, d) : 0;
}

static int write_skeleton(const xyl_skeleton *sk, const char *path)
{
    xyl_skel_format fmt = ends_with(path, ".obj") ? XYL_SKEL_FORMAT_OBJ : XYL_SKEL_FORMAT_SKEL;
    xyl_diag d = {0};
    return written(path, xyl_skeleton_write_file(sk, path, fmt, NULL, &d), &d);
}

static int grow(const options *o, const xyl_grammar *g, const char *source, double t0)
{
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    int rc = derive_string(o, g, source, &s);
    double t1 = now_seconds();
    xyl_diag d = {0};
    if (!rc) {
        xyl_result r = xyl_lsystem_interpret(g, s, &o->turtle, &sk, &d);
        if (r) rc = report(source, r, &d);
    }
    double t2 = now_seconds();
    if (!rc) rc = write_skeleton(sk, o->out);
    if (!rc) {
        xyl_grammar_info info;
        xyl_grammar_get_info(g, &info);
        printf("%s: %zu modules, %zu nodes, %u branches (max order %u), %zu leaves, depth %u\n",
               source, xyl_lstring_count(s), sk->node_count, sk->branch_count, sk->max_order,
               sk->leaf_count, o->has_depth ? o->depth : info.depth);
        printf("time: parse+derive %.3f ms, turtle %.3f ms, write %.3f ms\n", (t1 - t0) * 1e3,
               (t2 - t1) * 1e3, (now_seconds() - t2) * 1e3);
        if (d.warning_count) printf("warning: %s\n", d.warning);
        printf("wrote %s\n", o->out);
    }
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    return rc;
}

static int cmd_skeleton(const options *o)
{
    if (!o->out) return usage_error("%s", "'skeleton' needs --out FILE.skel or FILE.obj");
    if (!ends_with(o->out, ".skel") && !ends_with(o->out, ".obj"))
        return usage_error("--out must end in .skel or .obj, not '%s'", o->out);
    double t0 = now_seconds();
    xyl_grammar *g = NULL;
    const char *source = NULL;
    int rc = load_grammar(o, &g, &source);
    if (!rc) rc = grow(o, g, source, t0);
    xyl_grammar_destroy(g);
    return rc;
}

/* The skeleton the options name: a .skel file, or grown from a grammar. */
static int load_skeleton(const options *o, xyl_skeleton **sk, const char **source)
{
    if (o->skeleton_path) {
        *source = o->skeleton_path;
        xyl_diag d = {0};
        xyl_result r = xyl_skeleton_read_file(o->skeleton_path, NULL, sk, &d);
        if (!r && d.warning_count) printf("warning: %s: %s\n", o->skeleton_path, d.warning);
        return r ? report(o->skeleton_path, r, &d) : 0;
    }
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    int rc = load_grammar(o, &g, source);
    if (!rc) rc = derive_string(o, g, *source, &s);
    if (!rc) {
        xyl_diag d = {0};
        xyl_result r = xyl_lsystem_interpret(g, s, &o->turtle, sk, &d);
        if (r) rc = report(*source, r, &d);
    }
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return rc;
}

/* Grows every preset at its #depth to count its leaves, so the list says which ones have them.
 * The name stays the first word of each line for scripts. */
static int cmd_presets(void)
{
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        options o;
        memset(&o, 0, sizeof o);
        o.preset = xyl_lsystem_preset_name(i);
        xyl_skeleton *sk = NULL;
        const char *source = NULL;
        int rc = load_skeleton(&o, &sk, &source);
        if (rc) return rc;
        bool def = strcmp(o.preset, xyl_lsystem_default_preset()) == 0;
        printf("%-22s %5zu leaves  %s%s\n", o.preset, sk->leaf_count, xyl_lsystem_preset_summary(i),
               def ? " (default)" : "");
        xyl_skeleton_destroy(sk);
    }
    return 0;
}

static int write_mesh(const xyl_mesh *m, const char *path)
{
    xyl_mesh_format fmt = ends_with(path, ".obj") ? XYL_MESH_FORMAT_OBJ : XYL_MESH_FORMAT_GLB;
    xyl_diag d = {0};
    return written(path, xyl_mesh_write_file(m, path, fmt, NULL, &d), &d);
}

/* ---- foliage ------------------------------------------------------------------------------- */

typedef struct leaf_job {
    xyl_foliage *foliage;
    unsigned char *png; /* the texture's bytes */
    size_t png_size;
    double build_ms, texture_ms;
} leaf_job;

static int leaf_texture_bytes(const options *o, leaf_job *j)
{
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    const char *path = o->foliage.leaf_texture;
    if (path) {
        int rc = 0;
        j->png = (unsigned char *)read_all(path, &j->png_size, &rc);
        if (!j->png) return rc;
        if (j->png_size < 8 || memcmp(j->png, signature, 8) != 0) {
            fprintf(stderr, "xylem: %s: not a PNG file\n", path);
            return EXIT_DATA;
        }
        return 0;
    }
    if (j->foliage->leaf_count == 0) return 0;
    uint32_t w = XYL_LEAF_TEXTURE_WIDTH, h = XYL_LEAF_TEXTURE_HEIGHT;
    uint8_t *rgba = malloc((size_t)w * h * 4);
    char msg[256] = "out of memory";
    int e = rgba ? 0 : ENOMEM;
    if (rgba) xyl_leaf_texture(rgba, w, h);
    if (!e) e = xyl_png_encode(rgba, w, h, &j->png, &j->png_size, msg, sizeof msg);
    free(rgba);
    if (e) fprintf(stderr, "xylem: the leaf texture: %s\n", msg);
    return e ? EXIT_OSERR : 0;
}

static void leaf_job_free(leaf_job *j)
{
    xyl_foliage_destroy(j->foliage);
    free(j->png);
}

/* The leaves of an OBJ leaf mesh, one per component (count, then fill); *leaves malloc'd. */
static int leaves_from_obj_file(const char *path, xyl_leaf **leaves, size_t *n)
{
    int rc = 0;
    size_t size = 0;
    char *text = read_all(path, &size, &rc);
    if (!text) return rc;
    xyl_diag d = {0};
    xyl_result r = xyl_foliage_leaves_from_obj(text, size, NULL, NULL, 0, n, &d);
    if (r == XYL_OK && !(*leaves = malloc((*n ? *n : 1) * sizeof **leaves))) {
        r = XYL_ERR_OUT_OF_MEMORY;
        snprintf(d.message, sizeof d.message, "out of memory for %zu leaves", *n);
    }
    if (r == XYL_OK) r = xyl_foliage_leaves_from_obj(text, size, NULL, *leaves, *n, n, &d);
    free(text);
    return r ? report(path, r, &d) : 0;
}

/* --leaf-template: the one leaf of the file as the shape of every attachment. */
static int template_shape(const char *path, xyl_leaf_shape *shape)
{
    xyl_leaf *t = NULL;
    size_t n = 0;
    int rc = leaves_from_obj_file(path, &t, &n);
    if (!rc && n != 1) {
        fprintf(stderr, "xylem: %s: a leaf template holds one leaf (one connected component), not "
                        "%zu\n", path, n);
        rc = EXIT_DATA;
    }
    if (!rc) {
        xyl_diag d = {0};
        xyl_result r = xyl_leaf_shape_from_template(t, NULL, shape, &d);
        if (r) rc = report(path, r, &d);
    }
    free(t);
    return rc;
}

/* The leaves (the skeleton's attachments, shaped by --aspect or --leaf-template, or the
 * components of --leaf-mesh), and their chain and LOD tables. */
static int build_foliage(const options *o, const xyl_skeleton *sk, const char *source, leaf_job *j)
{
    double t0 = now_seconds();
    xyl_foliage_leaves_desc ld = {0};
    ld.shape.aspect = (float)o->foliage.aspect;
    ld.shape.seed = o->seed;
    xyl_diag d = {0};
    size_t n = 0;
    xyl_leaf *leaves = NULL;
    xyl_result r = XYL_OK;
    if (o->foliage.leaf_mesh) {
        int rc = leaves_from_obj_file(o->foliage.leaf_mesh, &leaves, &n);
        if (rc) return rc;
        source = o->foliage.leaf_mesh;
    } else {
        if (o->foliage.leaf_template) {
            int rc = template_shape(o->foliage.leaf_template, &ld.shape);
            if (rc) return rc;
        }
        r = xyl_foliage_leaves_from_skeleton(sk, &ld, NULL, 0, &n, &d);
        if (r == XYL_OK && !(leaves = malloc((n ? n : 1) * sizeof *leaves))) {
            r = XYL_ERR_OUT_OF_MEMORY;
            snprintf(d.message, sizeof d.message, "out of memory for %zu leaves", n);
        }
        if (r == XYL_OK) r = xyl_foliage_leaves_from_skeleton(sk, &ld, leaves, n, &n, &d);
    }
    xyl_foliage_desc fd = {0};
    fd.leaves = leaves;
    fd.leaf_count = n;
    fd.sectors = o->foliage.sectors;
    fd.cost = o->foliage.cost;
    if (r == XYL_OK) r = xyl_foliage_build(&fd, &j->foliage, &d);
    free(leaves);
    j->build_ms = (now_seconds() - t0) * 1e3;
    return r ? report(source, r, &d) : 0;
}

/* The PNG to embed: --leaf-texture's file, or the procedural leaf (none without leaves: no
 * material would use it). */
static int leaf_texture_png(const options *o, leaf_job *j)
{
    double t0 = now_seconds();
    int rc = leaf_texture_bytes(o, j);
    j->texture_ms = (now_seconds() - t0) * 1e3;
    return rc;
}

/* One row per LOD per sector: sector,lod,leaves,a,b,c,error (error: the world-unit bound). */
static int write_table(const xyl_foliage *f, const char *path)
{
    char *text = NULL;
    size_t size = 0;
    FILE *m = open_memstream(&text, &size);
    if (!m) {
        fprintf(stderr, "xylem: out of memory for the LOD table\n");
        return EXIT_OSERR;
    }
    fprintf(m, "sector,lod,leaves,a,b,c,error\n");
    for (uint32_t s = 0; s < f->sector_count; ++s)
        for (uint32_t i = 0; i <= f->sectors[s].merged_count; ++i) {
            const xyl_foliage_lod *l = &f->sectors[s].lods[i];
            fprintf(m, "%u,%u,%u,%u,%u,%u,%.9g\n", s, i, l->a + l->c, l->a, l->b, l->c,
                    (double)l->error);
        }
    bool bad = fclose(m) != 0;
    char msg[512];
    int e = bad ? ENOMEM : xyl_write_file_atomic(path, text, size, msg, sizeof msg);
    free(text);
    if (e) fprintf(stderr, "xylem: %s\n", bad ? "out of memory for the LOD table" : msg);
    return e ? (bad ? EXIT_OSERR : EXIT_CANTCREAT) : 0;
}

/* Leaves, the LOD array, its tables, in a line or two. */
static void print_foliage(const xyl_foliage *f, const char *source)
{
    if (f->original_count == 0) {
        printf("%s: no leaf attachments: no leaves, an empty LOD array (the file's \"leaves\" node "
               "has no mesh)\n", source);
        return;
    }
    size_t lods = 0;
    float coarse = 0.0f;
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_sector *sec = &f->sectors[s];
        lods += sec->merged_count + 1;
        if (sec->lods[sec->merged_count].error > coarse) coarse = sec->lods[sec->merged_count].error;
    }
    printf("%s: %zu leaves -> %zu in the LOD array, %u sector%s, %zu LODs; coarsest %zu leaves, "
           "error bound %.4g world units\n", source, f->original_count, f->leaf_count,
           f->sector_count, f->sector_count == 1 ? "" : "s", lods, f->coarsest_count,
           (double)coarse);
}

/* The .glb of the leaves (and the stems, when given), then the table. Leaves from a skeleton
 * stand at its origin. */
static int write_foliage(const options *o, const leaf_job *j, const xyl_skeleton *sk,
                         const xyl_mesh *stems)
{
    xyl_foliage_glb_desc gd = {0};
    gd.stems = stems;
    if (sk) memcpy(gd.origin, sk->origin, sizeof gd.origin);
    gd.texture_png = j->png;
    gd.texture_png_size = j->png_size;
    xyl_diag d = {0};
    int rc = written(o->out, xyl_foliage_write_glb_file(j->foliage, &gd, o->out, &d), &d);
    if (!rc && o->foliage.table) rc = write_table(j->foliage, o->foliage.table);
    return rc;
}

static int cmd_foliage(const options *o)
{
    if (!o->out || !ends_with(o->out, ".glb")) return usage_error("%s", "'foliage' needs --out FILE.glb");
    if (o->skeleton_path && (o->preset || o->grammar_path))
        return usage_error("%s", "give --skeleton or a grammar source, not both");
    if (o->foliage.leaf_mesh && (o->skeleton_path || o->preset || o->grammar_path))
        return usage_error("%s", "'foliage --leaf-mesh' takes its leaves from the mesh: give no "
                                 "source or --skeleton (mesh --foliage puts them on a tree)");
    double t0 = now_seconds();
    xyl_skeleton *sk = NULL;
    const char *source = o->foliage.leaf_mesh;
    leaf_job j;
    memset(&j, 0, sizeof j);
    int rc = o->foliage.leaf_mesh ? 0 : load_skeleton(o, &sk, &source);
    double t1 = now_seconds();
    if (!rc) rc = build_foliage(o, sk, source, &j);
    double t2 = now_seconds();
    if (!rc) rc = leaf_texture_png(o, &j);
    if (!rc) rc = write_foliage(o, &j, sk, NULL);
    if (!rc) {
        print_foliage(j.foliage, source);
        printf("time: skeleton %.3f ms, leaves and LODs %.3f ms, write %.3f ms (leaf texture "
               "%.3f ms of it)\n", (t1 - t0) * 1e3, j.build_ms, (now_seconds() - t2) * 1e3,
               j.texture_ms);
        printf("wrote %s\n", o->out);
        if (o->foliage.table) printf("wrote %s\n", o->foliage.table);
    }
    leaf_job_free(&j);
    xyl_skeleton_destroy(sk);
    return rc;
}

/* What the joint check found, what it repaired and what the written mesh still has: the first
 * build's pairs are not the output's. */
static void print_joints(const xyl_stems_stats *st)
{
    if (st->joint_pairs_first == 0)
        printf("joints: found no intersecting pair at a joint (1 build)\n");
    else
        printf("joints: found %zu intersecting pairs at joints in the construction; repaired in "
               "%u builds: %u laterals start later (by %.4g at most, %.4g in all, along their "
               "own skeletons), %u hidden whole (what grows from them kept); %zu of the "
               "construction's %zu faces kept (%.1f %%)\n",
               st->joint_pairs_first, st->builds, st->laterals_started_later,
               st->lateral_shift_max, st->lateral_shift_sum, st->laterals_hidden,
               st->faces_checked, st->faces_first,
               st->faces_first ? 100.0 * (double)st->faces_checked / (double)st->faces_first
                               : 100.0);
    printf("joints: the written mesh has %zu intersecting pairs at joints%s and %zu where the "
           "skeleton overlaps itself; %u laterals lie wholly inside another branch and are not "
           "meshed\n",
           st->joint_pairs_left, st->joint_pairs_left ? " (only a root could give way)" : "",
           st->skeleton_pairs, st->laterals_inside);
}

/* FILE.obj -> FILE-lodI.obj (malloc'd). */
static char *lod_path(const char *out, uint32_t i)
{
    size_t stem = strlen(out) - 4, n = stem + 32;
    char *p = malloc(n);
    if (p) snprintf(p, n, "%.*s-lod%u.obj", (int)stem, out, i);
    return p;
}

static int write_lods(const xyl_stems_lods *c, const char *out)
{
    if (ends_with(out, ".glb")) {
        xyl_diag d = {0};
        int rc = written(out, xyl_stems_lods_write_glb_file(c, out, NULL, &d), &d);
        if (!rc) printf("wrote %s (%u LODs, MSFT_lod)\n", out, c->lod_count);
        return rc;
    }
    for (uint32_t i = 0; i < c->lod_count; ++i) {
        char *path = lod_path(out, i);
        if (!path) return report(out, XYL_ERR_OUT_OF_MEMORY, &(xyl_diag){0});
        int rc = write_mesh(c->lods[i].mesh, path);
        if (!rc) printf("wrote %s\n", path);
        free(path);
        if (rc) return rc;
    }
    return 0;
}

/* mesh --lods: the chain, what each LOD holds, and its file(s). */
static int mesh_lods(const options *o, const xyl_skeleton *sk, const char *source, double t1)
{
    xyl_stems_lod_desc ld = {0};
    ld.stems = o->stems; /* the one place the CLI's mesher options reach the chain */
    ld.max_lods = o->lods;
    ld.first_budget = o->lod_error;
    xyl_stems_lods *c = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_stems_lods_build(sk, &ld, &c, &d);
    if (r) return report(source, r, &d);
    double t2 = now_seconds();
    printf("%s: %zu nodes -> %u stem LODs%s\n", source, sk->node_count, c->lod_count,
           c->trunk_only ? " (the last is the trunk alone)" : "");
    printf("  lod  budget        error         pruned        rings         nodes    faces  "
           "subtrees cut  sides (branches)\n");
    for (uint32_t i = 0; i < c->lod_count; ++i) {
        const xyl_stems_lod *l = &c->lods[i];
        printf("  %3u  %-12.6g  %-12.6g  %-12.6g  %-12.6g  %6zu  %7zu  %12zu ", i,
               (double)l->budget, (double)xyl_stems_lod_error(l), (double)l->error,
               (double)l->ring_error, l->node_count, l->face_count, l->subtrees_removed);
        for (uint32_t k = 3; k <= 32; ++k)
            if (l->stats.branches_by_sides[k]) printf(" %u:%u", k, l->stats.branches_by_sides[k]);
        printf("\n");
    }
    printf("  sphere: centre (%g, %g, %g), radius %g (skeleton coordinates)\n",
           (double)c->center[0], (double)c->center[1], (double)c->center[2], (double)c->radius);
    if (d.warning_count) printf("warning: %s\n", d.warning);
    int rc = write_lods(c, o->out);
    if (!rc)
        printf("time: LOD chain %.3f ms, write %.3f ms\n", (t2 - t1) * 1e3,
               (now_seconds() - t2) * 1e3);
    xyl_stems_lods_destroy(c);
    return rc;
}

/* How many branch tubes got each ring sides under --error-world. */
static void print_sides(const xyl_stems_stats *st, const xyl_stems_desc *desc)
{
    printf("sides: error %g (%s):", (double)desc->error_world,
           desc->sides_refined ? "refined arcs" : "ring sagitta");
    for (uint32_t k = 3; k <= 32; ++k)
        if (st->branches_by_sides[k]) printf(" %u branches k=%u", st->branches_by_sides[k], k);
    printf("; %u laterals clamped to their parent's sides\n", st->sides_clamped);
}

static int cmd_mesh(const options *o)
{
    if (!o->out) return usage_error("%s", "'mesh' needs --out FILE.glb or FILE.obj");
    if (!ends_with(o->out, ".glb") && !ends_with(o->out, ".obj"))
        return usage_error("--out must end in .glb or .obj, not '%s'", o->out);
    if (o->foliage.enabled && !ends_with(o->out, ".glb"))
        return usage_error("--foliage writes stems and leaves to a .glb, not '%s'", o->out);
    if (o->skeleton_path && (o->preset || o->grammar_path))
        return usage_error("%s", "give --skeleton or a grammar source, not both");
    if (o->lods && o->foliage.enabled)
        return usage_error("%s", "--lods writes the stem LODs alone; drop --foliage");
    if (o->has_lod_error && !o->lods) return usage_error("%s", "--lod-error needs --lods N");
    if (o->lods) {
        xyl_skeleton *sk = NULL;
        const char *source = NULL;
        int rc = load_skeleton(o, &sk, &source);
        if (!rc) rc = mesh_lods(o, sk, source, now_seconds());
        xyl_skeleton_destroy(sk);
        return rc;
    }
    double t0 = now_seconds();
    xyl_skeleton *sk = NULL;
    xyl_mesh *m = NULL;
    leaf_job j;
    memset(&j, 0, sizeof j);
    const char *source = NULL;
    int rc = load_skeleton(o, &sk, &source);
    double t1 = now_seconds();
    xyl_diag d = {0};
    xyl_stems_stats st = {0};
    xyl_stems_desc desc = o->stems;
    if (!rc) {
        xyl_result r = xyl_stems_build(sk, &desc, &m, &st, &d);
        if (r) rc = report(source, r, &d);
    }
    if (!rc && o->foliage.enabled) rc = build_foliage(o, sk, source, &j);
    double t2 = now_seconds();
    if (!rc && o->foliage.enabled) rc = leaf_texture_png(o, &j);
    if (!rc) rc = o->foliage.enabled ? write_foliage(o, &j, sk, m) : write_mesh(m, o->out);
    if (!rc) {
        printf("%s: %zu nodes -> %zu vertices, %zu quads, %zu triangles (%zu in the triangulated "
               "view)\n",
               source, sk->node_count, m->vertex_count, m->quad_count, m->triangle_count,
               m->tri_view_count);
        if (desc.joints == XYL_JOINTS_CHECKED) print_joints(&st);
        if (desc.error_world > 0.0f) print_sides(&st, &desc);
        if (d.warning_count) printf("warning: %s\n", d.warning);
        if (o->foliage.enabled) print_foliage(j.foliage, source);
        printf("time: skeleton %.3f ms, mesh %.3f ms, write %.3f ms\n", (t1 - t0) * 1e3,
               (t2 - t1) * 1e3 - j.build_ms, (now_seconds() - t2) * 1e3);
        if (o->foliage.enabled)
            printf("time: leaves and LODs %.3f ms, leaf texture %.3f ms (in the write)\n",
                   j.build_ms, j.texture_ms);
        printf("wrote %s\n", o->out);
        if (o->foliage.table) printf("wrote %s\n", o->foliage.table);
    }
    leaf_job_free(&j);
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
    return rc;
}

/* ---- render -------------------------------------------------------------------------------- */

typedef struct render_job {
    xyl_mesh *mesh, *refined;
    xyl_tess_patterns *patterns;
    xyl_tess_patches *patches, *drawn; /* drawn: patches, or the refined mesh's for --tess cpu */
    xyl_tess_batches *batches;
    xyl_tess_camera camera;
    xyl_tess_frame frame;
    xyl_tess_image_desc image;
    uint8_t *rgba;
    double select_ms, render_ms, gpu_ms; /* gpu_ms: the API's timer query (a CPU rasterizer's
                                            misses its deferred work) */
    const char *device;
    leaf_job leaves;      /* the source's leaves (foliage NULL: none, or --foliage none) */
    bool draw_leaves;     /* leaves and a backend that draws them */
    uint32_t *lods;       /* one per sector: the LOD drawn (0s with --foliage adaptive) */
    bool adaptive;        /* --foliage adaptive: the GPU's cut for leaf_view */
    xyl_foliage_view leaf_view;
    size_t leaves_drawn;
    bool gpu_timer_all;   /* gpu_ms times stems and leaves (else the stems only) */
    bool gpu_timer_billboard; /* gpu_ms times the billboard drawn in the tree's place */
    float stem_width;     /* twice the skeleton's thickest node's radius: where a forest
                             leaves stems out */
    bool framed;          /* the camera is set (--error-px: framed on the unpruned tree) */
    float stem_px;        /* the tessellation's share of --error-px (0: all of it) */
} render_job;

static void render_job_free(render_job *j)
{
    xyl_tess_batches_destroy(j->batches);
    if (j->drawn != j->patches) xyl_tess_patches_destroy(j->drawn);
    xyl_tess_patches_destroy(j->patches);
    xyl_tess_patterns_destroy(j->patterns);
    xyl_mesh_destroy(j->refined);
    xyl_mesh_destroy(j->mesh);
    free(j->rgba);
    leaf_job_free(&j->leaves);
    free(j->lods);
}

#if defined(XYL_HAVE_GL) || defined(XYL_HAVE_VULKAN)
/* A billboard kind as the render line names it. */
static const char *billboard_name(int kind)
{
    return kind == XYL_BILLBOARD_SPHERICAL     ? "spherical (one side view, +Z)"
           : kind == XYL_BILLBOARD_CYLINDRICAL ? "cylindrical (one side view, +Z)"
           : kind == XYL_BILLBOARD_CROSS       ? "cross planes"
                                               : "octahedral (one atlas, octahedral grid)";
}
#endif

/* The box of the stems and the leaves drawn with them. */
static void tree_bounds(const render_job *j, float lo[3], float hi[3])
{
    xyl_mesh_bounds(j->mesh, lo, hi);
    if (j->draw_leaves) xyl_foliage_bounds(j->leaves.foliage, lo, hi); /* past the twigs */
}

static void frame_camera(const options *o, render_job *j)
{
    float lo[3], hi[3];
    tree_bounds(j, lo, hi);
    double deg = 3.14159265358979323846 / 180.0;
    double az = o->render.has_camera ? o->render.azimuth : 30.0;
    double el = o->render.has_camera ? o->render.elevation : 10.0;
    xyl_tess_camera_frame(lo, hi, (float)(az * deg), (float)(el * deg), 0.8f,
                          (float)j->image.width / (float)j->image.height, &j->camera);
    if (o->render.has_camera && o->render.zoom != 1.0)
        xyl_tess_camera_zoom(&j->camera, (float)o->render.zoom);
}

/* render --error-px E given: one screen budget for the whole tree (docs/cli.md). W, the world
 * size of E px at the near side of the tree's bounding sphere as the default camera frames it,
 * prunes every twig narrower than W (a removed twig shows at most E px, where no other surface
 * of the tree is drawn); the rings get the fewest sides, up to --sides or 16, within W / 2
 * (refined arcs under --variant circle or arc, else the sagitta) and the tessellation what the
 * rings leave of E px, E (1 - their largest error / W) but at least E / 2: two errors of the
 * one drawn surface that add up to at most E px. Farther points see every share smaller. */
static int budget_stems(const options *o, render_job *j, const xyl_skeleton *sk,
                        const char *source)
{
    frame_camera(o, j);
    j->framed = true;
    float lo[3], hi[3], c[3], mlo[3], mhi[3], r2 = 0.0f, size = 0.0f;
    tree_bounds(j, lo, hi);
    xyl_mesh_bounds(j->mesh, mlo, mhi);
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5f * (lo[k] + hi[k]);
        r2 += 0.25f * (hi[k] - lo[k]) * (hi[k] - lo[k]);
        size = fmaxf(size, mhi[k] - mlo[k]);
    }
    xyl_tess_view v = {0};
    memcpy(v.eye, j->camera.eye, sizeof v.eye);
    v.fovy = j->camera.fovy;
    v.viewport_height = j->image.height;
    v.error_px = (float)o->render.error_px;
    v.near_distance = fmaxf(1e-3f * size, FLT_MIN); /* the tessellation's clamp */
    float w = 0.0f;
    xyl_diag d = {0};
    xyl_skeleton *pruned = NULL;
    xyl_skeleton_prune_stats ps = {0};
    xyl_stems_stats st = {0};
    xyl_stems_desc desc = o->stems;
    xyl_mesh *m = NULL;
    xyl_result r = xyl_tess_view_world_error(&v, c, sqrtf(r2), &w, &d);
    if (r == XYL_OK) r = xyl_skeleton_prune(sk, w, NULL, &pruned, &ps, &d);
    desc.error_world = 0.5f * w;
    /* the circle and arc rules round a ring to its refined-arc error; pn and rounded leave
     * errors below the ring's sagitta (docs/tessellation.md), which then bounds them */
    desc.sides_refined = o->render.variant == XYL_TESS_CIRCLE || o->render.variant == XYL_TESS_ARC;
    if (!o->stems.sides) desc.sides = 16; /* no --sides: the budget may ask up to 16 */
    if (r == XYL_OK) r = xyl_stems_build(pruned, &desc, &m, &st, &d);
    xyl_skeleton_destroy(pruned);
    if (r != XYL_OK) return report(source, r, &d);
    xyl_mesh_destroy(j->mesh);
    j->mesh = m;
    /* the tessellation gets what the rings leave: E (1 - ring error / W), at least E / 2 */
    j->stem_px = v.error_px * fmaxf(0.5f, 1.0f - (float)(st.ring_error_max / w));
    printf("budget: %g px = %g world units at the tree's near side; pruned twigs under %g wide: "
           "%zu of %zu nodes (%zu subtrees, widest %g), %zu leaves moved; ring sides within %g, "
           "tessellation within %g px\n", (double)v.error_px, (double)w, (double)w,
           ps.nodes_removed, sk->node_count, ps.subtrees_removed, (double)ps.max_removed_width,
           ps.leaves_moved, (double)desc.error_world, (double)j->stem_px);
    print_sides(&st, &desc);
    return 0;
}

/* Levels for the view (or the fixed level), timed: the per-frame CPU cost of the technique. */
static xyl_result select_levels(const options *o, render_job *j, const xyl_tess_patches *p,
                                uint32_t fixed, xyl_diag *d)
{
    xyl_tess_view view = {0};
    memcpy(view.eye, j->camera.eye, sizeof view.eye);
    view.fovy = j->camera.fovy;
    view.viewport_height = j->image.height;
    view.error_px = j->stem_px > 0.0f ? j->stem_px : (float)o->render.error_px;
    view.fixed_level = fixed;
    double t0 = now_seconds();
    xyl_result r = xyl_tess_select(p, j->patterns, &view, j->batches, d);
    j->select_ms = (now_seconds() - t0) * 1e3;
    return r;
}

/* --tess cpu: the reference evaluator refines on the CPU; the refined triangles are drawn at
 * level 1, where a patch shows exactly its three corners (a plain triangle). */
static xyl_result refine_on_cpu(render_job *j, xyl_diag *d)
{
    xyl_result r = xyl_tess_refine(j->patches, j->patterns, j->batches, NULL, NULL,
                                   &j->refined, d);
    if (r == XYL_OK) r = xyl_tess_patches_create(j->refined, NULL, &j->drawn, d);
    return r;
}

/* --foliage full: LOD 0 of every sector; lod: the coarsest within the pixel budget the stems'
 * levels use, from the same eye. */
static xyl_result pick_leaves(const options *o, render_job *j, xyl_diag *d)
{
    const xyl_foliage *f = j->leaves.foliage;
    j->lods = calloc(f->sector_count, sizeof *j->lods);
    if (!j->lods) return XYL_ERR_OUT_OF_MEMORY;
    xyl_result r = XYL_OK;
    xyl_foliage_view *v = &j->leaf_view;
    memcpy(v->eye, j->camera.eye, sizeof v->eye);
    v->fovy = j->camera.fovy;
    v->viewport_height = j->image.height;
    v->error_px = (float)o->render.error_px;
    j->adaptive = o->render.leaves == LEAVES_ADAPTIVE;
    if (o->render.leaves == LEAVES_LOD) r = xyl_foliage_pick(f, v, j->lods, f->sector_count, d);
    /* adaptive: the CPU's cut here; the GPU's count replaces it after the draw */
    if (r == XYL_OK && j->adaptive) r = xyl_foliage_cut(f, v, NULL, 0, &j->leaves_drawn, d);
    else if (r == XYL_OK)
        r = xyl_foliage_gather(f, j->lods, f->sector_count, NULL, 0, &j->leaves_drawn, d);
    return r;
}

static xyl_result prepare_render(const options *o, render_job *j, xyl_diag *d)
{
    const render_options *ro = &o->render;
    xyl_tess_patches_desc pd = {0};
    pd.variant = ro->variant;
    xyl_result r = xyl_tess_patterns_create(0, NULL, &j->patterns, d);
    if (r == XYL_OK) r = xyl_tess_patches_create(j->mesh, &pd, &j->patches, d);
    if (r == XYL_OK) r = xyl_tess_batches_create(NULL, &j->batches, d);
    if (r != XYL_OK) return r;
    j->drawn = j->patches;
    if (!j->framed) frame_camera(o, j);
    if (j->draw_leaves) r = pick_leaves(o, j, d);
    if (r == XYL_OK) r = select_levels(o, j, j->patches, ro->level, d);
    if (r == XYL_OK && ro->tess == TESS_CPU) {
        r = refine_on_cpu(j, d);
        if (r == XYL_OK) r = select_levels(o, j, j->drawn, 1, d);
    }
    return r;
}

static const float render_background[4] = {0.86f, 0.90f, 0.95f, 1.0f};

/* Light and colours shared by render and view. */
static void fill_look(xyl_tess_frame *f)
{
    memset(f, 0, sizeof *f);
    const float light[3] = {0.42f, 0.78f, 0.46f};
    memcpy(f->light_dir, light, sizeof light);
    const float bark[4] = {0.47f, 0.35f, 0.24f, 1.0f}, line[4] = {0.08f, 0.08f, 0.08f, 1.0f};
    memcpy(f->color, bark, sizeof bark);
    memcpy(f->line_color, line, sizeof line);
}

static void fill_frame(const render_job *j, xyl_tess_variant variant, xyl_tess_frame *f)
{
    fill_look(f);
    f->variant = j->drawn == j->patches ? (uint32_t)variant : (uint32_t)XYL_TESS_PN;
}

#ifdef XYL_HAVE_GL
/* Stems and leaves in one framebuffer of the CLI's own (multisampled, then resolved): the
 * renderers draw into whatever is bound, as into an engine's. */
typedef struct own_target {
    GLuint fbo, rb[2], resolve_fbo, resolve_rb;
} own_target;

static void own_target_free(own_target *t)
{
    glDeleteFramebuffers(1, &t->fbo);
    glDeleteFramebuffers(1, &t->resolve_fbo);
    glDeleteRenderbuffers(2, t->rb);
    glDeleteRenderbuffers(1, &t->resolve_rb);
}

static xyl_result own_target_make(own_target *t, uint32_t w, uint32_t h, uint32_t samples,
                                  xyl_diag *d)
{
    GLint max_samples = 1;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    if (samples > (uint32_t)max_samples) {
        snprintf(d->message, sizeof d->message, "%u samples asked, the driver has %d", samples,
                 max_samples);
        return XYL_ERR_UNSUPPORTED;
    }
    GLsizei n = samples > 1 ? (GLsizei)samples : 0;
    glCreateRenderbuffers(2, t->rb);
    glNamedRenderbufferStorageMultisample(t->rb[0], n, GL_RGBA8, (GLsizei)w, (GLsizei)h);
    glNamedRenderbufferStorageMultisample(t->rb[1], n, GL_DEPTH_COMPONENT24, (GLsizei)w, (GLsizei)h);
    glCreateFramebuffers(1, &t->fbo);
    glNamedFramebufferRenderbuffer(t->fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t->rb[0]);
    glNamedFramebufferRenderbuffer(t->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->rb[1]);
    glCreateRenderbuffers(1, &t->resolve_rb);
    glNamedRenderbufferStorage(t->resolve_rb, GL_RGBA8, (GLsizei)w, (GLsizei)h);
    glCreateFramebuffers(1, &t->resolve_fbo);
    glNamedFramebufferRenderbuffer(t->resolve_fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                   t->resolve_rb);
    if (glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE ||
        glCheckNamedFramebufferStatus(t->resolve_fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE ||
        glGetError() != GL_NO_ERROR) {
        snprintf(d->message, sizeof d->message, "a %ux%u framebuffer with %u samples is incomplete",
                 w, h, samples);
        return XYL_ERR_UNSUPPORTED;
    }
    return XYL_OK;
}

/* The resolved image, top row first, into j->rgba. */
static void read_image(const own_target *t, render_job *j)
{
    GLint w = (GLint)j->image.width, h = (GLint)j->image.height;
    glBlitNamedFramebuffer(t->fbo, t->resolve_fbo, 0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT,
                           GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t->resolve_fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, j->rgba);
    size_t row = 4u * (size_t)w;
    for (GLint y = 0; y < h / 2; ++y) {
        uint8_t *a = j->rgba + (size_t)y * row, *b = j->rgba + (size_t)(h - 1 - y) * row;
        for (size_t i = 0; i < row; ++i) {
            uint8_t c = a[i];
            a[i] = b[i];
            b[i] = c;
        }
    }
}

static xyl_result leaf_renderer(const render_job *j, xyl_foliage_gl **out, xyl_diag *d)
{
    uint32_t w = XYL_LEAF_TEXTURE_WIDTH, h = XYL_LEAF_TEXTURE_HEIGHT;
    uint8_t *tex = malloc((size_t)w * h * 4);
    if (!tex) return XYL_ERR_OUT_OF_MEMORY;
    xyl_leaf_texture(tex, w, h);
    xyl_result r = xyl_foliage_gl_create(NULL, out, d);
    if (r == XYL_OK) r = xyl_foliage_gl_set_foliage(*out, j->leaves.foliage, d);
    if (r == XYL_OK) r = xyl_foliage_gl_set_texture(*out, tex, w, h, d);
    free(tex);
    return r;
}

/* What draws the whole tree into the bound framebuffer: the stems, then the leaves. */
typedef struct tree_gl {
    render_job *j;
    xyl_tess_gl *gl;
    xyl_foliage_gl *leaves;
    xyl_tess_path path;
    bool wireframe;
} tree_gl;

static xyl_result draw_stems_leaves(const tree_gl *t, const float view_proj[16],
                                    const float light[3], xyl_diag *d)
{
    xyl_tess_frame stems = t->j->frame;
    memcpy(stems.view_proj, view_proj, sizeof stems.view_proj);
    memcpy(stems.light_dir, light, 3 * sizeof *light);
    if (t->wireframe) stems.flags |= XYL_TESS_FLAG_WIREFRAME;
    xyl_result r = xyl_tess_gl_draw(t->gl, t->j->batches, &stems, t->path, d);
    if (r == XYL_OK && t->leaves) {
        xyl_foliage_gl_frame lf = {0};
        memcpy(lf.view_proj, view_proj, sizeof lf.view_proj);
        memcpy(lf.light_dir, light, sizeof lf.light_dir);
        lf.color[0] = lf.color[1] = lf.color[2] = lf.color[3] = 1.0f; /* the texture's own */
        render_job *j = t->j;
        if (j->adaptive) {
            r = xyl_foliage_gl_draw_adaptive(t->leaves, &lf, &j->leaf_view, d);
            if (r == XYL_OK) r = xyl_foliage_gl_last_cut(t->leaves, NULL, 0, &j->leaves_drawn, d);
        } else {
            r = xyl_foliage_gl_draw(t->leaves, &lf, j->lods, j->leaves.foliage->sector_count, d);
        }
    }
    return r;
}

/* The billboard's bake callback: the tree without wireframe, as a caller's engine draws it. */
static xyl_result bake_tree(void *user, const float view_proj[16], const float light[3],
                            xyl_diag *d)
{
    tree_gl t = *(const tree_gl *)user;
    t.wireframe = false;
    return draw_stems_leaves(&t, view_proj, light, d);
}

/* One picture into rgba with the job's current frame: the tree, or (bb) its billboard. */
static xyl_result draw_picture(const tree_gl *t, xyl_billboard_gl *bb, uint8_t *rgba,
                               xyl_diag *d)
{
    render_job *j = t->j;
    own_target tg;
    memset(&tg, 0, sizeof tg);
    xyl_result r = own_target_make(&tg, j->image.width, j->image.height, j->image.samples, d);
    if (r == XYL_OK) {
        glBindFramebuffer(GL_FRAMEBUFFER, tg.fbo);
        glViewport(0, 0, (GLsizei)j->image.width, (GLsizei)j->image.height);
        const float *bg = j->image.background;
        glClearColor(bg[0], bg[1], bg[2], bg[3]);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        if (bb) {
            xyl_billboard_gl_frame bf = {0};
            memcpy(bf.view_proj, j->frame.view_proj, sizeof bf.view_proj);
            memcpy(bf.eye, j->camera.eye, sizeof bf.eye);
            memcpy(bf.light_dir, j->frame.light_dir, sizeof bf.light_dir);
            r = xyl_billboard_gl_draw(bb, &bf, d);
        } else {
            r = draw_stems_leaves(t, j->frame.view_proj, j->frame.light_dir, d);
        }
    }
    if (r == XYL_OK) {
        uint8_t *keep = j->rgba;
        j->rgba = rgba;
        read_image(&tg, j);
        j->rgba = keep;
        j->gpu_ms = xyl_tess_gl_last_gpu_ms(t->gl); /* the stems' share */
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    own_target_free(&tg);
    return r;
}

static xyl_result bake_billboard(const options *o, tree_gl *t, xyl_billboard_gl **bb,
                                 xyl_diag *d)
{
    const render_options *ro = &o->render;
    xyl_billboard_gl_desc bd = {0};
    bd.kind = ro->impostor         ? XYL_BILLBOARD_OCTAHEDRAL
              : ro->billboard_kind ? (xyl_billboard_kind)(ro->billboard_kind - 1)
                                   : XYL_BILLBOARD_CROSS;
    bd.planes = bd.kind == XYL_BILLBOARD_CROSS ? (ro->planes ? ro->planes : 4) : 0;
    bd.grid = bd.kind == XYL_BILLBOARD_OCTAHEDRAL ? ro->grid : 0;
    bd.resolution = ro->billboard_size ? ro->billboard_size : 512;
    tree_bounds(t->j, bd.lo, bd.hi);
    memcpy(bd.light_dir, t->j->frame.light_dir, sizeof bd.light_dir); /* the scene's light */
    double t0 = now_seconds();
    xyl_result r = xyl_billboard_gl_bake(&bd, bake_tree, t, bb, d);
    if (r == XYL_OK)
        printf("billboard: %s, %u views of %u x %u texels, baked in %.1f ms\n",
               billboard_name((int)bd.kind),
               xyl_billboard_gl_view_count(*bb), bd.resolution, bd.resolution,
               (now_seconds() - t0) * 1e3);
    return r;
}

/* RMSE of colour (RGB in [0, 1], over every pixel) and of coverage (a pixel covered when it
 * differs from the background by more than 2/255 in a channel) between two pictures. */
static void image_rmse(const uint8_t *a, const uint8_t *b, size_t pixels, const float bg[4],
                       double *colour, double *coverage)
{
    double sc = 0.0, sv = 0.0;
    for (size_t i = 0; i < pixels; ++i) {
        int ca = 0, cb = 0;
        for (int k = 0; k < 3; ++k) {
            double e = (a[4 * i + k] - b[4 * i + k]) / 255.0;
            sc += e * e;
            int g = (int)lrintf(bg[k] * 255.0f);
            ca |= abs(a[4 * i + k] - g) > 2;
            cb |= abs(b[4 * i + k] - g) > 2;
        }
        sv += ca != cb;
    }
    *colour = sqrt(sc / (3.0 * (double)pixels));
    *coverage = sqrt(sv / (double)pixels);
}

/* --billboard-error: the tree and its billboard from the 20 vertices of a dodecahedron around
 * the tree's box (framed as render frames it), one row each and the mean. */
static xyl_result billboard_error(const options *o, tree_gl *t, xyl_billboard_gl *bb,
                                  xyl_diag *d)
{
    render_job *j = t->j;
    const double phi = 1.6180339887498949, ip = 1.0 / phi;
    double dirs[20][3];
    int n = 0;
    for (int i = 0; i < 8; ++i)
        dirs[n][0] = i & 1 ? -1 : 1, dirs[n][1] = i & 2 ? -1 : 1, dirs[n][2] = i & 4 ? -1 : 1, ++n;
    for (int i = 0; i < 4; ++i) {
        double s1 = i & 1 ? -1 : 1, s2 = i & 2 ? -1 : 1;
        dirs[n][0] = 0, dirs[n][1] = s1 * ip, dirs[n][2] = s2 * phi, ++n;
        dirs[n][0] = s1 * ip, dirs[n][1] = s2 * phi, dirs[n][2] = 0, ++n;
        dirs[n][0] = s1 * phi, dirs[n][1] = 0, dirs[n][2] = s2 * ip, ++n;
    }
    size_t pixels = (size_t)j->image.width * j->image.height;
    uint8_t *tree = malloc(pixels * 4), *board = malloc(pixels * 4);
    xyl_result r = tree && board ? XYL_OK : XYL_ERR_OUT_OF_MEMORY;
    float lo[3], hi[3];
    tree_bounds(j, lo, hi);
    xyl_tess_camera keep = j->camera;
    double sum_c = 0.0, sum_v = 0.0, max_c = 0.0, max_v = 0.0;
    printf("billboard image error, %u x %u, 20 dodecahedron views:\n"
           "view  azimuth elevation  colour RMSE  coverage RMSE\n", j->image.width,
           j->image.height);
    for (int v = 0; r == XYL_OK && v < 20; ++v) {
        double *p = dirs[v], len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        double el = asin(p[1] / len), az = atan2(p[0], p[2]);
        xyl_tess_camera_frame(lo, hi, (float)az, (float)el, 0.8f,
                              (float)j->image.width / (float)j->image.height, &j->camera);
        r = xyl_tess_camera_matrix(&j->camera, XYL_TESS_CLIP_GL, j->frame.view_proj, d);
        if (r == XYL_OK)
            r = select_levels(o, j, j->drawn, j->drawn == j->patches ? o->render.level : 1, d);
        if (r == XYL_OK) r = draw_picture(t, NULL, tree, d);
        if (r == XYL_OK) r = draw_picture(t, bb, board, d);
        if (r != XYL_OK) break;
        double c, cov;
        image_rmse(tree, board, pixels, j->image.background, &c, &cov);
        printf("%4d  %7.1f %9.1f  %11.4f  %13.4f\n", v, az * 180.0 / 3.14159265358979323846,
               el * 180.0 / 3.14159265358979323846, c, cov);
        sum_c += c, sum_v += cov;
        max_c = fmax(max_c, c), max_v = fmax(max_v, cov);
    }
    if (r == XYL_OK)
        printf("mean              %11.4f  %13.4f\nmax               %11.4f  %13.4f\n",
               sum_c / 20.0, sum_v / 20.0, max_c, max_v);
    free(tree);
    free(board);
    j->camera = keep;
    if (r == XYL_OK) r = xyl_tess_camera_matrix(&j->camera, XYL_TESS_CLIP_GL, j->frame.view_proj, d);
    if (r == XYL_OK)
        r = select_levels(o, j, j->drawn, j->drawn == j->patches ? o->render.level : 1, d);
    return r;
}

#define FOREST_PER_LEAF 16 /* --forest with --foliage adaptive: the trees with a cut of their own */

/* --forest N: the tree as a species of xyl_forest_gl, N instances on a jittered grid
 * (spacing 1.1 times the tree's width, scales 0.8 to 1.2, seed 1), the camera framing the
 * whole grid (or --camera); one frame to warm up, the second timed to glFinish. */
static xyl_result forest_frame(const options *o, render_job *j, xyl_forest_gl *forest,
                               xyl_forest_gl_stats *st, double *ms, xyl_diag *d)
{
    xyl_forest_gl_frame fr = {0};
    memcpy(fr.view_proj, j->frame.view_proj, sizeof fr.view_proj);
    memcpy(fr.eye, j->camera.eye, sizeof fr.eye);
    fr.fovy = j->camera.fovy;
    fr.viewport_height = j->image.height;
    fr.error_px = o->render.error_px > 0.0 ? (float)o->render.error_px : 0.5f;
    fr.mode = o->render.leaves == LEAVES_FULL ? XYL_FOREST_FULL :
              o->render.leaves == LEAVES_BILLBOARD ? XYL_FOREST_LOD : XYL_FOREST_LEAF_LEVELS;
    fr.fade = o->render.has_fade ? (float)o->render.fade : 0.1f;
    fr.per_leaf = o->render.leaves == LEAVES_ADAPTIVE ? FOREST_PER_LEAF : 0;
    memcpy(fr.light_dir, j->frame.light_dir, sizeof fr.light_dir);
    fr.leaf_color[0] = fr.leaf_color[1] = fr.leaf_color[2] = fr.leaf_color[3] = 1.0f;
    memcpy(fr.stem_color, j->frame.color, sizeof fr.stem_color);
    own_target tg;
    memset(&tg, 0, sizeof tg);
    xyl_result r = own_target_make(&tg, j->image.width, j->image.height, j->image.samples, d);
    for (int pass = 0; r == XYL_OK && pass < 2; ++pass) {
        glBindFramebuffer(GL_FRAMEBUFFER, tg.fbo);
        glViewport(0, 0, (GLsizei)j->image.width, (GLsizei)j->image.height);
        const float *bg = j->image.background;
        glClearColor(bg[0], bg[1], bg[2], bg[3]);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glFinish();
        double t0 = now_seconds();
        r = xyl_forest_gl_draw(forest, &fr, st, d);
        glFinish();
        *ms = (now_seconds() - t0) * 1e3;
    }
    if (r == XYL_OK) read_image(&tg, j);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    own_target_free(&tg);
    return r;
}

static xyl_result forest_camera(const options *o, render_job *j, float spacing)
{
    float lo[3], hi[3];
    tree_bounds(j, lo, hi);
    uint64_t side = (uint64_t)ceil(sqrt((double)o->render.forest));
    float half = 0.5f * (float)(side - 1) * spacing + 0.6f * spacing;
    const float flo[3] = {-half, lo[1], -half}, fhi[3] = {half, hi[1] * 1.2f, half};
    double deg = 3.14159265358979323846 / 180.0;
    double az = o->render.has_camera ? o->render.azimuth : 30.0;
    double el = o->render.has_camera ? o->render.elevation : 25.0;
    xyl_tess_camera_frame(flo, fhi, (float)(az * deg), (float)(el * deg), 0.8f,
                          (float)j->image.width / (float)j->image.height, &j->camera);
    if (o->render.has_camera && o->render.zoom != 1.0)
        xyl_tess_camera_zoom(&j->camera, (float)o->render.zoom);
    float dx = j->camera.eye[0] - j->camera.target[0], dy = j->camera.eye[1] - j->camera.target[1],
          dz = j->camera.eye[2] - j->camera.target[2];
    float dist = sqrtf(dx * dx + dy * dy + dz * dz);
    j->camera.near_plane = 0.01f * dist; /* depth precision over the whole forest */
    j->camera.far_plane = 4.0f * dist + 4.0f * half;
    return xyl_tess_camera_matrix(&j->camera, XYL_TESS_CLIP_GL, j->frame.view_proj, NULL);
}

static xyl_result render_forest(const options *o, render_job *j, xyl_billboard_gl *bb,
                                xyl_diag *d)
{
    float lo[3], hi[3];
    tree_bounds(j, lo, hi);
    float spacing = 1.1f * fmaxf(hi[0] - lo[0], hi[2] - lo[2]);
    xyl_forest_grid_desc gd = {0};
    gd.count = o->render.forest;
    gd.spacing = spacing;
    gd.jitter = 0.6f;
    gd.scale_min = 0.8f;
    gd.scale_max = 1.2f;
    gd.seed = 1;
    xyl_forest_instance *inst = malloc((size_t)gd.count * sizeof *inst);
    if (!inst) return XYL_ERR_OUT_OF_MEMORY;
    xyl_forest_gl *forest = NULL;
    xyl_forest_gl_species_desc sd = {0};
    sd.foliage = j->leaves.foliage;
    sd.stems = j->mesh;
    sd.billboard = bb;
    sd.stem_width = j->stem_width;
    uint32_t species = 0;
    uint32_t tw = XYL_LEAF_TEXTURE_WIDTH, th = XYL_LEAF_TEXTURE_HEIGHT;
    uint8_t *tex = malloc((size_t)tw * th * 4);
    xyl_result r = tex ? xyl_forest_grid(&gd, inst, gd.count, d) : XYL_ERR_OUT_OF_MEMORY;
    if (r == XYL_OK) r = forest_camera(o, j, spacing);
    if (r == XYL_OK) r = xyl_forest_gl_create(NULL, &forest, d);
    if (r == XYL_OK) r = xyl_forest_gl_add_species(forest, &sd, &species, d);
    if (r == XYL_OK) {
        xyl_leaf_texture(tex, tw, th);
        r = xyl_forest_gl_set_texture(forest, tex, tw, th, d);
    }
    if (r == XYL_OK) r = xyl_forest_gl_set_instances(forest, inst, gd.count, d);
    xyl_forest_gl_stats st;
    double ms = 0.0;
    if (r == XYL_OK) r = forest_frame(o, j, forest, &st, &ms, d);
    xyl_forest_gl_species_info info;
    if (r == XYL_OK) r = xyl_forest_gl_species(forest, species, &info, d);
    if (r == XYL_OK) {
        printf("forest: %llu trees (%u bytes each), %llu in view, spacing %.2f; leaf levels "
               "0..%u%s\n", (unsigned long long)st.instances, st.bytes_per_instance,
               (unsigned long long)st.visible, (double)spacing, info.level_count - 1,
               info.has_billboard ? " and billboards" : "");
        printf("forest frame: %.3f ms (wall, to glFinish), LOD choice %.3f ms CPU, upload "
               "%.3f ms; %llu draws, %llu leaves, %llu triangles, %llu with stems, %llu "
               "cross-fading, %llu with a per-leaf cut\n", ms, st.choose_ms, st.upload_ms,
               (unsigned long long)st.draws, (unsigned long long)st.leaves,
               (unsigned long long)st.triangles, (unsigned long long)st.with_stems,
               (unsigned long long)st.faded, (unsigned long long)st.per_leaf);
        printf("level leaves (error):");
        for (uint32_t k = 0; k < info.level_count; ++k)
            printf(" %u (%.3g)", info.level_leaves[k], (double)info.level_error[k]);
        printf("; billboard error %.3g, stems at levels below %u\n",
               (double)info.billboard_error, info.stem_levels);
        printf("instances per level:");
        for (uint32_t k = 0; k < info.level_count; ++k)
            printf(" %llu", (unsigned long long)st.per_level[k]);
        if (info.has_billboard)
            printf(", %s %llu", o->render.impostor ? "impostor" : "billboard",
                   (unsigned long long)st.per_level[XYL_FOREST_MAX_LEVELS]);
        printf("\n");
    }
    xyl_forest_gl_destroy(forest);
    free(tex);
    free(inst);
    return r;
}

static xyl_result render_gl(const options *o, render_job *j, xyl_diag *d)
{
    xyl_gl_context *ctx = NULL;
    xyl_tess_gl *gl = NULL;
    xyl_foliage_gl *leaves = NULL;
    xyl_billboard_gl *bb = NULL;
    xyl_result r = xyl_gl_context_create_headless(NULL, &ctx, d);
    if (r == XYL_OK) r = xyl_tess_camera_matrix(&j->camera, XYL_TESS_CLIP_GL, j->frame.view_proj, d);
    if (r == XYL_OK) r = xyl_tess_gl_create(NULL, j->patterns, &gl, d);
    if (r == XYL_OK) r = xyl_tess_gl_set_patches(gl, j->drawn, d);
    if (r == XYL_OK && j->draw_leaves) r = leaf_renderer(j, &leaves, d);
    tree_gl t = {j, gl, leaves,
                 o->render.tess == TESS_HARDWARE ? XYL_TESS_PATH_HARDWARE : XYL_TESS_PATH_INSTANCED,
                 j->image.wireframe};
    bool billboard = o->render.leaves == LEAVES_BILLBOARD;
    if (o->render.forest && j->lods) /* a forest's billboard shows every leaf */
        memset(j->lods, 0, j->leaves.foliage->sector_count * sizeof *j->lods);
    if (r == XYL_OK && billboard) r = bake_billboard(o, &t, &bb, d);
    if (r == XYL_OK && bb && o->render.billboard_error) r = billboard_error(o, &t, bb, d);
    double t0 = now_seconds();
    if (r == XYL_OK && o->render.forest) r = render_forest(o, j, bb, d);
    else if (r == XYL_OK && (leaves || bb)) r = draw_picture(&t, bb, j->rgba, d);
    else if (r == XYL_OK)
        r = xyl_tess_gl_render_rgba(gl, j->batches, &j->frame, t.path, &j->image, j->rgba, d);
    j->render_ms = (now_seconds() - t0) * 1e3;
    xyl_billboard_gl_destroy(bb);
    if (leaves) xyl_foliage_gl_destroy(leaves);
    if (r == XYL_OK) {
        if (!leaves) j->gpu_ms = xyl_tess_gl_last_gpu_ms(gl);
        printf("device: %s (OpenGL)\n", xyl_gl_context_renderer(ctx));
    }
    xyl_tess_gl_destroy(gl);
    xyl_gl_context_destroy(ctx);
    return r;
}

#else
static xyl_result render_gl(const options *o, render_job *j, xyl_diag *d)
{
    (void)o, (void)j;
    snprintf(d->message, sizeof d->message, "this xylem was built without the GL backend");
    return XYL_ERR_UNSUPPORTED;
}
#endif

#ifdef XYL_HAVE_VULKAN
/* Stems and leaves into one target of the CLI's own device (render_vk.c), as an engine would. */
static xyl_result render_vk_tree(const options *o, render_job *j, xyl_diag *d)
{
    uint32_t w = XYL_LEAF_TEXTURE_WIDTH, h = XYL_LEAF_TEXTURE_HEIGHT;
    uint8_t *tex = malloc((size_t)w * h * 4);
    if (!tex) return XYL_ERR_OUT_OF_MEMORY;
    xyl_leaf_texture(tex, w, h);
    xyl_cli_vk_tree t;
    memset(&t, 0, sizeof t);
    t.patterns = j->patterns;
    t.patches = j->drawn;
    t.batches = j->batches;
    t.frame = j->frame;
    t.image = &j->image;
    t.foliage = j->leaves.foliage;
    t.lods = j->adaptive ? NULL : j->lods;
    t.cut_view = &j->leaf_view;
    t.cut_leaves = &j->leaves_drawn;
    t.leaf_texture = tex;
    t.texture_width = w;
    t.texture_height = h;
    const render_options *ro = &o->render;
    xyl_cli_vk_billboard bb;
    memset(&bb, 0, sizeof bb);
    if (ro->leaves == LEAVES_BILLBOARD) {
        bb.kind = ro->impostor         ? XYL_BILLBOARD_OCTAHEDRAL
                  : ro->billboard_kind ? ro->billboard_kind - 1
                                       : XYL_BILLBOARD_CROSS;
        bb.planes = bb.kind == XYL_BILLBOARD_CROSS ? (ro->planes ? ro->planes : 4) : 0;
        bb.grid = bb.kind == XYL_BILLBOARD_OCTAHEDRAL ? ro->grid : 0;
        bb.resolution = ro->billboard_size ? ro->billboard_size : 512;
        tree_bounds(j, bb.lo, bb.hi);
        memcpy(bb.eye, j->camera.eye, sizeof bb.eye);
        t.billboard = &bb;
    }
    char name[256] = "";
    double t0 = now_seconds();
    xyl_result r = xyl_cli_render_vk_tree(&t, j->rgba, name, &j->gpu_ms, d);
    j->render_ms = (now_seconds() - t0) * 1e3;
    j->gpu_timer_all = true;
    j->gpu_timer_billboard = t.billboard != NULL;
    free(tex);
    if (r == XYL_OK) printf("device: %s (Vulkan)\n", name);
    if (r == XYL_OK && t.billboard)
        printf("billboard: %s, %u views of %u x %u texels, baked in %.1f ms (Vulkan)\n",
               billboard_name(bb.kind), bb.views, bb.resolution, bb.resolution, bb.bake_ms);
    return r;
}

static xyl_result render_vk(const options *o, render_job *j, xyl_diag *d)
{
    xyl_result r = xyl_tess_camera_matrix(&j->camera, XYL_TESS_CLIP_VULKAN, j->frame.view_proj, d);
    if (r == XYL_OK && j->draw_leaves) return render_vk_tree(o, j, d);
    xyl_tess_vk *vk = NULL;
    xyl_tess_vk_desc vd = {0};
    if (r == XYL_OK) r = xyl_tess_vk_create(&vd, j->patterns, &vk, d);
    if (r == XYL_OK) r = xyl_tess_vk_set_patches(vk, j->drawn, d);
    double t0 = now_seconds();
    if (r == XYL_OK) r = xyl_tess_vk_render_rgba(vk, j->batches, &j->frame, &j->image, j->rgba, d);
    j->render_ms = (now_seconds() - t0) * 1e3;
    if (r == XYL_OK) {
        j->gpu_ms = xyl_tess_vk_last_gpu_ms(vk);
        printf("device: %s (Vulkan)\n", xyl_tess_vk_device_name(vk));
    }
    xyl_tess_vk_destroy(vk);
    return r;
}
#else
static xyl_result render_vk(const options *o, render_job *j, xyl_diag *d)
{
    (void)o, (void)j;
    snprintf(d->message, sizeof d->message, "this xylem was built without the Vulkan backend");
    return XYL_ERR_UNSUPPORTED;
}
#endif

static void print_render(const options *o, const render_job *j, const char *path)
{
    if (o->render.forest) { /* render_forest printed its figures */
        printf("wrote %s\n", path);
        return;
    }
    if (j->draw_leaves && j->adaptive) {
        printf("leaves: --foliage adaptive: the coarsest leaf within the budget per cluster, "
               "%zu of %zu leaves drawn (LOD array built in %.3f ms)\n", j->leaves_drawn,
               j->leaves.foliage->original_count, j->leaves.build_ms);
    } else if (j->draw_leaves) {
        const xyl_foliage *f = j->leaves.foliage;
        uint32_t lo = UINT32_MAX, hi = 0, top = 0;
        for (uint32_t s = 0; s < f->sector_count; ++s) {
            lo = j->lods[s] < lo ? j->lods[s] : lo;
            hi = j->lods[s] > hi ? j->lods[s] : hi;
            top = f->sectors[s].merged_count > top ? f->sectors[s].merged_count : top;
        }
        char which[64];
        if (lo == hi) snprintf(which, sizeof which, "LOD %u", lo);
        else snprintf(which, sizeof which, "LODs %u..%u", lo, hi);
        printf("leaves: --foliage %s: %s of 0..%u, %zu of %zu leaves drawn (LOD array built in "
               "%.3f ms)\n", o->render.leaves == LEAVES_FULL ? "full" :
                         o->render.leaves == LEAVES_BILLBOARD ? "billboard (baked from)" : "lod",
               which, top,
               j->leaves_drawn, f->original_count, j->leaves.build_ms);
    }
    uint32_t lo = 64, hi = 0;
    for (size_t c = 0; c < j->batches->cmd_count; ++c) {
        lo = j->batches->batches[c].level < lo ? j->batches->batches[c].level : lo;
        hi = j->batches->batches[c].level > hi ? j->batches->batches[c].level : hi;
    }
    printf("patches: %zu (%zu quads), levels %u..%u, %llu triangles drawn\n", j->drawn->count,
           j->drawn->quad_count, lo, hi, (unsigned long long)j->batches->triangles);
    printf("time: level selection %.3f ms, render %.3f ms (one frame, wall, readback included), "
           "GPU timer %.3f ms%s\n", j->select_ms, j->render_ms, j->gpu_ms,
           !j->draw_leaves           ? ""
           : j->gpu_timer_billboard ? " (the billboard)"
           : j->gpu_timer_all       ? " (stems and leaves)"
                                    : " (stems)");
    printf("wrote %s\n", path);
}

/* A .glb (from xylem or any glTF writer) as the mesh to refine. */
static int load_glb(const char *path, xyl_mesh **mesh)
{
    size_t size = 0;
    int rc = 0;
    char *bytes = read_all(path, &size, &rc);
    if (!bytes) return rc;
    xyl_diag d = {0};
    xyl_result r = xyl_sample_read_glb((const unsigned char *)bytes, size, mesh, &d);
    free(bytes);
    return r ? report(path, r, &d) : 0;
}

/* The mesh to refine: a .glb, or the stems of a skeleton (file or grammar), whose skeleton
 * goes to *keep when keep is not NULL (it has the leaf attachments). */
static int load_mesh(const options *o, xyl_mesh **mesh, const char **source, xyl_skeleton **keep)
{
    if (o->mesh_path) {
        *source = o->mesh_path;
        return load_glb(o->mesh_path, mesh);
    }
    xyl_skeleton *sk = NULL;
    int rc = load_skeleton(o, &sk, source);
    if (rc) return rc;
    xyl_diag d = {0};
    xyl_result r = xyl_stems_build(sk, &o->stems, mesh, NULL, &d);
    if (keep && r == XYL_OK) *keep = sk;
    else xyl_skeleton_destroy(sk);
    return r ? report(*source, r, &d) : 0;
}

/* The source's leaves and their LODs. */
static int prepare_leaves(const options *o, render_job *j, const xyl_skeleton *sk,
                          const char *source)
{
    if (sk->leaf_count == 0) return 0;
    int rc = build_foliage(o, sk, source, &j->leaves);
    if (!rc) j->draw_leaves = j->leaves.foliage->leaf_count > 0;
    return rc;
}

static int cmd_render(const options *o)
{
    const render_options *ro = &o->render;
    if (!o->out || !ends_with(o->out, ".png")) return usage_error("%s", "'render' needs --out FILE.png");
    if ((o->skeleton_path != NULL) + (o->mesh_path != NULL) + (o->preset || o->grammar_path) > 1)
        return usage_error("%s", "give one of --skeleton, --mesh or a grammar source");
    if (ro->level && ro->error_px > 0.0) return usage_error("%s", "give --level or --error-px, not both");
    if (ro->vulkan && ro->tess == TESS_HARDWARE)
        return usage_error("%s", "--tess hardware is the GL backend's; use --backend gl");
    if (ro->frames || ro->screenshot)
        return usage_error("%s", "--frames and --screenshot are options of 'view'");
    bool billboard = ro->leaves == LEAVES_BILLBOARD;
    if (ro->billboard_error && ro->vulkan)
        return usage_error("%s", "--billboard-error renders with the GL backend only");
    if (!billboard && (ro->billboard_kind || ro->planes || ro->grid || ro->billboard_size ||
                       ro->billboard_error))
        return usage_error("%s", "--billboard, --planes, --grid, --billboard-size and "
                                 "--billboard-error go with --foliage billboard or impostor");
    if (ro->impostor && ro->billboard_kind && ro->billboard_kind != 4)
        return usage_error("%s", "--foliage impostor is the octahedral billboard; give "
                                 "--foliage billboard for another kind");
    if (ro->planes && ro->billboard_kind && ro->billboard_kind != 3)
        return usage_error("%s", "--planes is the cross billboard's");
    if (ro->grid && ro->billboard_kind != 4 && !ro->impostor)
        return usage_error("%s", "--grid is the octahedral billboard's (--foliage impostor)");
    if (ro->forest && (ro->vulkan || ro->leaves == LEAVES_NONE || ro->billboard_error))
        return usage_error("%s", "--forest draws with the GL backend, with --foliage lod, "
                                 "adaptive, full, billboard or impostor, without "
                                 "--billboard-error");
    if (ro->has_fade && !ro->forest) return usage_error("%s", "--fade goes with --forest");
    render_job j;
    memset(&j, 0, sizeof j);
    j.image.width = ro->width ? ro->width : 1024;
    j.image.height = ro->height ? ro->height : 1024;
    j.image.wireframe = ro->wireframe;
    j.image.samples = ro->samples ? ro->samples : 4;
    memcpy(j.image.background, render_background, sizeof render_background);
    const char *source = NULL;
    xyl_diag d = {0};
    xyl_result r = XYL_OK;
    xyl_skeleton *sk = NULL;
    /* --error-px given: the budget chooses the stems too (not for a --mesh or a forest) */
    bool budget = ro->error_px > 0.0 && !ro->forest;
    int rc = load_mesh(o, &j.mesh, &source, ro->leaves == LEAVES_NONE && !budget ? NULL : &sk);
    if (!rc && sk && ro->leaves != LEAVES_NONE) rc = prepare_leaves(o, &j, sk, source);
    for (size_t k = 0; sk && k < sk->node_count; ++k)
        j.stem_width = fmaxf(j.stem_width, 2.0f * sk->nodes[k].radius);
    if (!rc && sk && budget) rc = budget_stems(o, &j, sk, source);
    xyl_skeleton_destroy(sk);
    if (!rc && ro->forest && !j.draw_leaves) {
        fprintf(stderr, "xylem: %s: --forest needs a source with leaves\n", source);
        rc = EXIT_DATA;
    }
    if (!rc && r == XYL_OK) r = prepare_render(o, &j, &d);
    if (!rc && r == XYL_OK) {
        j.rgba = malloc((size_t)j.image.width * j.image.height * 4);
        if (!j.rgba) r = XYL_ERR_OUT_OF_MEMORY;
    }
    if (!rc && r == XYL_OK) {
        fill_frame(&j, ro->variant, &j.frame);
        r = ro->vulkan ? render_vk(o, &j, &d) : render_gl(o, &j, &d);
    }
    if (!rc && r != XYL_OK) rc = report_backend(source, r, &d);
    if (!rc) {
        char msg[512];
        if (xyl_png_write(o->out, j.rgba, j.image.width, j.image.height, msg, sizeof msg) != 0) {
            fprintf(stderr, "xylem: %s\n", msg);
            rc = EXIT_CANTCREAT;
        }
    }
    if (!rc) print_render(o, &j, o->out);
    render_job_free(&j);
    return rc;
}

#ifdef XYL_HAVE_GLFW
#ifdef XYL_HAVE_IMGUI
static int tune_view(const options *o);
#endif

static int cmd_view(const options *o)
{
    const render_options *ro = &o->render;
    if (o->out) return usage_error("%s", "'view' writes no --out (use --screenshot FILE.png)");
    if ((o->skeleton_path != NULL) + (o->mesh_path != NULL) + (o->preset || o->grammar_path) > 1)
        return usage_error("%s", "give one of --skeleton, --mesh or a grammar source");
    if (ro->level && ro->error_px > 0.0) return usage_error("%s", "give --level or --error-px, not both");
    if (ro->vulkan || ro->tess == TESS_CPU)
        return usage_error("%s", "'view' draws with the GL backend: --tess instanced or hardware");
    if (ro->has_camera && ro->zoom != 1.0)
        return usage_error("%s", "'view' zooms with the mouse wheel: --camera AZIMUTH,ELEVATION");
    if (ro->screenshot && (!ends_with(ro->screenshot, ".png") || !ro->frames))
        return usage_error("%s", "--screenshot takes FILE.png and needs --frames N");
    bool grammar = !o->skeleton_path && !o->mesh_path;
#ifdef XYL_HAVE_IMGUI
    if (grammar) return tune_view(o);
    if (o->set_count) return usage_error("%s", "--set tunes a grammar: not with --mesh or --skeleton");
    printf("view: the tuning panel regrows a grammar; --mesh and --skeleton show the fixed viewer\n");
#else
    if (o->set_count) {
        fprintf(stderr, "xylem: --set needs the tuning panel: this xylem was built without Dear "
                        "ImGui (libimgui-dev)\n");
        return EXIT_UNAVAILABLE;
    }
    if (grammar)
        printf("view: built without Dear ImGui (libimgui-dev): the fixed viewer, no tuning panel\n");
#endif
    xyl_mesh *mesh = NULL;
    const char *source = NULL;
    int rc = load_mesh(o, &mesh, &source, NULL);
    if (rc) return rc;
    double deg = 3.14159265358979323846 / 180.0;
    xyl_view_request req;
    memset(&req, 0, sizeof req);
    req.mesh = mesh;
    req.variant = ro->variant;
    req.path = ro->tess == TESS_HARDWARE ? XYL_TESS_PATH_HARDWARE : XYL_TESS_PATH_INSTANCED;
    req.fixed_level = ro->level;
    req.error_px = (float)ro->error_px;
    req.azimuth = (float)((ro->has_camera ? ro->azimuth : 30.0) * deg);
    req.elevation = (float)((ro->has_camera ? ro->elevation : 10.0) * deg);
    req.width = ro->width ? ro->width : 1024;
    req.height = ro->height ? ro->height : 1024;
    req.wireframe = ro->wireframe;
    req.samples = ro->samples ? ro->samples : 4;
    req.frames = ro->frames;
    req.screenshot = ro->screenshot;
    req.background = render_background;
    xyl_tess_frame look;
    fill_look(&look);
    req.look = &look;
    rc = xyl_view_run(&req);
    if (!rc && ro->screenshot) printf("wrote %s\n", ro->screenshot);
    xyl_mesh_destroy(mesh);
    return rc;
}

#ifdef XYL_HAVE_IMGUI
/* The command line's options as the panel's starting state; --set steps follow. */
static int tune_view(const options *o)
{
    const render_options *ro = &o->render;
    view_params p;
    view_params_init(&p);
    char err[512];
    const char *preset = o->preset ? o->preset : xyl_lsystem_default_preset();
    int rc = o->grammar_path ? view_params_set(&p, "grammar", o->grammar_path, err, sizeof err)
                             : view_params_set(&p, "preset", preset, err, sizeof err);
    if (rc) {
        fprintf(stderr, "xylem: %s\n", err);
        return rc;
    }
    p.has_depth = o->has_depth, p.depth = o->depth;
    p.has_seed = o->has_seed, p.seed = o->seed;
    p.turtle = o->turtle;
    p.stems = o->stems;
    p.variant = ro->variant;
    p.path = ro->tess == TESS_HARDWARE ? XYL_TESS_PATH_HARDWARE : XYL_TESS_PATH_INSTANCED;
    p.level = ro->level;
    if (ro->error_px > 0.0) p.error_px = (float)ro->error_px;
    p.wireframe = ro->wireframe;
    double deg = 3.14159265358979323846 / 180.0;
    if (ro->has_camera) p.azimuth = (float)(ro->azimuth * deg), p.elevation = (float)(ro->elevation * deg);
    rc = xyl_view_check_sets(&p, o->sets, o->set_count);
    xyl_tune_request req = {&p, o->sets, o->set_count, ro->width ? ro->width : 1280,
                            ro->height ? ro->height : 800, ro->samples ? ro->samples : 4,
                            ro->frames, ro->screenshot};
    if (!rc) rc = xyl_view_tune(&req);
    if (!rc && ro->screenshot) printf("wrote %s\n", ro->screenshot);
    view_params_free(&p);
    return rc;
}
#endif
#else
static int cmd_view(const options *o)
{
    (void)o;
    fprintf(stderr, "xylem: this xylem was built without GLFW: no 'view'\n");
    return EXIT_UNAVAILABLE;
}
#endif

int main(int argc, char **argv)
{
    if (argc < 2) {
        fputs(usage_text, stderr);
        return EXIT_USAGE;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        fputs(usage_text, stdout);
        return 0;
    }
    if (strcmp(cmd, "--version") == 0) {
        printf("xylem %d.%d.%d\n", XYL_VERSION_MAJOR, XYL_VERSION_MINOR, XYL_VERSION_PATCH);
        return 0;
    }
    if (strcmp(cmd, "presets") == 0) return argc == 2 ? cmd_presets() : usage_error("%s", "'presets' takes no arguments");
    if (strcmp(cmd, "preset") == 0) return cmd_preset(argc, argv);
    options o;
    memset(&o, 0, sizeof o);
    o.render.variant = XYL_TESS_ARC; /* the handle rule that follows bent branches */
    bool derive = strcmp(cmd, "derive") == 0, skeleton = strcmp(cmd, "skeleton") == 0;
    bool mesh = strcmp(cmd, "mesh") == 0, render = strcmp(cmd, "render") == 0;
    bool view = strcmp(cmd, "view") == 0, foliage = strcmp(cmd, "foliage") == 0;
    if (!derive && !skeleton && !mesh && !render && !view && !foliage)
        return usage_error("unknown command '%s'", cmd);
    int rc = parse_options(argc, argv, &o);
    if (rc) return rc;
    if (o.foliage.enabled && !mesh)
        return usage_error("%s", "--foliage is an option of 'mesh' and 'render'");
    if (o.set_count && !view) return usage_error("%s", "--set is an option of 'view'");
    if (o.foliage.given && !foliage && !o.foliage.enabled)
        return usage_error("%s", "--sectors, --aspect, --table, --leaf-texture, --leaf-mesh, "
                                 "--leaf-template and --cost go with 'foliage' or 'mesh --foliage'");
    if (o.foliage.leaf_mesh && o.foliage.leaf_template)
        return usage_error("%s", "give --leaf-mesh or --leaf-template, not both");
    if (o.foliage.leaf_template && o.foliage.aspect > 0.0)
        return usage_error("%s", "--leaf-template sets the leaves' shape: it takes no --aspect");
    if (foliage) {
        o.foliage.enabled = true;
        return cmd_foliage(&o);
    }
    if (mesh) return cmd_mesh(&o);
    if (render) return cmd_render(&o);
    if (view) return cmd_view(&o);
    return derive ? cmd_derive(&o) : cmd_skeleton(&o);
}
