/* The CPU tessellation: every instance's pattern evaluated with the reference evaluator into a
 * plain triangle mesh (what the instanced path draws, vertex for vertex). */
#include <string.h>

#include "tess_internal.h"
#include "xyl_internal.h"

static const xyl_tess_pattern_range *range_of(const xyl_tess_patterns *pat,
                                              const xyl_tess_instance *in)
{
    return &pat->ranges[in->kind == XYL_TESS_KIND_QUAD ? 0 : 1][in->level];
}

static xyl_result check_batches(const xyl_tess_patches *tp, const xyl_tess_patterns *pat,
                                const xyl_tess_batches *b, size_t *nv, size_t *nt,
                                xyl_diag *diag)
{
    *nv = 0;
    *nt = 0;
    for (size_t i = 0; i < b->instance_count; ++i) {
        const xyl_tess_instance *in = &b->instances[i];
        if (in->patch >= tp->count || in->level < 1 || in->level > pat->max_level ||
            in->kind != xyl_tess_patch_kind(&tp->records[in->patch]))
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, (int64_t)i,
                             "instance %zu does not match the patches or patterns", i);
        *nv += range_of(pat, in)->vertex_count;
        *nt += range_of(pat, in)->index_count / 3;
    }
    return XYL_OK;
}

static void evaluate(const xyl_tess_patches *tp, const xyl_tess_patterns *pat,
                     const xyl_tess_batches *b, xyl_vec3 *pos, xyl_vec3 *nrm, uint32_t *idx)
{
    uint32_t base = 0;
    for (size_t i = 0; i < b->instance_count; ++i) {
        const xyl_tess_instance *in = &b->instances[i];
        const xyl_tess_pattern_range *r = range_of(pat, in);
        const xyl_tess_patch *rec = &tp->records[in->patch];
        for (uint32_t v = 0; v < r->vertex_count; ++v) {
            uint32_t pk = pat->vertices[r->first_vertex + v];
            float p[3], n[3];
            xyl_tess_eval_lattice(rec, tp->variant, in->level, in->edge_levels, pk & 0xffu,
                                  (pk >> XYL_TESS_PATTERN_SHIFT_J) & 0xffu, p, n);
            pos[base + v] = (xyl_vec3){p[0], p[1], p[2]};
            nrm[base + v] = (xyl_vec3){n[0], n[1], n[2]};
        }
        for (uint32_t k = 0; k < r->index_count; ++k)
            *idx++ = base + pat->indices[r->first_index + k];
        base += r->vertex_count;
    }
}

xyl_result xyl_tess_refine(const xyl_tess_patches *patches, const xyl_tess_patterns *patterns,
                           const xyl_tess_batches *batches, const xyl_mesh_limits *limits,
                           const xyl_allocator *alloc, xyl_mesh **out, xyl_diag *diag)
{
    if (!patches || !patterns || !batches || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "patches, patterns, batches and out are required");
    size_t nv, nt;
    xyl_result r = check_batches(patches, patterns, batches, &nv, &nt, diag);
    if (r != XYL_OK) return r;
    xyl_mesh_limits lim = limits ? *limits : (xyl_mesh_limits){0};
    uint64_t max_v = lim.max_vertices ? lim.max_vertices : (1u << 26);
    uint64_t max_f = lim.max_faces ? lim.max_faces : (1u << 26);
    if (nv > max_v || nt > max_f || nv > UINT32_MAX)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "refined mesh of %zu vertices and %zu triangles exceeds the limits", nv,
                         nt);
    xyl_vec3 *pos = xyl__calloc(alloc, nv ? nv : 1, sizeof *pos);
    xyl_vec3 *nrm = xyl__calloc(alloc, nv ? nv : 1, sizeof *nrm);
    uint32_t *idx = xyl__calloc(alloc, nt ? 3 * nt : 1, sizeof *idx);
    if (!pos || !nrm || !idx) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for %zu vertices", nv);
    } else {
        evaluate(patches, patterns, batches, pos, nrm, idx);
        xyl_mesh_desc md = {0};
        md.positions = pos;
        md.normals = nrm;
        md.vertex_count = nv;
        md.triangles = idx;
        md.triangle_count = nt;
        md.limits = lim;
        if (alloc) md.alloc = *alloc;
        r = xyl_mesh_create(&md, out, diag);
    }
    xyl__free(alloc, pos);
    xyl__free(alloc, nrm);
    xyl__free(alloc, idx);
    return r;
}
