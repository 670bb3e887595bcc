/* The tuning viewer's parameters and their --set names (view_params.h). */
#define _POSIX_C_SOURCE 200809L

#include "view_params.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEG (3.14159265358979323846 / 180.0)

void view_params_init(view_params *p)
{
    memset(p, 0, sizeof *p);
    p->error_px = 0.5f;
    p->variant = XYL_TESS_ARC;
    p->panel = true;
    p->leaves = true; /* a leafy grammar opens leafy; leaves=0 skips the foliage stage */
    p->azimuth = (float)(30.0 * DEG);
    p->elevation = (float)(10.0 * DEG);
    p->zoom = 1.0f;
    const float bg[4] = {0.86f, 0.90f, 0.95f, 1.0f}, light[3] = {0.42f, 0.78f, 0.46f};
    memcpy(p->background, bg, sizeof bg);
    memcpy(p->light, light, sizeof light);
}

bool view_params_copy(view_params *dst, const view_params *src)
{
    char *text = NULL;
    if (src->text && !(text = strdup(src->text))) return false;
    free(dst->text);
    *dst = *src;
    dst->text = text;
    return true;
}

void view_params_free(view_params *p)
{
    free(p->text);
    p->text = NULL;
}

bool view_params_set_text(view_params *p, const char *text, const char *source)
{
    char *copy = strdup(text);
    if (!copy) return false;
    free(p->text);
    p->text = copy;
    p->define_count = 0;
    if (source) snprintf(p->source, sizeof p->source, "%s", source);
    return true;
}

const view_define *view_params_define(const view_params *p, const char *name)
{
    for (uint32_t i = 0; i < p->define_count; ++i)
        if (strcmp(p->defines[i].name, name) == 0) return &p->defines[i];
    return NULL;
}

bool view_params_tune_define(view_params *p, const char *name, double value)
{
    view_define *d = (view_define *)view_params_define(p, name);
    if (!d) {
        if (p->define_count == VIEW_MAX_DEFINES || strlen(name) >= VIEW_NAME_CAP) return false;
        d = &p->defines[p->define_count++];
        snprintf(d->name, sizeof d->name, "%s", name);
    }
    d->value = value;
    return true;
}

/* ---- grammar text ---------------------------------------------------------------------------- */

/* The next line of text: [*s, end) without its line break; *s moves past it. */
static bool next_line(const char **s, const char **start, size_t *len)
{
    if (!**s) return false;
    *start = *s;
    const char *nl = strchr(*s, '\n');
    *len = nl ? (size_t)(nl - *s) : strlen(*s);
    *s = nl ? nl + 1 : *s + *len;
    return true;
}

/* A header line "#word rest": the word (without '#') and where the rest starts, or false. */
static bool header_word(const char *line, size_t len, char *word, size_t cap, size_t *rest)
{
    size_t i = 0;
    while (i < len && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i >= len || line[i] != '#') return false;
    size_t n = 0;
    for (++i; i < len && (isalnum((unsigned char)line[i]) || line[i] == '_'); ++i)
        if (n + 1 < cap) word[n++] = line[i];
    word[n] = '\0';
    *rest = i;
    return n > 0;
}

/* The comment of a line ("//" standing as a word), or len when none. */
static size_t comment_start(const char *line, size_t len)
{
    for (size_t i = 0; i + 1 < len; ++i)
        if (line[i] == '/' && line[i + 1] == '/' && (i == 0 || isspace((unsigned char)line[i - 1])) &&
            (i + 2 == len || isspace((unsigned char)line[i + 2])))
            return i;
    return len;
}

