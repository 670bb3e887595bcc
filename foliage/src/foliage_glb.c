/* glTF 2.0 binary export of a foliage, with or without its stems (docs/foliage.md, "Export"):
 * the leaves in array order as one primitive of quads, a double-sided alpha-masked material,
 * the optional PNG texture, and the LOD tables in the leaves node's extras. The container comes
 * from mesh/'s document builder (glb_write.h), which also writes the stems' part. */
#include <math.h>
#include <string.h>

#include "foliage_internal.h"
#include "glb_write.h"

#define DEFAULT_ALPHA_CUTOFF 0.5f
/* A leaf's corner order is xyl__leaf_corners': (-s,-t), (+s,-t), (-s,+t), (+s,+t); its two
 * triangles turn counter-clockwise seen from the side the normal points to. */
static const uint32_t LEAF_TRIANGLES[XYL_FOLIAGE_GLB_INDICES_PER_LEAF] = {0, 1, 3, 0, 3, 2};
/* glTF's sampler enums: LINEAR, LINEAR_MIPMAP_LINEAR, CLAMP_TO_EDGE. */
#define GL_LINEAR 9729
#define GL_LINEAR_MIPMAP_LINEAR 9987
#define GL_CLAMP_TO_EDGE 33071
/* A normal this close to unit (squared length) is written bit for bit, as the stem writer does. */

typedef struct leaf_doc {
    const xyl_foliage *f;
    const unsigned char *png; /* NULL: no texture */
    size_t png_size;
    float cutoff;
    bool has_stems;
    xyl__glb_mesh stems;
    uint32_t first_accessor; /* the leaves' POSITION; NORMAL, TEXCOORD_0, indices follow */
    uint32_t image_view;
    double origin[3]; /* the leaves' node translation (the desc's origin) */
} leaf_doc;

/* ==== the leaves' bytes ====================================================================== */

static void leaf_corners_f(const xyl_leaf *l, xyl_vec3 out[4])
{
    xyl__dvec3 c[4];
    xyl__leaf_corners(l, c);
    for (int k = 0; k < 4; ++k) out[k] = xyl__to_f3(c[k]);
}

static void emit_positions(const void *ctx, xyl__sink *s)
{
    const xyl_foliage *f = ctx;
    for (size_t i = 0; i < f->leaf_count; ++i) {
        xyl_vec3 c[4];
        leaf_corners_f(&f->leaves[i], c);
        for (int k = 0; k < 4; ++k) {
            xyl__put_f32le(s, c[k].x);
            xyl__put_f32le(s, c[k].y);
            xyl__put_f32le(s, c[k].z);
        }
    }
}

static void emit_normals(const void *ctx, xyl__sink *s)
{
    const xyl_foliage *f = ctx;
    for (size_t i = 0; i < f->leaf_count; ++i) {
        xyl_vec3 n = xyl__glb_unit_normal(f->leaves[i].normal);
        for (int k = 0; k < 4; ++k) {
            xyl__put_f32le(s, n.x);
            xyl__put_f32le(s, n.y);
            xyl__put_f32le(s, n.z);
        }
    }
}

/* Corner (s, t) takes (u0 or u1, v0 or v1) of the leaf's rectangle; glTF's v runs down the
 * image, so the file holds 1 - v: the tip end (v1 = 1) is the image's top row. */
static void emit_uvs(const void *ctx, xyl__sink *s)
{
    const xyl_foliage *f = ctx;
    for (size_t i = 0; i < f->leaf_count; ++i) {
        const float *r = f->leaves[i].uv;
        bool whole = r[0] == 0.0f && r[1] == 0.0f && r[2] == 0.0f && r[3] == 0.0f;
        float u0 = r[0], v0 = r[1], u1 = whole ? 1.0f : r[2], v1 = whole ? 1.0f : r[3];
        for (int k = 0; k < 4; ++k) {
            xyl__put_f32le(s, k & 1 ? u1 : u0);
            xyl__put_f32le(s, 1.0f - (k & 2 ? v1 : v0));
        }
    }
}

static void emit_indices(const void *ctx, xyl__sink *s)
{
    const xyl_foliage *f = ctx;
    for (size_t i = 0; i < f->leaf_count; ++i)
        for (int k = 0; k < XYL_FOLIAGE_GLB_INDICES_PER_LEAF; ++k)
            xyl__put_u32le(s, (uint32_t)(4 * i) + LEAF_TRIANGLES[k]);
}

static void emit_image(const void *ctx, xyl__sink *s)
{
    const leaf_doc *d = ctx;
    xyl__put(s, d->png, d->png_size);
}

