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
 * writer split. Errors: XYL_ERR_PARSE (not glTF, or a file this reader does not take: the message
 * says what), XYL_ERR_INVALID_ARGUMENT, XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED,
 * XYL_ERR_OUT_OF_MEMORY. */
xyl_result xyl_sample_read_glb(const unsigned char *data, size_t size, xyl_mesh **out,
                               xyl_diag *diag);

#ifdef __cplusplus
}
#endif

#endif