/* "#define NAME rest": NAME and the rest's span. */
static bool define_parts(const char *line, size_t len, char *name, size_t cap, size_t *value_at)
{
    char word[16];
    size_t i = 0;
    if (!header_word(line, len, word, sizeof word, &i) || strcmp(word, "define") != 0) return false;
    while (i < len && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t n = 0;
    for (; i < len && (isalnum((unsigned char)line[i]) || line[i] == '_'); ++i)
        if (n + 1 < cap) name[n++] = line[i];
    name[n] = '\0';
    *value_at = i;
    return n > 0;
}

uint32_t view_text_defines(const char *text, view_text_define *out, uint32_t cap)
{
    uint32_t count = 0, line_no = 0;
    const char *s = text ? text : "", *line;
    size_t len;
    while (count < cap && next_line(&s, &line, &len)) {
        ++line_no;
        char name[VIEW_NAME_CAP], value[64];
        size_t at;
        if (!define_parts(line, len, name, sizeof name, &at)) continue;
        size_t end = comment_start(line, len);
        if (end < at || end - at >= sizeof value) continue;
        memcpy(value, line + at, end - at);
        value[end - at] = '\0';
        char *e = NULL;
        double v = strtod(value, &e);
        if (e == value || !isfinite(v)) continue;
        while (*e && isspace((unsigned char)*e)) ++e;
        if (*e) continue; /* an expression: not a slider */
        snprintf(out[count].name, sizeof out[count].name, "%s", name);
        out[count].value = v;
        out[count].line = line_no;
        ++count;
    }
    return count;
}

void view_text_line(const char *text, uint32_t line, char *out, size_t cap)
{
    const char *s = text ? text : "", *start = NULL;
    size_t len = 0;
    out[0] = '\0';
    for (uint32_t n = 0; n < line; ++n)
        if (!next_line(&s, &start, &len)) return;
    if (len >= cap) len = cap - 1;
    memcpy(out, start, len);
    out[len] = '\0';
    if (len && out[len - 1] == '\r') out[len - 1] = '\0';
}

/* A growing output buffer; ok turns false on the first failed allocation. */
typedef struct text_out {
    char *data;
    size_t size, cap;
    bool ok;
} text_out;

static void put(text_out *o, const char *s, size_t n)
{
    if (!o->ok) return;
    if (o->size + n + 1 > o->cap) {
        size_t cap = (o->size + n + 1) * 2;
        char *d = realloc(o->data, cap);
        if (!d) {
            o->ok = false;
            return;
        }
        o->data = d, o->cap = cap;
    }
    memcpy(o->data + o->size, s, n);
    o->size += n;
    o->data[o->size] = '\0';
}

static void putf(text_out *o, const char *fmt, ...)
{
    char buf[160];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (n > 0) put(o, buf, (size_t)n < sizeof buf ? (size_t)n : sizeof buf - 1);
}

/* The header line for word (angle, step, depth, seed) if it is tuned. */
static bool header_value(const view_params *p, const char *word, bool with_derive, text_out *o)
{
    if (strcmp(word, "angle") == 0 && p->has_angle) putf(o, "#angle %.9g", p->angle_deg);
    else if (strcmp(word, "step") == 0 && p->has_step) putf(o, "#step %.9g", p->step);
    else if (strcmp(word, "tropism") == 0 && p->has_tropism)
        putf(o, "#tropism %.9g %.9g %.9g %.9g", p->tropism[0], p->tropism[1], p->tropism[2], p->tropism[3]);
    else if (with_derive && strcmp(word, "depth") == 0 && p->has_depth) putf(o, "#depth %u", p->depth);
    else if (with_derive && strcmp(word, "seed") == 0 && p->has_seed)
        putf(o, "#seed %llu", (unsigned long long)p->seed);
    else return false;
    return true;
}

char *view_params_tuned_text(const view_params *p, bool with_derive)
{
    static const char *const words[] = {"angle", "step", "tropism", "depth", "seed"};
    const char *text = p->text ? p->text : "";
    bool seen[5] = {false, false, false, false, false};
    const char *s = text, *line;
    size_t len;
    while (next_line(&s, &line, &len)) {
        char word[16];
        size_t at;
        if (!header_word(line, len, word, sizeof word, &at)) continue;
        for (int w = 0; w < 5; ++w)
            if (strcmp(word, words[w]) == 0) seen[w] = true;
    }
    text_out o = {NULL, 0, 0, true};
    put(&o, "", 0);
    /* Tuned header values the grammar does not state go first, before the axiom. */
    for (int w = 0; w < 5; ++w)
        if (!seen[w] && header_value(p, words[w], with_derive, &o)) put(&o, "\n", 1);
    s = text;
    while (next_line(&s, &line, &len)) {
        bool has_nl = line[len] == '\n';
        char word[16], name[VIEW_NAME_CAP];
        size_t at, end = comment_start(line, len);
        const view_define *d = NULL;
        if (define_parts(line, len, name, sizeof name, &at) && (d = view_params_define(p, name))) {
            put(&o, line, at);
            putf(&o, " %.9g", d->value);
            if (end < len) put(&o, " ", 1), put(&o, line + end, len - end);
        } else if (header_word(line, len, word, sizeof word, &at) &&
                   header_value(p, word, with_derive, &o)) {
            if (end < len) put(&o, " ", 1), put(&o, line + end, len - end);
        } else {
            put(&o, line, len);
        }
        if (has_nl) put(&o, "\n", 1);
    }
    if (!o.ok) {
        free(o.data);
        return NULL;
    }
    return o.data;
}

/* ---- --set ----------------------------------------------------------------------------------- */

static int bad(char *err, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, cap, fmt, ap);
    va_end(ap);
    return 64;
}