static void corner_bounds(const xyl_foliage *f, xyl__glb_accessor *a)
{
    a->bounds = true;
    for (size_t i = 0; i < f->leaf_count; ++i) {
        xyl_vec3 c[4];
        leaf_corners_f(&f->leaves[i], c);
        for (int k = 0; k < 4; ++k) {
            if (i == 0 && k == 0) a->min = a->max = c[0];
            a->min.x = fminf(a->min.x, c[k].x);
            a->min.y = fminf(a->min.y, c[k].y);
            a->min.z = fminf(a->min.z, c[k].z);
            a->max.x = fmaxf(a->max.x, c[k].x);
            a->max.y = fmaxf(a->max.y, c[k].y);
            a->max.z = fmaxf(a->max.z, c[k].z);
        }
    }
}

/* The leaves' four views and accessors (none for zero leaves), and the image's view. */
static xyl_result add_leaves(leaf_doc *d, xyl__glb *g, xyl_diag *diag)
{
    const xyl_foliage *f = d->f;
    if (f->leaf_count > UINT32_MAX / 4)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "%zu leaves take more vertices than a GLB's 32-bit indices reach",
                         f->leaf_count);
    if (f->leaf_count == 0) return XYL_OK;
    uint64_t nv = 4 * (uint64_t)f->leaf_count;
    uint32_t v;
    v = xyl__glb_add_view(g, 12 * nv, XYL__GL_ARRAY_BUFFER, emit_positions, f);
    d->first_accessor = xyl__glb_add_accessor(g, v, XYL__GL_FLOAT, "VEC3", nv);
    v = xyl__glb_add_view(g, 12 * nv, XYL__GL_ARRAY_BUFFER, emit_normals, f);
    xyl__glb_add_accessor(g, v, XYL__GL_FLOAT, "VEC3", nv);
    v = xyl__glb_add_view(g, 8 * nv, XYL__GL_ARRAY_BUFFER, emit_uvs, f);
    xyl__glb_add_accessor(g, v, XYL__GL_FLOAT, "VEC2", nv);
    uint64_t ni = (uint64_t)XYL_FOLIAGE_GLB_INDICES_PER_LEAF * f->leaf_count;
    v = xyl__glb_add_view(g, 4 * ni, XYL__GL_ELEMENT_ARRAY_BUFFER, emit_indices, f);
    xyl__glb_add_accessor(g, v, XYL__GL_UNSIGNED_INT, "SCALAR", ni);
    if (d->png) d->image_view = xyl__glb_add_view(g, d->png_size, 0, emit_image, d);
    uint64_t total = xyl__glb_layout(g);
    if (total > UINT32_MAX) return xyl__glb_too_large(total, diag);
    corner_bounds(f, &g->accessors[d->first_accessor]);
    return XYL_OK;
}

/* ==== the JSON =============================================================================== */

static void json_lods(const xyl_foliage_sector *sec, xyl__sink *s)
{
    xyl__put_str(s, ",\"lods\":[");
    for (uint32_t i = 0; i <= sec->merged_count; ++i) {
        const xyl_foliage_lod *l = &sec->lods[i];
        xyl__put_str(s, i ? ",[" : "[");
        xyl__put_uint(s, l->a);
        xyl__put_str(s, ",");
        xyl__put_uint(s, l->b);
        xyl__put_str(s, ",");
        xyl__put_uint(s, l->c);
        xyl__put_str(s, ",");
        xyl__put_float(s, l->error);
        xyl__put_str(s, "]");
    }
    xyl__put_str(s, "]");
}

static void json_extras(const xyl_foliage *f, xyl__sink *s)
{
    xyl__put_str(s, ",\"extras\":{\"xylem_foliage\":{\"version\":1,\"leaf_count\":");
    xyl__put_uint(s, f->leaf_count);
    xyl__put_str(s, ",\"original_count\":");
    xyl__put_uint(s, f->original_count);
    xyl__put_str(s, ",\"vertices_per_leaf\":");
    xyl__put_uint(s, XYL_FOLIAGE_GLB_VERTICES_PER_LEAF);
    xyl__put_str(s, ",\"indices_per_leaf\":");
    xyl__put_uint(s, XYL_FOLIAGE_GLB_INDICES_PER_LEAF);
    xyl__put_json_vec3(s, ",\"axis_origin\":", f->axis_origin);
    xyl__put_json_vec3(s, ",\"axis_direction\":", f->axis_direction);
    xyl__put_json_vec3(s, ",\"azimuth_zero\":", f->azimuth_zero);
    xyl__put_str(s, ",\"sectors\":[");
    for (uint32_t k = 0; k < f->sector_count; ++k) {
        const xyl_foliage_sector *sec = &f->sectors[k];
        xyl__put_str(s, k ? ",{\"base\":" : "{\"base\":");
        xyl__put_uint(s, sec->base);
        xyl__put_str(s, ",\"original_count\":");
        xyl__put_uint(s, sec->original_count);
        xyl__put_str(s, ",\"merged_count\":");
        xyl__put_uint(s, sec->merged_count);
        xyl__put_json_vec3(s, ",\"center\":", sec->center);
        xyl__put_str(s, ",\"radius\":");
        xyl__put_float(s, sec->radius);
        json_lods(sec, s);
        xyl__put_str(s, "}");
    }
    xyl__put_str(s, "]}}");
}

