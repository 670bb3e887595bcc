/* Reads a glTF 2.0 binary (.glb) into an xyl_mesh through tinygltf (Debian libtinygltf-dev), for
 * `xylem render --mesh`. The one C++ file of the samples; no exception crosses this interface. */
#ifndef XYL_SAMPLES_GLB_READ_H
#define XYL_SAMPLES_GLB_READ_H

#include <stddef.h>

#include <xylem/xyl_mesh.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Every TRIANGLES primitive of every mesh, in mesh space (node transforms are not applied), merged
 * into one mesh: POSITION (float VEC3) required, NORMAL (float VEC3) on all primitives or none
 * (then computed), indices of any unsigned type or none. In a file xylem wrote (asset generator
 * "xylem") consecutive triangles (a, b, c), (a, c, d) are rejoined into the quad (a, b, c, d) the
 * writer split, and its mesh "leaves" (foliage quads, not a surface) is left out. Embedded
 * images are not decoded. Errors: XYL_ERR_PARSE (not glTF, or a file this reader does not take:
 * the message says what), XYL_ERR_INVALID_ARGUMENT, XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED,
 * XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl_sample_read_glb(const unsigned char *data, size_t size, xyl_mesh **out,
                               xyl_diag *diag);

/* One LOD row and one sector of a foliage's table, as the leaves node's extras hold them. */
typedef struct xyl_sample_leaf_lod {
    uint32_t a, b, c;
    float error;
} xyl_sample_leaf_lod;

typedef struct xyl_sample_leaf_sector {
    uint32_t base, original_count, merged_count;
    size_t lod_count;
    xyl_sample_leaf_lod *lods;
} xyl_sample_leaf_sector;

/* The leaves of a .glb that xyl_foliage_write_glb_* wrote (docs/foliage.md, "Export"), as the
 * file holds them. Arrays from malloc; xyl_sample_glb_leaves_free frees them. */
typedef struct xyl_sample_glb_leaves {
    size_t leaf_count;          /* from the primitive: its vertices / 4 */
    xyl_vec3 *positions;        /* 4 per leaf */
    xyl_vec3 *normals;          /* 4 per leaf */
    float *uvs;                 /* 8 per leaf */
    uint32_t *indices;          /* 6 per leaf */
    size_t extras_leaf_count, extras_original_count; /* what the extras say */
    uint32_t sector_count;
    xyl_sample_leaf_sector *sectors;
    size_t stem_vertex_count;   /* the mesh "stems", 0 without one */
    int masked, double_sided;   /* the leaves' material: alphaMode MASK, doubleSided */
    double alpha_cutoff;
    size_t texture_bytes;       /* the base colour texture's PNG bytes, 0 without one */
} xyl_sample_glb_leaves;

/* Reads the node "leaves" (its mesh, if any, and its extras "xylem_foliage") and the mesh
 * "stems". Errors: XYL_ERR_PARSE (not glTF, no node "leaves", extras or a primitive not as the
 * writer makes them: the message says what), XYL_ERR_INVALID_ARGUMENT, XYL_ERR_OUT_OF_MEMORY.
 * On failure *out is zeroed. */
xyl_result xyl_sample_read_glb_leaves(const unsigned char *data, size_t size,
                                      xyl_sample_glb_leaves *out, xyl_diag *diag);
void xyl_sample_glb_leaves_free(xyl_sample_glb_leaves *leaves);

#ifdef __cplusplus
}
#endif

#endif