static bool number(const char *s, double lo, double hi, double *out)
{
    char *e = NULL;
    errno = 0;
    double v = strtod(s, &e);
    if (!*s || errno || *e || !(v >= lo && v <= hi)) return false;
    *out = v;
    return true;
}

static bool whole(const char *s, uint64_t hi, uint64_t *out)
{
    char *e = NULL;
    errno = 0;
    if (!*s || *s == '-') return false;
    unsigned long long v = strtoull(s, &e, 10);
    if (errno || *e || v > hi) return false;
    *out = v;
    return true;
}

static bool flag(const char *s, bool *out)
{
    if (!strcmp(s, "1") || !strcmp(s, "on") || !strcmp(s, "true")) *out = true;
    else if (!strcmp(s, "0") || !strcmp(s, "off") || !strcmp(s, "false")) *out = false;
    else return false;
    return true;
}

/* One of names[] (NULL-terminated): its index, or -1. */
static int choice(const char *s, const char *const *names)
{
    for (int i = 0; names[i]; ++i)
        if (strcmp(s, names[i]) == 0) return i;
    return -1;
}

static bool triple(const char *s, double lo, double hi, float out[3])
{
    double v[3];
    char extra;
    if (sscanf(s, "%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &extra) != 3) return false;
    for (int k = 0; k < 3; ++k)
        if (!(v[k] >= lo && v[k] <= hi)) return false;
    for (int k = 0; k < 3; ++k) out[k] = (float)v[k];
    return true;
}

static int load_file(view_params *p, const char *path, char *err, size_t cap)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(err, cap, "%s: cannot open: %s", path, strerror(errno));
        return 66;
    }
    char *text = NULL;
    size_t size = 0;
    FILE *m = open_memstream(&text, &size);
    char buf[4096];
    size_t got;
    bool ok = m != NULL;
    while (ok && (got = fread(buf, 1, sizeof buf, f)) > 0) ok = fwrite(buf, 1, got, m) == got;
    ok = ok && !ferror(f);
    if (m && fclose(m)) ok = false;
    fclose(f);
    if (ok && memchr(text, '\0', size)) ok = false;
    if (ok) ok = view_params_set_text(p, text, path);
    free(text);
    if (!ok) snprintf(err, cap, "%s: cannot read (or holds a NUL byte)", path);
    return ok ? 0 : 66;
}

