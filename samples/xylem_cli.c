/* xylem: command-line front end for tools and scripts (docs/cli.md).
 *
 * Exit codes (sysexits): 0 success, 64 usage (bad option, unknown preset), 65 bad input data
 * (grammar, skeleton, non-finite numbers, a limit reached), 66 input file unreadable,
 * 71 out of memory, 73 output file not writable. Errors go to stderr as
 * "xylem: <source>:<line>:<column>: <message>". */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <xylem/xyl_lsystem.h>

enum { EXIT_USAGE = 64, EXIT_DATA = 65, EXIT_NOINPUT = 66, EXIT_OSERR = 71, EXIT_CANTCREAT = 73 };

typedef struct options {
    const char *preset;
    const char *grammar_path;
    const char *skeleton_path;
    xyl_stems_desc stems;
    const char *out;
    bool has_seed, has_depth, merge;
    uint64_t seed;
    uint32_t depth;
    xyl_turtle_desc turtle;
} options;

static const char usage_text[] =
    "usage: xylem <command> [options]\n"
    "\n"
    "commands:\n"
    "  presets                      list the built-in grammars\n"
    "  preset NAME                  print a built-in grammar's text\n"
    "  derive   [source] [--seed N] [--depth N]\n"
    "                               print the derived module string\n"
    "  skeleton [source] [--seed N] [--depth N] [--radius pipe|grammar]\n"
    "           [--radius-exponent X] [--tip-radius R] [--angles grammar|murray]\n"
    "           [--merge-collinear] --out FILE.skel|FILE.obj\n"
    "                               grow the branch skeleton and write it\n"
    "  mesh     [source | --skeleton FILE.skel] [skeleton options] [--sides K]\n"
    "           [--subdivide none|catmark|loop] [--normals branch|smooth]\n"
    "           --out FILE.glb|FILE.obj\n"
    "                               wrap the skeleton in one closed quad mesh and write it\n"
    "\n"
    "source: --preset NAME (default: the default tree) or --grammar FILE\n"
    "exit codes: 0 ok, 64 usage, 65 bad input, 66 unreadable input, 71 out of memory,\n"
    "            73 output not writable\n";

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
    } else if (strcmp(opt, "--skeleton") == 0) {
        o->skeleton_path = val;
    } else {
        return usage_error("unknown option '%s'", opt);
    }
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
        if (strncmp(opt, "--", 2) != 0) return usage_error("unexpected argument '%s'", opt);
        if (i + 1 >= argc) return usage_error("option '%s' needs a value", opt);
        const char *val = argv[++i];
        uint64_t u;
        if (strcmp(opt, "--preset") == 0) o->preset = val;
        else if (strcmp(opt, "--grammar") == 0) o->grammar_path = val;
        else if (strcmp(opt, "--out") == 0) o->out = val;
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
            int rc = parse_turtle_option(o, opt, val);
            if (rc) return rc;
        }
    }
    if (o->preset && o->grammar_path) return usage_error("%s", "give --preset or --grammar, not both");
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

static int cmd_presets(void)
{
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        const char *name = xyl_lsystem_preset_name(i);
        bool def = strcmp(name, xyl_lsystem_default_preset()) == 0;
        printf("%-22s %s%s\n", name, xyl_lsystem_preset_summary(i), def ? " (default)" : "");
    }
    return 0;
}

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

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
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
    return written(path, xyl_skeleton_write_file(sk, path, fmt, &d), &d);
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

static int write_mesh(const xyl_mesh *m, const char *path)
{
    xyl_mesh_format fmt = ends_with(path, ".obj") ? XYL_MESH_FORMAT_OBJ : XYL_MESH_FORMAT_GLB;
    xyl_diag d = {0};
    return written(path, xyl_mesh_write_file(m, path, fmt, &d), &d);
}

static int cmd_mesh(const options *o)
{
    if (!o->out) return usage_error("%s", "'mesh' needs --out FILE.glb or FILE.obj");
    if (!ends_with(o->out, ".glb") && !ends_with(o->out, ".obj"))
        return usage_error("--out must end in .glb or .obj, not '%s'", o->out);
    if (o->skeleton_path && (o->preset || o->grammar_path))
        return usage_error("%s", "give --skeleton or a grammar source, not both");
    double t0 = now_seconds();
    xyl_skeleton *sk = NULL;
    xyl_mesh *m = NULL;
    const char *source = NULL;
    int rc = load_skeleton(o, &sk, &source);
    double t1 = now_seconds();
    xyl_diag d = {0};
    if (!rc) {
        xyl_result r = xyl_stems_build(sk, &o->stems, &m, &d);
        if (r) rc = report(source, r, &d);
    }
    double t2 = now_seconds();
    if (!rc) rc = write_mesh(m, o->out);
    if (!rc) {
        printf("%s: %zu nodes -> %zu vertices, %zu quads, %zu triangles (%zu in the triangulated "
               "view)\n",
               source, sk->node_count, m->vertex_count, m->quad_count, m->triangle_count,
               m->tri_view_count);
        printf("time: skeleton %.3f ms, mesh %.3f ms, write %.3f ms\n", (t1 - t0) * 1e3,
               (t2 - t1) * 1e3, (now_seconds() - t2) * 1e3);
        printf("wrote %s\n", o->out);
    }
    xyl_mesh_destroy(m);
    xyl_skeleton_destroy(sk);
    return rc;
}

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
    bool derive = strcmp(cmd, "derive") == 0, skeleton = strcmp(cmd, "skeleton") == 0;
    bool mesh = strcmp(cmd, "mesh") == 0;
    if (!derive && !skeleton && !mesh) return usage_error("unknown command '%s'", cmd);
    int rc = parse_options(argc, argv, &o);
    if (rc) return rc;
    if (mesh) return cmd_mesh(&o);
    return derive ? cmd_derive(&o) : cmd_skeleton(&o);
}