static void json_leaves_mesh(const leaf_doc *d, xyl__sink *s)
{
    static const char *const keys[] = {("{\"name\":\"leaves\",\"primitives\":[{\"attributes\":{"
                                        "\"POSITION\":"),
                                       ",\"NORMAL\":", ",\"TEXCOORD_0\":", "},\"indices\":"};
    for (uint32_t k = 0; k < 4; ++k) {
        xyl__put_str(s, keys[k]);
        xyl__put_uint(s, d->first_accessor + k);
    }
    xyl__put_str(s, ",\"material\":0,\"mode\":");
    xyl__put_uint(s, XYL__GL_TRIANGLES);
    xyl__put_str(s, "}]}");
}

/* Double-sided and alpha-masked; a texture's colour as it is, or a leaf green without one. */
static void json_material(const leaf_doc *d, xyl__sink *s)
{
    xyl__put_str(s, ",\"materials\":[{\"name\":\"leaf\",\"pbrMetallicRoughness\":{");
    if (d->png)
        xyl__put_str(s, "\"baseColorTexture\":{\"index\":0}");
    else
        xyl__put_str(s, "\"baseColorFactor\":[0.23,0.42,0.12,1]");
    xyl__put_str(s, ",\"metallicFactor\":0,\"roughnessFactor\":0.8},\"alphaMode\":\"MASK\","
                    "\"alphaCutoff\":");
    xyl__put_float(s, d->cutoff);
    xyl__put_str(s, ",\"doubleSided\":true}]");
    if (!d->png) return;
    xyl__put_str(s, ",\"textures\":[{\"sampler\":0,\"source\":0}],\"samplers\":[{\"magFilter\":");
    xyl__put_uint(s, GL_LINEAR);
    xyl__put_str(s, ",\"minFilter\":");
    xyl__put_uint(s, GL_LINEAR_MIPMAP_LINEAR);
    xyl__put_str(s, ",\"wrapS\":");
    xyl__put_uint(s, GL_CLAMP_TO_EDGE);
    xyl__put_str(s, ",\"wrapT\":");
    xyl__put_uint(s, GL_CLAMP_TO_EDGE);
    xyl__put_str(s, "}],\"images\":[{\"bufferView\":");
    xyl__put_uint(s, d->image_view);
    xyl__put_str(s, ",\"mimeType\":\"image/png\"}]");
}