static int set_grammar(view_params *p, const char *name, const char *v, char *err, size_t cap)
{
    double x;
    uint64_t u;
    if (!strcmp(name, "preset")) {
        const char *src = xyl_lsystem_preset_source(v);
        if (!src) return bad(err, cap, "unknown preset '%s' (run 'xylem presets' for the list)", v);
        if (!view_params_set_text(p, src, v)) return bad(err, cap, "out of memory");
    } else if (!strcmp(name, "grammar")) {
        return load_file(p, v, err, cap);
    } else if (!strcmp(name, "grammar_text")) {
        if (!view_params_set_text(p, v, "grammar_text")) return bad(err, cap, "out of memory");
    } else if (!strcmp(name, "depth")) {
        if (!whole(v, 64, &u)) return bad(err, cap, "depth takes a whole number 0..64, not '%s'", v);
        p->has_depth = true, p->depth = (uint32_t)u;
    } else if (!strcmp(name, "seed")) {
        if (!whole(v, UINT64_MAX, &u)) return bad(err, cap, "seed takes a whole number >= 0, not '%s'", v);
        p->has_seed = true, p->seed = u;
    } else if (!strcmp(name, "angle")) {
        if (!number(v, -360.0, 360.0, &x))
            return bad(err, cap, "angle takes degrees in [-360, 360], not '%s'", v);
        p->has_angle = true, p->angle_deg = x;
    } else if (!strcmp(name, "step")) {
        if (!number(v, 1e-6, 1e6, &x)) return bad(err, cap, "step takes a number in [1e-6, 1e6], not '%s'", v);
        p->has_step = true, p->step = x;
    } else if (!strcmp(name, "tropism")) {
        double t[4];
        char extra;
        if (sscanf(v, "%lf,%lf,%lf,%lf%c", &t[0], &t[1], &t[2], &t[3], &extra) != 4 ||
            !isfinite(t[0] + t[1] + t[2] + t[3]) || fabs(t[0]) + fabs(t[1]) + fabs(t[2]) > 1e6 ||
            !(fabs(t[3]) <= 10.0))
            return bad(err, cap, "tropism takes X,Y,Z,ELASTICITY (|e| <= 10), not '%s'", v);
        p->has_tropism = true;
        memcpy(p->tropism, t, sizeof t);
    } else if (!strncmp(name, "define.", 7)) {
        view_text_define defs[VIEW_MAX_DEFINES];
        uint32_t n = view_text_defines(p->text, defs, VIEW_MAX_DEFINES), i = 0;
        while (i < n && strcmp(defs[i].name, name + 7) != 0) ++i;
        if (i == n) return bad(err, cap, "the grammar has no '#define %s' with a number to tune", name + 7);
        if (!number(v, -1e30, 1e30, &x)) return bad(err, cap, "%s takes a number, not '%s'", name, v);
        if (!view_params_tune_define(p, name + 7, x)) return bad(err, cap, "too many tuned #defines");
    } else {
        return -1;
    }
    return 0;
}

