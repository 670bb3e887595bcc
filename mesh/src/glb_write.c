/* The byte sink and the GLB document shared by the writers of mesh/ and foliage/ (glb_write.h).
 * docs/mesh-export.md and docs/foliage.md describe the files they make. */
#include <assert.h>
#include <string.h>

#include "float_text.h"
#include "glb_write.h"

/* GLB container (glTF 2.0 spec, "Binary glTF Layout"). */
#define GLB_MAGIC UINT32_C(0x46546C67)      /* "glTF" */
#define GLB_VERSION UINT32_C(2)
#define GLB_CHUNK_JSON UINT32_C(0x4E4F534A) /* "JSON" */
#define GLB_CHUNK_BIN UINT32_C(0x004E4942)  /* "BIN\0" */
#define GLB_HEADER_BYTES 12u
#define GLB_CHUNK_HEADER_BYTES 8u
#define GLB_ALIGN 4u

/* ==== byte sink ============================================================================== */

static bool sink_room(xyl__sink *s, size_t n)
{
    size_t cap = s->cap;
    while (cap - s->len < n) cap = cap > SIZE_MAX / 2 ? SIZE_MAX : 2 * cap;
    unsigned char *b = xyl__alloc(s->alloc, cap);
    if (!b) return false;
    memcpy(b, s->buf, s->len);
    xyl__free(s->alloc, s->buf);
    s->buf = b;
    s->cap = cap;
    return true;
}

void xyl__put(xyl__sink *s, const void *bytes, size_t n)
{
    if (s->overflow || n > SIZE_MAX - 1 - s->len ||
        (s->cap && s->cap - s->len < n + 1 && !sink_room(s, n + 1))) {
        s->overflow = true;
        return;
    }
    if (s->buf) memcpy(s->buf + s->len, bytes, n);
    s->len += n;
}

void xyl__put_str(xyl__sink *s, const char *text)
{
    xyl__put(s, text, strlen(text));
}

void xyl__put_uint(xyl__sink *s, uint64_t v)
{
    char b[24];
    size_t k = sizeof b;
    do {
        b[--k] = (char)('0' + v % 10);
        v /= 10;
    } while (v != 0);
    xyl__put(s, b + k, sizeof b - k);
}

/* '.' whatever the locale (float_text.h). */
void xyl__put_float(xyl__sink *s, float v)
{
    char out[XYL__FLOAT_TEXT_MAX];
    xyl__put(s, out, xyl__float_text(v, out));
}

void xyl__put_double(xyl__sink *s, double v)
{
    char out[XYL__DOUBLE_TEXT_MAX];
    xyl__put(s, out, xyl__double_text(v, out));
}

void xyl__put_json_translation(xyl__sink *s, const double origin[3])
{
    if (origin[0] == 0.0 && origin[1] == 0.0 && origin[2] == 0.0) return;
    xyl__put_str(s, ",\"translation\":[");
    for (int k = 0; k < 3; ++k) {
        if (k) xyl__put_str(s, ",");
        xyl__put_double(s, origin[k]);
    }
    xyl__put_str(s, "]");
}

void xyl__put_u32le(xyl__sink *s, uint32_t v)
{
    const unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8),
                                (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    xyl__put(s, b, sizeof b);
}

void xyl__put_f32le(xyl__sink *s, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    xyl__put_u32le(s, bits);
}

void xyl__put_padding(xyl__sink *s, size_t n, char byte)
{
    for (size_t i = 0; i < n; ++i) xyl__put(s, &byte, 1);
}

xyl_vec3 xyl__glb_unit_normal(xyl_vec3 n)
{
    xyl__dvec3 d = xyl__from_f3(n);
    if (fabs(xyl__d3_dot(d, d) - 1.0) <= 1e-5) return n;
    return xyl__to_f3(xyl__d3_normalize_or(d, xyl__d3(0, 1, 0)));
}

void xyl__put_json_vec3(xyl__sink *s, const char *key, xyl_vec3 v)
{
    xyl__put_str(s, key);
    xyl__put_str(s, "[");
    xyl__put_float(s, v.x);
    xyl__put_str(s, ",");
    xyl__put_float(s, v.y);
    xyl__put_str(s, ",");
    xyl__put_float(s, v.z);
    xyl__put_str(s, "]");
}

/* ==== the document =========================================================================== */

static uint64_t pad4(uint64_t n)
{
    return (GLB_ALIGN - n % GLB_ALIGN) % GLB_ALIGN;
}

uint32_t xyl__glb_add_view(xyl__glb *g, uint64_t bytes, int target, xyl__glb_emit_fn emit,
                           const void *ctx)
{
    assert(g->view_count < XYL__GLB_MAX_VIEWS);
    xyl__glb_view *v = &g->views[g->view_count];
    memset(v, 0, sizeof *v);
    v->bytes = bytes;
    v->target = target;
    v->emit = emit;
    v->ctx = ctx;
    return g->view_count++;
}

uint32_t xyl__glb_add_accessor(xyl__glb *g, uint32_t view, int component, const char *type,
                               uint64_t count)
{
    assert(g->accessor_count < XYL__GLB_MAX_VIEWS);
    xyl__glb_accessor *a = &g->accessors[g->accessor_count];
    memset(a, 0, sizeof *a);
    a->view = view;
    a->component = component;
    a->type = type;
    a->count = count;
    return g->accessor_count++;
}

static uint64_t glb_total(const xyl__glb *g)
{
    uint64_t t = GLB_HEADER_BYTES + GLB_CHUNK_HEADER_BYTES + g->json_len + pad4(g->json_len);
    if (g->bin_len) t += GLB_CHUNK_HEADER_BYTES + g->bin_len + pad4(g->bin_len);
    return t;
}