/* Nodes "stems" (when given) and "leaves"; a part without geometry is a node without a mesh. */
static void leaf_body(const void *ctx, xyl__sink *s)
{
    const leaf_doc *d = ctx;
    bool stems_mesh = d->has_stems && !d->stems.empty, leaves_mesh = d->f->leaf_count > 0;
    xyl__put_str(s, d->has_stems ? "\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":["
                                 : "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[");
    if (d->has_stems) {
        xyl__put_str(s, stems_mesh ? "{\"name\":\"stems\",\"mesh\":0" : "{\"name\":\"stems\"");
        xyl__put_json_translation(s, d->stems.mesh->origin);
        xyl__put_str(s, "},");
    }
    xyl__put_str(s, "{\"name\":\"leaves\"");
    xyl__put_json_translation(s, d->origin);
    if (leaves_mesh) {
        xyl__put_str(s, ",\"mesh\":");
        xyl__put_uint(s, stems_mesh ? 1 : 0);
    }
    json_extras(d->f, s);
    xyl__put_str(s, "}]");
    if (!stems_mesh && !leaves_mesh) return;
    xyl__put_str(s, ",\"meshes\":[");
    if (stems_mesh) xyl__glb_mesh_json(&d->stems, s);
    if (stems_mesh && leaves_mesh) xyl__put_str(s, ",");
    if (leaves_mesh) json_leaves_mesh(d, s);
    xyl__put_str(s, "]");
    if (leaves_mesh) json_material(d, s);
}

/* ==== checking and planning ================================================================== */

static const unsigned char PNG_SIGNATURE[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};

/* The signature and a first IHDR chunk with a size: enough that a reader sees a PNG image (the
 * library decodes no image; a broken stream further on is the caller's). */
static bool looks_like_png(const unsigned char *b, size_t n)
{
    static const unsigned char ihdr[8] = {0, 0, 0, 13, 'I', 'H', 'D', 'R'};
    if (n < 8 + 8 + 13 + 4 || memcmp(b, PNG_SIGNATURE, 8) != 0 || memcmp(b + 8, ihdr, 8) != 0)
        return false;
    uint32_t w = (uint32_t)b[16] << 24 | (uint32_t)b[17] << 16 | (uint32_t)b[18] << 8 | b[19];
    uint32_t h = (uint32_t)b[20] << 24 | (uint32_t)b[21] << 16 | (uint32_t)b[22] << 8 | b[23];
    return w > 0 && h > 0;
}

static xyl_result check_desc(const xyl_foliage_glb_desc *desc, leaf_doc *d, xyl_diag *diag)
{
    d->cutoff = DEFAULT_ALPHA_CUTOFF;
    if (!desc) return XYL_OK;
    if (!isfinite(desc->alpha_cutoff))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "alpha_cutoff is not finite");
    if (desc->alpha_cutoff < 0.0f || desc->alpha_cutoff > 1.0f)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "alpha_cutoff %g is outside [0, 1]", (double)desc->alpha_cutoff);
    if (desc->alpha_cutoff > 0.0f) d->cutoff = desc->alpha_cutoff;
    if (!desc->texture_png != !desc->texture_png_size)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "texture_png and texture_png_size go together (%s with size %zu)",
                         desc->texture_png ? "bytes" : "NULL", desc->texture_png_size);
    if (desc->texture_png && !looks_like_png(desc->texture_png, desc->texture_png_size))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "texture_png is not a PNG image (no signature and IHDR chunk)");
    if (desc->texture_png && desc->texture_png_size > UINT32_MAX)
        return xyl__glb_too_large(desc->texture_png_size, diag);
    if (!isfinite(desc->origin[0]) || !isfinite(desc->origin[1]) || !isfinite(desc->origin[2]))
        return xyl__fail(diag, XYL_ERR_NON_FINITE, 0, 0, -1, "the origin is not finite");
    memcpy(d->origin, desc->origin, sizeof d->origin);
    return XYL_OK;
}

/* The whole document; on success d holds the stems' part (xyl__glb_mesh_free). */
static xyl_result plan_doc(const xyl_foliage *f, const xyl_foliage_glb_desc *desc, leaf_doc *d,
                           xyl__glb *g, xyl_diag *diag)
{
    memset(d, 0, sizeof *d);
    memset(g, 0, sizeof *g);
    d->f = f;
    xyl_result r = check_desc(desc, d, diag);
    if (r != XYL_OK) return r;
    /* a texture needs a material, which only leaves have */
    if (desc && desc->texture_png && f->leaf_count) {
        d->png = desc->texture_png;
        d->png_size = desc->texture_png_size;
    }
    d->has_stems = desc && desc->stems;
    if (d->has_stems) r = xyl__glb_mesh_add(desc->stems, &desc->alloc, g, &d->stems, diag);
    if (r == XYL_OK) r = add_leaves(d, g, diag);
    g->body = leaf_body;
    g->body_ctx = d;
    if (r == XYL_OK) r = xyl__glb_finish(g, diag);
    if (r != XYL_OK) xyl__glb_mesh_free(&d->stems);
    return r;
}

/* ==== public ================================================================================= */

xyl_result xyl_foliage_write_glb_memory(const xyl_foliage *foliage,
                                        const xyl_foliage_glb_desc *desc, void *out,
                                        size_t capacity, size_t *size, xyl_diag *diag)
{
    if (!foliage || (!out && !size))
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "foliage and out or size must be given");
    leaf_doc d;
    xyl__glb g;
    xyl_result r = plan_doc(foliage, desc, &d, &g, diag);
    if (r != XYL_OK) return r;
    r = xyl__glb_write_memory(&g, out, capacity, size, diag);
    xyl__glb_mesh_free(&d.stems);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}

xyl_result xyl_foliage_write_glb_file(const xyl_foliage *foliage,
                                      const xyl_foliage_glb_desc *desc, const char *path,
                                      xyl_diag *diag)
{
    if (!foliage || !path || !*path)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "foliage and path must be given");
    leaf_doc d;
    xyl__glb g;
    xyl_result r = plan_doc(foliage, desc, &d, &g, diag);
    if (r != XYL_OK) return r;
    r = xyl__glb_write_file(&g, path, desc ? &desc->alloc : NULL, diag);
    xyl__glb_mesh_free(&d.stems);
    if (r == XYL_OK) xyl__diag_ok(diag);
    return r;
}