static int set_tree(view_params *p, const char *name, const char *v, char *err, size_t cap)
{
    static const char *const radius[] = {"pipe", "grammar", NULL}, *const angles[] = {"grammar", "murray", NULL};
    static const char *const subdiv[] = {"none", "catmark", "loop", NULL};
    static const char *const normals[] = {"branch", "smooth", NULL}, *const joints[] = {"checked", "unchecked", NULL};
    xyl_turtle_desc *t = &p->turtle;
    double x;
    uint64_t u;
    int c;
    if (!strcmp(name, "radius")) {
        if ((c = choice(v, radius)) < 0) return bad(err, cap, "radius takes pipe or grammar, not '%s'", v);
        t->radius_mode = (xyl_radius_mode)c;
    } else if (!strcmp(name, "radius_exponent")) {
        if (!number(v, 0.5, 8.0, &x) || x == 0.5) return bad(err, cap, "radius_exponent takes a number in (0.5, 8], not '%s'", v);
        t->radius_exponent = x;
    } else if (!strcmp(name, "tip_radius")) {
        if (!number(v, 0.0, 1e30, &x)) return bad(err, cap, "tip_radius takes a number >= 0 (0: #width / 2), not '%s'", v);
        t->tip_radius = x;
    } else if (!strcmp(name, "angles")) {
        if ((c = choice(v, angles)) < 0) return bad(err, cap, "angles takes grammar or murray, not '%s'", v);
        t->angle_mode = (xyl_angle_mode)c;
    } else if (!strcmp(name, "murray_min_angle") || !strcmp(name, "murray_max_angle")) {
        if (!number(v, 0.0, 180.0, &x)) return bad(err, cap, "%s takes degrees in [0, 180] (0: default), not '%s'", name, v);
        *(name[7] == 'm' && name[8] == 'i' ? &t->murray_min_angle : &t->murray_max_angle) = x * DEG;
    } else if (!strcmp(name, "merge_collinear")) {
        if (!flag(v, &t->merge_collinear)) return bad(err, cap, "merge_collinear takes 0 or 1, not '%s'", v);
    } else if (!strcmp(name, "sides")) {
        if (!whole(v, 32, &u) || u < 3) return bad(err, cap, "sides takes a whole number 3..32, not '%s'", v);
        p->stems.sides = (uint32_t)u;
    } else if (!strcmp(name, "subdivide")) {
        if ((c = choice(v, subdiv)) < 0) return bad(err, cap, "subdivide takes none, catmark or loop, not '%s'", v);
        p->stems.subdivision = (xyl_subdivision)c;
    } else if (!strcmp(name, "normals")) {
        if ((c = choice(v, normals)) < 0) return bad(err, cap, "normals takes branch or smooth, not '%s'", v);
        p->stems.normals = (xyl_normal_mode)c;
    } else if (!strcmp(name, "joints")) {
        if ((c = choice(v, joints)) < 0) return bad(err, cap, "joints takes checked or unchecked, not '%s'", v);
        p->stems.joints = (xyl_joint_check)c;
    } else if (!strcmp(name, "error_world")) {
        if (!number(v, 0.0, 1e30, &x)) return bad(err, cap, "error_world takes a number >= 0 (0: every branch gets sides), not '%s'", v);
        p->stems.error_world = (float)x;
    } else if (!strcmp(name, "sides_refined")) {
        if (!flag(v, &p->stems.sides_refined)) return bad(err, cap, "sides_refined takes 0 or 1, not '%s'", v);
    } else if (!strcmp(name, "base")) {
        static const char *const bases[] = {"closed", "open", NULL};
        if ((c = choice(v, bases)) < 0) return bad(err, cap, "base takes closed or open, not '%s'", v);
        p->stems.base = (xyl_stems_base)c;
    } else if (!strcmp(name, "root_flare")) {
        if (!number(v, 0.0, XYL_STEMS_MAX_ROOT_FLARE, &x)) return bad(err, cap, "root_flare takes a number in [0, 8], not '%s'", v);
        p->stems.root_flare = (float)x;
    } else if (!strcmp(name, "leaves")) {
        if (!flag(v, &p->leaves)) return bad(err, cap, "leaves takes 0 or 1, not '%s'", v);
    } else if (!strcmp(name, "foliage")) {
        static const char *const draws[] = {"lod", "full", "none", NULL};
        if ((c = choice(v, draws)) < 0) return bad(err, cap, "foliage takes lod, full or none, not '%s'", v);
        p->leaf_draw = (view_leaf_draw)c;
        if (p->leaf_draw != VIEW_LEAVES_NONE) p->leaves = true; /* drawing them needs them built */
    } else if (!strcmp(name, "leaf_aspect")) {
        if (!number(v, 0.0, 100.0, &x)) return bad(err, cap, "leaf_aspect takes a number in [0, 100] (0: 0.5), not '%s'", v);
        p->leaf_aspect = (float)x;
    } else if (!strcmp(name, "leaf_jitter")) {
        if (!number(v, 0.0, 0.99, &x)) return bad(err, cap, "leaf_jitter takes a number in [0, 0.99], not '%s'", v);
        p->leaf_jitter = (float)x;
    } else if (!strcmp(name, "leaf_sectors")) {
        if (!whole(v, 256, &u) || u < 1) return bad(err, cap, "leaf_sectors takes a whole number 1..256, not '%s'", v);
        p->leaf_sectors = (uint32_t)u;
    } else {
        return -1;
    }
    return 0;
}