uint64_t xyl__glb_layout(xyl__glb *g)
{
    uint64_t at = 0;
    for (uint32_t i = 0; i < g->view_count; ++i) {
        at += pad4(at);
        g->views[i].offset = at;
        at += g->views[i].bytes; /* no overflow: fewer than 16 views under 2^60 bytes each */
    }
    g->bin_len = at;
    return glb_total(g);
}

xyl_result xyl__glb_too_large(uint64_t bytes, xyl_diag *diag)
{
    return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                     "the GLB would take %llu bytes; its length fields hold at most %lu",
                     (unsigned long long)bytes, (unsigned long)UINT32_MAX);
}

static void json_accessors(const xyl__glb *g, xyl__sink *s)
{
    xyl__put_str(s, ",\"accessors\":[");
    for (uint32_t i = 0; i < g->accessor_count; ++i) {
        const xyl__glb_accessor *a = &g->accessors[i];
        xyl__put_str(s, i ? ",{\"bufferView\":" : "{\"bufferView\":");
        xyl__put_uint(s, a->view);
        xyl__put_str(s, ",\"componentType\":");
        xyl__put_uint(s, (uint64_t)a->component);
        xyl__put_str(s, ",\"count\":");
        xyl__put_uint(s, a->count);
        xyl__put_str(s, ",\"type\":\"");
        xyl__put_str(s, a->type);
        xyl__put_str(s, "\"");
        if (a->bounds) {
            xyl__put_json_vec3(s, ",\"min\":", a->min);
            xyl__put_json_vec3(s, ",\"max\":", a->max);
        }
        xyl__put_str(s, "}");
    }
    xyl__put_str(s, "]");
}

static void json_buffers(const xyl__glb *g, xyl__sink *s)
{
    xyl__put_str(s, ",\"bufferViews\":[");
    for (uint32_t i = 0; i < g->view_count; ++i) {
        const xyl__glb_view *v = &g->views[i];
        xyl__put_str(s, i ? ",{\"buffer\":0,\"byteOffset\":" : "{\"buffer\":0,\"byteOffset\":");
        xyl__put_uint(s, v->offset);
        xyl__put_str(s, ",\"byteLength\":");
        xyl__put_uint(s, v->bytes);
        if (v->target) {
            xyl__put_str(s, ",\"target\":");
            xyl__put_uint(s, (uint64_t)v->target);
        }
        xyl__put_str(s, "}");
    }
    xyl__put_str(s, "],\"buffers\":[{\"byteLength\":");
    xyl__put_uint(s, g->bin_len);
    xyl__put_str(s, "}]");
}

static void render_json(const xyl__glb *g, xyl__sink *s)
{
    xyl__put_str(s, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"xylem\"},\"scene\":0,");
    g->body(g->body_ctx, s);
    if (g->view_count) {
        json_accessors(g, s);
        json_buffers(g, s);
    }
    xyl__put_str(s, "}");
}

xyl_result xyl__glb_finish(xyl__glb *g, xyl_diag *diag)
{
    xyl__glb_layout(g);
    xyl__sink count = {NULL, 0, false, 0, NULL};
    render_json(g, &count);
    g->json_len = count.len;
    g->total = glb_total(g);
    if (count.overflow || g->total > UINT32_MAX) return xyl__glb_too_large(g->total, diag);
    return XYL_OK;
}

void xyl__glb_emit(const xyl__glb *g, xyl__sink *s)
{
    uint64_t json_chunk = g->json_len + pad4(g->json_len);
    xyl__put_u32le(s, GLB_MAGIC);
    xyl__put_u32le(s, GLB_VERSION);
    xyl__put_u32le(s, (uint32_t)g->total);
    xyl__put_u32le(s, (uint32_t)json_chunk);
    xyl__put_u32le(s, GLB_CHUNK_JSON);
    render_json(g, s);
    xyl__put_padding(s, (size_t)pad4(g->json_len), ' ');
    if (g->bin_len == 0) return;
    xyl__put_u32le(s, (uint32_t)(g->bin_len + pad4(g->bin_len)));
    xyl__put_u32le(s, GLB_CHUNK_BIN);
    uint64_t at = 0;
    for (uint32_t i = 0; i < g->view_count; ++i) {
        const xyl__glb_view *v = &g->views[i];
        xyl__put_padding(s, (size_t)(v->offset - at), '\0');
        size_t before = s->len;
        v->emit(v->ctx, s);
        assert(s->overflow || s->len - before == v->bytes);
        (void)before;
        at = v->offset + v->bytes;
    }
    xyl__put_padding(s, (size_t)pad4(g->bin_len), '\0');
}

xyl_result xyl__glb_write_memory(const xyl__glb *g, void *out, size_t capacity, size_t *size,
                                 xyl_diag *diag)
{
    if (size) *size = (size_t)g->total;
    if (!out) return XYL_OK;
    if (capacity < g->total)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "the GLB takes %llu bytes; the buffer holds %zu",
                         (unsigned long long)g->total, capacity);
    xyl__sink fill = {out, 0, false, 0, NULL};
    xyl__glb_emit(g, &fill);
    assert(!fill.overflow && fill.len == g->total);
    return XYL_OK;
}

xyl_result xyl__glb_write_file(const xyl__glb *g, const char *path, const xyl_allocator *alloc,
                               xyl_diag *diag)
{
    unsigned char *buf = xyl__alloc(alloc, (size_t)g->total + 1);
    if (!buf) return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the GLB");
    xyl__sink fill = {buf, 0, false, 0, NULL};
    xyl__glb_emit(g, &fill);
    assert(!fill.overflow && fill.len == g->total);
    xyl_result r = xyl__write_file_atomic(path, buf, fill.len, alloc, diag);
    xyl__free(alloc, buf);
    return r;
}