static int set_view(view_params *p, const char *name, const char *v, char *err, size_t cap)
{
    static const char *const variants[] = {"pn", "rounded", "circle", "arc", NULL};
    static const char *const tess[] = {"instanced", "hardware", NULL};
    static const char *const cameras[] = {"default", "front", "side", "top", "low", NULL};
    static const float presets[][2] = {{30, 10}, {0, 0}, {90, 0}, {0, 89}, {30, -20}};
    double x;
    uint64_t u;
    int c;
    if (!strcmp(name, "variant")) {
        if ((c = choice(v, variants)) < 0) return bad(err, cap, "variant takes pn, rounded, circle or arc, not '%s'", v);
        p->variant = (xyl_tess_variant)c;
    } else if (!strcmp(name, "tess")) {
        if ((c = choice(v, tess)) < 0) return bad(err, cap, "tess takes instanced or hardware, not '%s'", v);
        p->path = c ? XYL_TESS_PATH_HARDWARE : XYL_TESS_PATH_INSTANCED;
    } else if (!strcmp(name, "level")) {
        if (!whole(v, XYL_TESS_MAX_LEVEL, &u)) return bad(err, cap, "level takes 0 (adaptive) to 64, not '%s'", v);
        p->level = (uint32_t)u;
    } else if (!strcmp(name, "error_px")) {
        if (!number(v, 1.0 / 64, 64.0, &x)) return bad(err, cap, "error_px takes pixels in [1/64, 64], not '%s'", v);
        p->error_px = (float)x;
    } else if (!strcmp(name, "wireframe")) {
        if (!flag(v, &p->wireframe)) return bad(err, cap, "wireframe takes 0 or 1, not '%s'", v);
    } else if (!strcmp(name, "panel")) {
        if (!flag(v, &p->panel)) return bad(err, cap, "panel takes 0 or 1, not '%s'", v);
    } else if (!strcmp(name, "camera")) {
        if ((c = choice(v, cameras)) < 0) return bad(err, cap, "camera takes default, front, side, top or low, not '%s'", v);
        p->azimuth = (float)(presets[c][0] * DEG), p->elevation = (float)(presets[c][1] * DEG);
        p->zoom = 1.0f;
    } else if (!strcmp(name, "azimuth")) {
        if (!number(v, -3600.0, 3600.0, &x)) return bad(err, cap, "azimuth takes degrees, not '%s'", v);
        p->azimuth = (float)(x * DEG);
    } else if (!strcmp(name, "elevation")) {
        if (!number(v, -89.0, 89.0, &x)) return bad(err, cap, "elevation takes degrees in [-89, 89], not '%s'", v);
        p->elevation = (float)(x * DEG);
    } else if (!strcmp(name, "zoom")) {
        if (!number(v, 0.05, 4.0, &x)) return bad(err, cap, "zoom takes a number in [0.05, 4], not '%s'", v);
        p->zoom = (float)x;
    } else if (!strcmp(name, "background")) {
        if (!triple(v, 0.0, 1.0, p->background)) return bad(err, cap, "background takes R,G,B in [0, 1], not '%s'", v);
    } else if (!strcmp(name, "light")) {
        float l[3];
        if (!triple(v, -1e6, 1e6, l) || l[0] * l[0] + l[1] * l[1] + l[2] * l[2] < 1e-12f)
            return bad(err, cap, "light takes a direction X,Y,Z (not zero), not '%s'", v);
        float n = sqrtf(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
        for (int k = 0; k < 3; ++k) p->light[k] = l[k] / n;
    } else {
        return -1;
    }
    return 0;
}

int view_params_set(view_params *p, const char *name, const char *value, char *err, size_t cap)
{
    int rc = set_grammar(p, name, value, err, cap);
    if (rc < 0) rc = set_tree(p, name, value, err, cap);
    if (rc < 0) rc = set_view(p, name, value, err, cap);
    if (rc < 0) rc = bad(err, cap, "--set: unknown name '%s' (docs/cli.md lists them)", name);
    return rc;
}
